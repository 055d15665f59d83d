"""The rows of a clearance: which pairs, in which order, built once per configuration and scene.

:class:`Layout` fixes every row of :func:`~assembler_pin.collision.check.clearance`'s arrays
(the same count and order call after call, as the optimizer's rows need); the carriers of the
rows' closest points (:data:`LEG`, :data:`PLATE`, :data:`FIXED`) say what moves them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..config.schema import AssemblerConfig
from ..model.geometry import LEGS_PER_PLATFORM
from .bodies import stack_body_names
from .kernel import KernelInputs, kernel_inputs
from .pairs import pair_table
from .scene import Obstacle, Scene

__all__ = ["FIXED", "LEG", "PLATE", "Layout", "build_layout", "half_widths", "layout_of", "row_block"]

# carrier kinds of a closest point: on a leg (moves with its two plates and its length),
# on a plate (rigid with it), fixed (an obstacle, the floor)
LEG, PLATE, FIXED = 0, 1, 2


@dataclass(frozen=True, kw_only=True)
class Layout:
    """The rows of one configuration and scene, in the order of every clearance's arrays,
    the same call after call (:class:`~assembler_pin.optimize.rows.ClearanceRows` needs a fixed
    count and order): first the exact ones, the ``P`` leg pairs (the kernel's), the payload's
    (against the ``G`` legs and plates 0..n-1, when it has a radius), the floor's (the ``G``
    legs, the plates not standing, the payload), each sphere's (its ``G`` legs, its ``K``
    plates, the payload); then, from row ``X``, the screened ones: the ``Q`` leg–plate pairs,
    the ``S`` plate pairs, each box's or cylinder's (its legs, its plates, the payload)."""

    cfg: AssemblerConfig
    scene: Scene | None
    names: tuple[str, ...]
    pairs: np.ndarray  # (m, 2) body ids (read-only: shared by every clearance)
    kind: np.ndarray  # (m, 2) carrier kinds
    index: np.ndarray  # (m, 2) leg g or plate k
    exact: np.ndarray  # (m,) the exact rows (a template)
    G: int
    K: int
    P: int
    Q: int
    S: int
    X: int
    kernel_inputs: KernelInputs
    payload_at: int  # first row of the payload against the legs and plates 0..n-1 (-1: no payload)
    unchecked: np.ndarray | None  # (solids, G + K + W) a support obstacle's rows with the standing plates
    W: int  # rows of the payload per obstacle and the floor: 1, or 0 without a payload
    leg_plate: np.ndarray  # (Q, 4) (leg, plate, trim bottom, trim top)
    plate_pairs: np.ndarray  # (S, 2)
    floor: tuple | None  # (first row, z [m], trim bottom (G,), trim top (G,), plates checked)
    sphere_at: int
    centres: np.ndarray  # (spheres, 3) world [m]
    radii: np.ndarray  # (spheres,) [m]
    solid_at: int
    solids: tuple[Obstacle, ...]
    cores: tuple[np.ndarray, np.ndarray, np.ndarray]  # bounding capsules: start, vector (N, 3), radius (N,) [m]
    slabs: tuple[np.ndarray, np.ndarray, np.ndarray]  # centre (N, 3), axes (N, 3, 3) as columns, half widths (N, 3) [m]

    @property
    def m(self) -> int:
        """The count of rows."""
        return len(self.pairs)


def row_block(m: int, body: tuple, kind: tuple, index: tuple) -> tuple[np.ndarray, ...]:
    """Static columns of ``m`` rows: each of ``body``, ``kind``, ``index`` a pair of (m,) arrays
    or scalars."""
    columns = (body, kind, index)
    return tuple(np.stack([np.broadcast_to(a, m), np.broadcast_to(b, m)], 1).astype(int) for a, b in columns)


def build_layout(cfg: AssemblerConfig, scene: Scene | None) -> Layout:
    t = pair_table(cfg)
    G, K = LEGS_PER_PLATFORM * cfg.platforms, cfg.platforms + 1
    legs, plates = np.arange(G), np.arange(K)
    n, W = cfg.platforms, int(cfg.payload.radius > 0)
    own = (*stack_body_names(n), *(("payload",) if W else ()))
    names = tuple(own)
    blocks = [row_block(len(t.leg_a), (t.leg_a, t.leg_b), (LEG, LEG), (t.leg_a, t.leg_b))]
    payload_at = -1
    if W:  # the payload, on plate n, against every leg and the plates below plate n
        payload_at = len(t.leg_a)
        blocks.append(row_block(G, (legs, len(own) - 1), (LEG, PLATE), (legs, n)))
        blocks.append(row_block(n, (G + plates[:n], len(own) - 1), (PLATE, PLATE), (plates[:n], n)))
    obstacles = () if scene is None else scene.obstacles
    floor = None
    if scene is not None:
        names = (*own, *(o.name for o in obstacles)) + (("floor",) if scene.floor_z is not None else ())
    ids = {o.name: len(own) + i for i, o in enumerate(obstacles)}

    def rows() -> int:
        return sum(len(b[0]) for b in blocks)

    def against(oid: int, k: np.ndarray = plates) -> None:
        blocks.append(row_block(G, (legs, oid), (LEG, FIXED), (legs, 0)))
        blocks.append(row_block(len(k), (G + k, oid), (PLATE, FIXED), (k, 0)))
        if W:
            blocks.append(row_block(1, (len(own) - 1, oid), (PLATE, FIXED), (n, 0)))

    if scene is not None and scene.floor_z is not None:
        on = np.asarray(scene.standing, dtype=int)
        platform = legs // LEGS_PER_PLATFORM
        k = np.setdiff1d(plates, on)
        floor = (rows(), float(scene.floor_z), np.isin(platform, on), np.isin(platform + 1, on), k)
        against(len(names) - 1, k)
    spheres = [o for o in obstacles if o.kind == "sphere"]
    sphere_at = rows()
    for o in spheres:
        against(ids[o.name])
    X = rows()
    g, k = t.leg_plate[:, 0], t.leg_plate[:, 1]
    lay_leg_plate = kernel_inputs(cfg).leg_plate
    blocks.append(row_block(len(g), (g, G + k), (LEG, PLATE), (g, k)))
    ka, kb = t.plate_pairs[:, 0], t.plate_pairs[:, 1]
    blocks.append(row_block(len(ka), (G + ka, G + kb), (PLATE, PLATE), (ka, kb)))
    solids = tuple(o for o in obstacles if o.kind != "sphere")
    solid_at = rows()
    for o in solids:
        against(ids[o.name])
    pairs, kind, index = (np.concatenate([b[i] for b in blocks]).reshape(-1, 2) for i in range(3))
    for a in (pairs, kind, index):
        a.flags.writeable = False
    exact = np.zeros(len(pairs), bool)
    exact[:X] = True
    unchecked = None
    if any(o.support for o in solids):
        assert scene is not None
        unchecked = np.zeros((len(solids), G + K + W), bool)
        standing = [k for k in scene.standing if k < K]
        unchecked[np.ix_([o.support for o in solids], [G + k for k in standing])] = True
        exact[solid_at : solid_at + unchecked.size] |= unchecked.ravel()  # kept at inf, never measured
    cores = [o.bounding_capsule() for o in solids]
    return Layout(
        cfg=cfg,
        scene=scene,
        names=names,
        pairs=pairs,
        kind=kind,
        index=index,
        exact=exact,
        G=G,
        K=K,
        P=len(t.leg_a),
        Q=len(g),
        S=len(ka),
        X=X,
        kernel_inputs=kernel_inputs(cfg),
        payload_at=payload_at,
        unchecked=unchecked,
        W=W,
        leg_plate=lay_leg_plate,
        plate_pairs=t.plate_pairs,
        floor=floor,
        sphere_at=sphere_at,
        centres=np.array([o.pose.translation for o in spheres], dtype=float).reshape(-1, 3),
        radii=np.array([o.size[0] for o in spheres], dtype=float),
        solid_at=solid_at,
        solids=solids,
        cores=(
            np.array([c[0] for c in cores], dtype=float).reshape(-1, 3),
            np.array([c[1] for c in cores], dtype=float).reshape(-1, 3),
            np.array([c[2] for c in cores], dtype=float),
        ),
        slabs=(
            np.array([o.pose.translation for o in solids], dtype=float).reshape(-1, 3),
            np.array([o.pose.rotation for o in solids], dtype=float).reshape(-1, 3, 3),
            np.array([half_widths(o) for o in solids], dtype=float).reshape(-1, 3),
        ),
    )


def half_widths(o: Obstacle) -> tuple[float, float, float]:
    """Half the width of a box or a cylinder between the faces of its slabs, along its own
    axes [m] (a cylinder has one slab, its caps: ``inf`` across it)."""
    if o.kind == "box":
        return (0.5 * o.size[0], 0.5 * o.size[1], 0.5 * o.size[2])
    return (math.inf, math.inf, 0.5 * o.size[1])


_LAYOUTS: dict[tuple, Layout] = {}


def layout_of(cfg: AssemblerConfig, scene: Scene | None) -> Layout:
    """The rows of ``cfg`` and ``scene``, built once per configuration object and obstacle
    tuple (by identity: a scene rebuilt from its file builds them again), floor and standing."""
    key = (id(cfg),) if scene is None else (id(cfg), id(scene.obstacles), scene.floor_z, scene.standing)
    hit = _LAYOUTS.get(key)
    if hit is not None and hit.cfg is cfg and (scene is None or (hit.scene and hit.scene.obstacles is scene.obstacles)):
        return hit
    lay = build_layout(cfg, scene)
    if len(_LAYOUTS) >= 16:
        _LAYOUTS.pop(next(iter(_LAYOUTS)))
    _LAYOUTS[key] = lay
    return lay
