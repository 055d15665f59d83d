"""The clearance of a pose: the smallest distance between two bodies that must not touch.

:func:`clearance` measures every pair of :mod:`~assembler_pin.collision.pairs` (the stack's
own bodies) and, with a :class:`~assembler_pin.collision.scene.Scene`, every body against
every obstacle and the floor. It returns a :class:`Clearance`: the smallest distance, the
two bodies, every pair's distance, and :meth:`Clearance.gradient`, the derivatives of the
pair distances with respect to the plate poses.

**Which engine.** Capsule–capsule (every leg pair, ~1100 capsule pairs for four platforms),
capsule–sphere, capsule–floor, plate–floor and plate–sphere distances are closed forms
(:mod:`~assembler_pin.collision.distance`), vectorized in numpy. Plates against legs, plates
and boxes or cylinders, and legs against boxes or cylinders have no closed form here: a cheap
lower bound (bounding spheres, and for a plate the slab of its two faces) screens every such
pair, and only those within :data:`NEAR` of the clearance go to coal's GJK
(``coal.distance``, ~0.6 µs per pair with shapes made once, plus ~3 µs of Python around each
call). Pinocchio's ``GeometryModel`` + ``computeDistances`` would run all ~1200 pairs of a
four-platform stack in C++ at ~0.6 µs each, and updating the 48 capsules' placements and
lengths from Python costs more again: the vectorized closed form is the faster of the two.

**Distances** are between surfaces [m], negative when two bodies overlap (for capsules, the
distance of the axes minus the radii; for coal pairs, coal's signed distance). Pairs the
screen leaves out keep their lower bound (``exact`` False); the smallest distance is always
exact: screened pairs whose bound is below it are measured until none is.

**Derivatives** are taken with respect to a world twist ``η_k = (v, ω)`` of each plate
``k = 0..n`` (``T_k ← exp6(η_k) T_k``), the convention of :mod:`assembler_pin.statics.derivatives`:
by the envelope theorem ``∂d = n · (δx_a − δx_b)`` with ``x_a, x_b`` the closest points
moving with their bodies and ``n`` the unit normal from b to a. A leg's point at ``σ`` from
its bottom joint moves with both of its plates and with the leg's length when it lies on a
segment end that follows the top joint.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..config.schema import AssemblerConfig
from ..exceptions import SceneError
from ..kinematics import PlateArrays, plate_arrays
from ..model.assembler import AssemblerModel
from ..model.geometry import LEGS_PER_PLATFORM, leg_geometry
from .bodies import MOTOR, SHAFT, StackBodies, leg_segments, stack_body_names
from .distance import (
    cylinder_lowest_point,
    point_in_cylinder_distance,
    segment_point,
    segment_segment,
    segment_segment_columns,
)
from .kernel import self_kernel
from .pairs import pair_table, per_config
from .scene import Obstacle, Scene, read_scene

__all__ = ["GJK_TOLERANCE", "NEAR", "Clearance", "clearance"]

logger = logging.getLogger(__name__)

#: Pairs whose screening bound is within this of the clearance are measured exactly [m].
NEAR = 0.05

#: coal's GJK tolerance [m] (the default, 1e-6, leaves the distance noisy at that level: too
#: coarse for derivatives held to central differences). The penetration depth of overlapping
#: pairs comes from coal's EPA at its default tolerance: its derivative is good to ~1e-3.
GJK_TOLERANCE = 1e-10

# carrier kinds of a closest point: on a leg (moves with its two plates and its length),
# on a plate (rigid with it), fixed (an obstacle, the floor)
_LEG, _PLATE, _FIXED = 0, 1, 2


@dataclass
class _Rows:
    """Pair rows of one kind: distances, the two bodies and their closest points' carriers."""

    dist: np.ndarray
    exact: np.ndarray
    body: np.ndarray  # (m, 2) body ids
    kind: np.ndarray  # (m, 2) carrier kinds
    index: np.ndarray  # (m, 2) leg g or plate k
    sigma: np.ndarray  # (m, 2) σ of a leg point [m]
    hb: np.ndarray  # (m, 2) d σ / d L of a leg point
    point: np.ndarray  # (m, 2, 3) closest points (a leg's on its axis), world [m]
    normal: np.ndarray  # (m, 3) unit normal from body b to body a


def _empty_rows() -> _Rows:
    z = np.zeros
    return _Rows(
        z(0), z(0, bool), z((0, 2), int), z((0, 2), int), z((0, 2), int), z((0, 2)), z((0, 2)), z((0, 2, 3)), z((0, 3))
    )


def _concat(rows: list[_Rows]) -> _Rows:
    rows = [r for r in rows if len(r.dist)] or [_empty_rows()]
    return _Rows(*(np.concatenate([getattr(r, f) for r in rows]) for f in _Rows.__dataclass_fields__))


def _unit(v: np.ndarray) -> np.ndarray:
    norm = np.sqrt(np.einsum("...k,...k->...", v, v))
    fallback = np.broadcast_to(np.array([0.0, 0.0, 1.0]), v.shape)
    return np.where(norm[..., None] > 1e-15, v / np.maximum(norm, 1e-300)[..., None], fallback)


@dataclass(frozen=True)
class Clearance:
    """The clearance of one pose.

    Attributes:
        min_distance: the smallest distance between two bodies that must not touch [m]
            (``inf`` when no pair is checked).
        between: the names of those two bodies (``"SP1 leg 3"``, ``"plate 2"``, an
            obstacle's name, ``"floor"``).
        limit: the smallest distance allowed (the configuration's ``clearance``) [m].
        names: every body's name, indexed by ``pairs`` (shared: do not modify).
        pairs: (m, 2) the bodies of every checked pair (indices into ``names``).
        distances: (m,) their distances [m] (lower bounds where ``exact`` is False).
        exact: (m,) True where the distance was measured, not only bounded.
    """

    min_distance: float
    between: tuple[str, str]
    limit: float
    names: Sequence[str]
    pairs: np.ndarray
    distances: np.ndarray
    exact: np.ndarray
    _parts: list[_Rows] = field(repr=False)
    _bodies: StackBodies = field(repr=False)
    _reversed: bool = field(default=False, repr=False)  # plates given in the reverse order (a turned model)

    @functools.cached_property
    def _rows(self) -> _Rows:
        """Every row's closest points and normal (built on first use: the derivatives)."""
        return _concat(self._parts)

    @property
    def clear(self) -> bool:
        """True when the smallest distance is at least the allowed clearance."""
        return bool(self.min_distance >= self.limit)

    def to_dict(self) -> dict:
        """``{"min_distance_m": d, "between": [a, b]}`` (``null`` distance when no pair is checked)."""
        d = self.min_distance if math.isfinite(self.min_distance) else None
        return {"min_distance_m": d, "between": list(self.between)}

    def __repr__(self) -> str:
        a, b = self.between
        return f"Clearance({self.min_distance:.4g} m between {a} and {b}, limit {self.limit} m)"

    def witness_points(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The closest pair's two witness points (3,), (3,), world [m]: on the surface of
        ``between[0]`` and ``between[1]``, ``min_distance`` apart along the pair's normal
        (the first point is the second moved by ``min_distance`` times the unit normal from
        the second body to the first); None when no pair is checked.

        A leg's closest point is on its axis: its surface point is that point moved by the
        radius of its motor or shaft (whichever holds it) towards the other body.
        """
        if not math.isfinite(self.min_distance) or not len(self.distances):
            return None
        r = self._rows
        i = int(np.flatnonzero(r.dist <= self.min_distance + 1e-12)[0])
        n = r.normal[i]
        a = r.point[i, 0].copy()
        if r.kind[i, 0] == _LEG:
            leg = self._bodies.cfg.leg
            a -= (leg.motor_radius if r.sigma[i, 0] <= leg.motor_length else leg.shaft_radius) * n
        return a, a - self.min_distance * n

    def gradient(self, rows: np.ndarray | Sequence[int] | None = None) -> np.ndarray:
        """Derivatives of the pair distances with respect to the plates' world twists.

        Args:
            rows: which pairs (indices into ``distances``; default all). Only exact rows have
                a meaningful derivative.

        Returns:
            (m, n+1, 6): ``∂d / ∂(v_k, ω_k)`` for plates k = 0..n [m/m, m/rad].
        """
        r = self._rows
        sel = np.arange(len(r.dist)) if rows is None else np.asarray(rows, dtype=int)
        b = self._bodies
        out = np.zeros((len(sel), len(b.p), 6))
        n = r.normal[sel]
        for side, sign in ((0, 1.0), (1, -1.0)):
            kind, idx, x = r.kind[sel, side], r.index[sel, side], r.point[sel, side]
            at = np.nonzero(kind == _PLATE)[0]
            np.add.at(out, (at, idx[at]), sign * np.hstack([n[at], np.cross(x[at], n[at])]))
            at = np.nonzero(kind == _LEG)[0]
            if not len(at):
                continue
            g = idx[at]
            u, L, nn = b.axis[g], b.length[g], n[at]
            nu = np.einsum("ij,ij->i", nn, u)
            c_top = (r.sigma[sel[at], side] / L)[:, None] * (nn - nu[:, None] * u) + (r.hb[sel[at], side] * nu)[
                :, None
            ] * u
            c_bottom = nn - c_top
            j = g // LEGS_PER_PLATFORM
            for plate, c, anchor in ((j, c_bottom, b.bottom[g]), (j + 1, c_top, b.top[g])):
                np.add.at(out, (at, plate), sign * np.hstack([c, np.cross(anchor, c)]))
        return out[:, ::-1].copy() if self._reversed else out


# ---------------------------------------------------------------- closed forms
def _capsule_rows(
    bodies: StackBodies, legs: np.ndarray, part: np.ndarray, trim_bottom=False, trim_top=False
) -> tuple[np.ndarray, ...]:
    start, vec, lo, hi, hb, radius = leg_segments(bodies, legs, part, trim_bottom, trim_top)
    return start, vec, lo, hi, hb, radius


def _variant_index(t, G: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows of the leg–leg capsule pairs (4 per leg pair: motor/shaft × motor/shaft) as
    indices into the 8 variants of each leg part (part × bottom trim × top trim)."""
    parts_a = np.tile(np.array([MOTOR, MOTOR, SHAFT, SHAFT]), len(t.leg_a))
    parts_b = np.tile(np.array([MOTOR, SHAFT, MOTOR, SHAFT]), len(t.leg_a))
    tr = np.repeat(t.trim.astype(int), 4, axis=0)
    va = np.repeat(t.leg_a, 4) * 8 + parts_a * 4 + tr[:, 0] * 2 + tr[:, 1]
    vb = np.repeat(t.leg_b, 4) * 8 + parts_b * 4 + tr[:, 2] * 2 + tr[:, 3]
    return va, vb


def _legs_all_parts(bodies: StackBodies, trim_bottom=False, trim_top=False) -> tuple[np.ndarray, ...]:
    G = len(bodies.length)
    g = np.repeat(np.arange(G), 2)
    part = np.tile(np.array([MOTOR, SHAFT]), G)
    tb = np.repeat(np.asarray(trim_bottom), 2) if np.ndim(trim_bottom) else trim_bottom
    tt = np.repeat(np.asarray(trim_top), 2) if np.ndim(trim_top) else trim_top
    return (g, part, *_capsule_rows(bodies, g, part, tb, tt))


def _leg_rows_from_parts(g, d, s, start, vec, lo, hi, hb, other_body, other_kind, other_index, other_point, normal):
    """Reduce per-capsule rows (2 per leg, motor then shaft) to one row per leg."""
    m = len(d) // 2
    best = np.argmin(d.reshape(m, 2), axis=1) + 2 * np.arange(m)
    x = start[best] + s[best, None] * vec[best]
    sig = lo[best] + s[best] * np.maximum(hi[best] - lo[best], 0.0)
    z = np.zeros(m)
    return _Rows(
        d[best],
        np.ones(m, bool),
        np.stack([g[best], other_body[best]], 1),
        np.stack([np.full(m, _LEG), other_kind[best]], 1),
        np.stack([g[best], other_index[best]], 1),
        np.stack([sig, z], 1),
        np.stack([s[best] * hb[best], z], 1),
        np.stack([x, other_point[best]], 1),
        normal[best],
    )


def _floor(bodies: StackBodies, floor_z: float, floor_id: int, standing: tuple[int, ...] = (0,)) -> _Rows:
    """Every leg and every plate against the floor (a half-space below ``floor_z``): exact,
    signed; but not the ``standing`` plates, nor a leg's ``node_zone`` at a standing plate."""
    G = len(bodies.length)
    platform = np.arange(G) // LEGS_PER_PLATFORM
    on = np.asarray(standing, dtype=int)
    g, _, start, vec, lo, hi, hb, radius = _legs_all_parts(bodies, np.isin(platform, on), np.isin(platform + 1, on))
    z0, z1 = start[:, 2], start[:, 2] + vec[:, 2]
    s = (z1 < z0).astype(float)
    x = start + s[:, None] * vec
    d = x[:, 2] - floor_z - radius
    d[hi < lo] = np.inf
    m = len(d)
    on_floor = x.copy()
    on_floor[:, 2] = floor_z
    up = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (m, 3))
    rows = [
        _leg_rows_from_parts(
            g, d, s, start, vec, lo, hi, hb, np.full(m, floor_id), np.full(m, _FIXED), np.zeros(m, int), on_floor, up
        )
    ]
    cfg = bodies.cfg
    k = np.setdiff1d(np.arange(len(bodies.p)), on)
    if len(k):
        low, height = cylinder_lowest_point(bodies.p[k], bodies.R[k][:, :, 2], cfg.plate.radius, cfg.plate.thickness)
        below = low.copy()
        below[:, 2] = floor_z
        rows.append(
            _Rows(
                height - floor_z,
                np.ones(len(k), bool),
                np.stack([G + k, np.full(len(k), floor_id)], 1),
                np.stack([np.full(len(k), _PLATE), np.full(len(k), _FIXED)], 1),
                np.stack([k, np.zeros(len(k), int)], 1),
                np.zeros((len(k), 2)),
                np.zeros((len(k), 2)),
                np.stack([low, below], 1),
                np.broadcast_to(np.array([0.0, 0.0, 1.0]), (len(k), 3)).copy(),
            )
        )
    return _concat(rows)


def _sphere(bodies: StackBodies, obstacle: Obstacle, body_id: int) -> _Rows:
    """Every leg and plate against a sphere: closed forms, exact."""
    centre, r = obstacle.pose.translation, obstacle.size[0]
    g, _, start, vec, lo, hi, hb, radius = _legs_all_parts(bodies)
    d_axis, s = segment_point(start, vec, centre)
    x = start + s[:, None] * vec
    d = d_axis - radius - r
    d[hi < lo] = np.inf
    n = _unit(x - centre)
    m = len(d)
    rows = [
        _leg_rows_from_parts(
            g,
            d,
            s,
            start,
            vec,
            lo,
            hi,
            hb,
            np.full(m, body_id),
            np.full(m, _FIXED),
            np.zeros(m, int),
            centre + r * n,
            n,
        )
    ]
    cfg = bodies.cfg
    local = np.einsum("kji,kj->ki", bodies.R, centre - bodies.p)  # Rᵀ (c - p)
    dc, closest = point_in_cylinder_distance(local, cfg.plate.radius, cfg.plate.thickness)
    on_plate = bodies.p + np.einsum("kij,kj->ki", bodies.R, closest)
    k = np.arange(len(bodies.p))
    nk = _unit(on_plate - centre)
    nk = np.where((dc < 0)[:, None], -nk, nk)
    G = len(bodies.length)
    rows.append(
        _Rows(
            dc - r,
            np.ones(len(k), bool),
            np.stack([G + k, np.full(len(k), body_id)], 1),
            np.stack([np.full(len(k), _PLATE), np.full(len(k), _FIXED)], 1),
            np.stack([k, np.zeros(len(k), int)], 1),
            np.zeros((len(k), 2)),
            np.zeros((len(k), 2)),
            np.stack([on_plate, centre + r * nk], 1),
            nk,
        )
    )
    return _concat(rows)


# ---------------------------------------------------------------- coal pairs
def _coal():
    import coal  # shipped with pin; imported on the first pair that needs it

    return coal


def _obstacle_shape(o: Obstacle):
    coal = _coal()
    if o.kind == "box":
        return coal.Box(*o.size)
    return coal.Cylinder(o.size[0], o.size[1])


def _z_to(u: np.ndarray) -> np.ndarray:
    """A rotation whose z axis is the unit vector ``u``."""
    ux, uy, uz = float(u[0]), float(u[1]), float(u[2])
    if abs(ux) < 0.9:  # x = e_x × u, normalized
        x = (0.0, -uz, uy)
    else:  # x = e_y × u
        x = (uz, 0.0, -ux)
    norm = math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
    x = (x[0] / norm, x[1] / norm, x[2] / norm)
    y = (uy * x[2] - uz * x[1], uz * x[0] - ux * x[2], ux * x[1] - uy * x[0])
    return np.array([[x[0], y[0], ux], [x[1], y[1], uy], [x[2], y[2], uz]])


def _coal_distance(shape_a, R_a, p_a, shape_b, R_b, p_b) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    coal = _coal()
    req, res = coal.DistanceRequest(), coal.DistanceResult()
    req.gjk_tolerance = GJK_TOLERANCE
    req.gjk_max_iterations = 1000
    d = coal.distance(shape_a, coal.Transform3s(R_a, p_a), shape_b, coal.Transform3s(R_b, p_b), req, res)
    wa, wb = np.array(res.getNearestPoint1()), np.array(res.getNearestPoint2())
    return float(d), wa, wb, -np.array(res.normal)


@dataclass
class _Screened:
    """Pairs measured by coal on demand: their lower bounds and how to measure each."""

    rows: _Rows
    measure: Callable[[int], tuple | None]  # row → (d, x_a, x_b, n, sigma_a, hb_a) or None


def _leg_screen(
    bodies: StackBodies,
    g: np.ndarray,
    core: tuple[np.ndarray, np.ndarray, np.ndarray],
    slab: tuple[np.ndarray, float] | None = None,
) -> np.ndarray:
    """Lower bounds (m, 2) of the motor and the shaft of each leg ``g`` (m,) against bodies held
    in capsules ``core = (start, vector, radius)`` (one per leg, or one for all), and optionally
    in the slab of a plate (``(normal, half-thickness)``, about the core's start)."""
    part = np.tile(np.array([MOTOR, SHAFT]), len(g))
    start, vec, lo, hi, _, radius = leg_segments(bodies, np.repeat(g, 2), part)
    c0, c1, cr = _repeat_core(core, len(g))
    if np.any(core[1]):
        d_axis, _, _ = segment_segment(start, vec, c0, c1)
    else:  # bodies held in spheres (the plates): the segment to a point
        d_axis, _ = segment_point(start, vec, c0)
    lb = d_axis - cr - radius
    if slab is not None:
        normal, half = np.repeat(slab[0], 2, axis=0), slab[1]
        h0 = np.einsum("ij,ij->i", start - c0, normal)
        h1 = h0 + np.einsum("ij,ij->i", vec, normal)
        lb = np.maximum(lb, np.maximum(np.minimum(h0, h1), np.minimum(-h0, -h1)) - half - radius)
    lb[hi < lo] = np.inf
    return lb.reshape(-1, 2)


def _repeat_core(core: tuple, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    start, vec, radius = core
    start = np.broadcast_to(start, (m, 3))
    vec = np.broadcast_to(vec, (m, 3))
    radius = np.broadcast_to(radius, (m,))
    return np.repeat(start, 2, axis=0), np.repeat(vec, 2, axis=0), np.repeat(radius, 2)


def _screened_rows(lb: np.ndarray, body: np.ndarray, kind: np.ndarray, index: np.ndarray) -> _Rows:
    """Rows known by their lower bounds ``lb`` only (not measured yet)."""
    m = len(lb)
    return _Rows(
        lb,
        np.zeros(m, bool),
        body,
        kind,
        index,
        np.zeros((m, 2)),
        np.zeros((m, 2)),
        np.zeros((m, 2, 3)),
        _UP[:m].copy(),
    )


_UP = np.tile(np.array([0.0, 0.0, 1.0]), (4096, 1))


def _coal_leg_rows(
    bodies: StackBodies,
    g: np.ndarray,
    lb: np.ndarray,
    static: tuple[np.ndarray, np.ndarray, np.ndarray],
    other: Callable[[int], tuple],
) -> _Screened:
    """One row per leg ``g`` against a body coal measures (``other(r)``: shape, R, p), known by
    the smaller bound of its two parts ``lb`` (m, 2) until measured (both parts, the smaller)."""

    def measure(r: int) -> tuple | None:
        best = None
        for part in (MOTOR, SHAFT):
            if not np.isfinite(lb[r, part]):
                continue
            start, vec, lo, hi, hb, radius = (x[0] for x in leg_segments(bodies, g[r : r + 1], np.array([part])))
            got = _measure_capsule(bodies, int(g[r]), start, vec, lo, hi, hb, radius, other(r))
            if got is not None and (best is None or got[0] < best[0]):
                best = got
        return best

    return _Screened(_screened_rows(lb.min(axis=1), *static), measure)


def _measure_capsule(bodies, g, start, vec, lo, hi, hb, radius, other):
    """coal's distance between one leg capsule and ``other = (shape, R, p)``."""
    if hi < lo:
        return None
    length = max(hi - lo, 1e-12)
    capsule = _coal().Capsule(radius, length)
    d, wa, wb, n = _coal_distance(capsule, _z_to(bodies.axis[g]), start + 0.5 * vec, *other)
    s = float(np.clip(np.dot(wa - start, bodies.axis[g]) / length, 0.0, 1.0))
    return d, start + s * vec, wb, n, lo + s * max(hi - lo, 0.0), s * hb


@per_config
def _static_rows(cfg: AssemblerConfig) -> tuple:
    """The bodies, carrier kinds and indices of the leg–plate and plate–plate rows."""
    t = pair_table(cfg)
    G = LEGS_PER_PLATFORM * cfg.platforms
    g, k = t.leg_plate[:, 0], t.leg_plate[:, 1]
    legs_plates = (np.stack([g, G + k], 1), np.stack([np.full(len(g), _LEG), np.full(len(g), _PLATE)], 1), t.leg_plate)
    ka, kb = t.plate_pairs[:, 0], t.plate_pairs[:, 1]
    plates = (np.stack([G + ka, G + kb], 1), np.full((len(ka), 2), _PLATE), t.plate_pairs)
    legs = np.stack([t.leg_a, t.leg_b], 1)
    self_pairs = np.concatenate([legs, legs_plates[0], plates[0]])  # the rows of the stack alone
    return legs_plates, plates, self_pairs


class _PlateShape:
    """The plates' coal cylinder, made on the first measurement that needs it."""

    def __init__(self, cfg: AssemblerConfig) -> None:
        self.cfg, self.shape = cfg, None

    def __call__(self):
        if self.shape is None:
            self.shape = _coal().Cylinder(self.cfg.plate.radius, max(self.cfg.plate.thickness, 1e-9))
        return self.shape


def _screened_pairs(
    bodies: StackBodies, scene: Scene | None, ids: dict, bounds: tuple[np.ndarray, np.ndarray]
) -> list[_Screened]:
    """The pairs coal measures, with their lower bounds (``bounds``: the self pass's leg–plate
    (Q, 2) and plate–plate (S,) bounds; the obstacles' computed here)."""
    cfg = bodies.cfg
    t = pair_table(cfg)
    G = len(bodies.length)
    plate = _PlateShape(cfg)
    rho = math.hypot(cfg.plate.radius, 0.5 * cfg.plate.thickness)
    legs_plates, plates, _ = _static_rows(cfg)
    out: list[_Screened] = []
    if len(t.leg_plate):  # legs against the plates they do not sit on
        g, k = t.leg_plate[:, 0], t.leg_plate[:, 1]
        lb = bounds[0]

        def plate_of(r: int, k: np.ndarray = k) -> tuple:  # k bound now: the loop below rebinds the name
            return plate(), bodies.R[k[r]], bodies.p[k[r]]

        out.append(_coal_leg_rows(bodies, g, lb, legs_plates, plate_of))
    if len(t.plate_pairs):  # plate against plate
        ka, kb = t.plate_pairs[:, 0], t.plate_pairs[:, 1]
        lbp = bounds[1]

        def plate_pair(r: int) -> tuple:
            a, b = int(ka[r]), int(kb[r])
            d, wa, wb, n = _coal_distance(plate(), bodies.R[a], bodies.p[a], plate(), bodies.R[b], bodies.p[b])
            return d, wa, wb, n, 0.0, 0.0

        out.append(_Screened(_screened_rows(lbp, *plates), plate_pair))
    if scene is None:
        return out
    legs = np.arange(G)
    for o in scene.obstacles:
        if o.kind == "sphere":
            continue
        shape, oid = _obstacle_shape(o), ids[o.name]
        fixed = (shape, o.pose.rotation, o.pose.translation)
        core_start, core_vec, core_r = o.bounding_capsule()
        lb = _leg_screen(bodies, legs, (core_start, core_vec, np.array(core_r)))
        legs_static = (
            np.stack([legs, np.full(G, oid)], 1),
            np.stack([np.full(G, _LEG), np.full(G, _FIXED)], 1),
            np.stack([legs, np.zeros(G, int)], 1),
        )

        def obstacle_of(r: int, fixed: tuple = fixed) -> tuple:
            return fixed

        out.append(_coal_leg_rows(bodies, legs, lb, legs_static, obstacle_of))
        k = np.arange(len(bodies.p))
        lbk = segment_point(
            np.broadcast_to(core_start, bodies.p.shape), np.broadcast_to(core_vec, bodies.p.shape), bodies.p
        )[0]
        mk = len(k)
        plates_static = (
            np.stack([G + k, np.full(mk, oid)], 1),
            np.stack([np.full(mk, _PLATE), np.full(mk, _FIXED)], 1),
            np.stack([k, np.zeros(mk, int)], 1),
        )

        def plate_obstacle(r: int, fixed: tuple = fixed) -> tuple:
            d, wa, wb, n = _coal_distance(plate(), bodies.R[r], bodies.p[r], *fixed)
            return d, wa, wb, n, 0.0, 0.0

        out.append(_Screened(_screened_rows(lbk - rho - core_r, *plates_static), plate_obstacle))
    return out


def _measure(screened: _Screened, r: int) -> None:
    got = screened.measure(r)
    rows = screened.rows
    rows.exact[r] = True
    if got is None:
        rows.dist[r] = np.inf
        return
    d, xa, xb, n, sigma, hb = got
    rows.dist[r], rows.point[r, 0], rows.point[r, 1], rows.normal[r] = d, xa, xb, n
    rows.sigma[r, 0], rows.hb[r, 0] = sigma, hb


_calls = 0  # clearances asked for in this process (the kernel is loaded when they are many)


@per_config
def _kernel_inputs(cfg: AssemblerConfig) -> tuple:
    """The kernel's constant inputs for a configuration: anchors, variant pairs, pair lists, sizes."""
    t = pair_table(cfg)
    G = LEGS_PER_PLATFORM * cfg.platforms
    va, vb = _variant_index(t, G)
    sizes = np.array(
        [
            cfg.leg.motor_length,
            cfg.leg.node_zone,
            cfg.leg.motor_radius,
            cfg.leg.shaft_radius,
            cfg.plate.radius,
            0.5 * cfg.plate.thickness,
            math.hypot(cfg.plate.radius, 0.5 * cfg.plate.thickness),
        ]
    )
    geometry = leg_geometry(cfg)
    bottom = np.ascontiguousarray(geometry.bottom_in_plate.reshape(-1, 3))
    top = np.ascontiguousarray(geometry.top_in_plate.reshape(-1, 3))
    legs = np.stack([t.leg_a, t.leg_b], 1)
    return bottom, top, va, vb, t.leg_plate, t.plate_pairs, sizes, legs, np.zeros((len(legs), 2), int)


def _kernel_pass(am: AssemblerModel, pa: PlateArrays, kernel) -> tuple[StackBodies, _Rows, tuple]:
    """Bodies, leg–leg rows and the coal pairs' bounds from the compiled kernel."""
    bottom, top, va, vb, leg_plate, plate_pairs, sizes, legs, kinds = _kernel_inputs(am.config)
    G, P = len(bottom), len(legs)
    B, T, U, L = np.empty((G, 3)), np.empty((G, 3)), np.empty((G, 3)), np.empty(G)
    d, x, sig, hb, nrm = np.empty(P), np.empty((P, 2, 3)), np.empty((P, 2)), np.empty((P, 2)), np.empty((P, 3))
    lp, pp = np.empty((len(leg_plate), 2)), np.empty(len(plate_pairs))
    kernel(pa.R, pa.p, bottom, top, va, vb, leg_plate, plate_pairs, sizes, B, T, U, L, d, x, sig, hb, nrm, lp, pp)
    bodies = StackBodies(am.config, B, T, U, L, pa.R, pa.p)
    return bodies, _Rows(d, np.ones(P, bool), legs, kinds, legs, sig, hb, x, nrm), (lp, pp)


@per_config
def _numpy_inputs(cfg: AssemblerConfig) -> tuple:
    """Constants of the numpy pass: for the leg-part variants the pairs use (part × trims of
    :func:`~assembler_pin.collision.bodies.leg_segments`), their leg, ``lo``, the two
    candidates of ``hi = min(a1 + b1 L, a2 + b2 L)``, radius; the pairs as variant rows; the
    platform of each leg's two plates; the leg parts and plates of the screens."""
    bottom, top, va, vb, leg_plate, plate_pairs, *_ = _kernel_inputs(cfg)
    G = len(bottom)
    used, inverse = np.unique(np.concatenate([va, vb]), return_inverse=True)
    g, part, tb, tt = used // 8, (used // 4) % 2, (used // 2) % 2 == 1, used % 2 == 1
    leg = cfg.leg
    shaft = part == SHAFT
    lo = np.where(shaft, leg.motor_length, 0.0)
    lo = np.where(tb, np.maximum(lo, leg.node_zone), lo)
    a1, b1 = np.where(shaft, 0.0, leg.motor_length), shaft.astype(float)
    a2, b2 = np.where(tt, -leg.node_zone, np.inf), tt.astype(float)
    radius = np.where(shaft, leg.shaft_radius, leg.motor_radius)
    ia, ib = inverse[: len(va)], inverse[len(va) :]
    plate_of = np.arange(G) // LEGS_PER_PLATFORM
    lp_g = np.repeat(leg_plate[:, 0], 2)  # the screens: (leg, plate) × (motor, shaft)
    lp_k = np.repeat(leg_plate[:, 1], 2)
    lp_shaft = np.tile(np.array([False, True]), len(leg_plate))
    radius_sum = radius[ia] + radius[ib]
    return g, lo, a1, b1, a2, b2, ia, ib, radius_sum, plate_of, bottom, top, lp_g, lp_k, lp_shaft, plate_pairs


def _numpy_pass(am: AssemblerModel, pa: PlateArrays) -> tuple[StackBodies, _Rows, tuple]:
    """The kernel's pass in numpy (:func:`_kernel_pass`'s outputs): bodies, leg–leg rows and
    the coal pairs' bounds. Points are kept as columns (3, m) and gathered with ``np.take``:
    the cost of this pass is the count of numpy calls, not the pairs."""
    cfg = am.config
    g, lo, a1, b1, a2, b2, ia, ib, radius_sum, plate_of, bottom_in, top_in, lp_g, lp_k, lp_shaft, plate_pairs = (
        _numpy_inputs(cfg)
    )
    R, p = pa.R, pa.p
    bottom = np.einsum("gij,gj->gi", R[plate_of], bottom_in) + p[plate_of]
    top = np.einsum("gij,gj->gi", R[plate_of + 1], top_in) + p[plate_of + 1]
    vec = top - bottom
    length = np.sqrt(np.einsum("ij,ij->i", vec, vec))
    axis = vec / np.maximum(length, 1e-300)[:, None]
    Lg = length[g]
    h1, h2 = a1 + b1 * Lg, a2 + b2 * Lg
    hi = np.minimum(h1, h2)
    hb = np.where(h2 < h1, 1.0, b1)
    span = hi - lo
    axis_g = np.take(axis.T, g, axis=1)
    start = np.take(bottom.T, g, axis=1) + lo * axis_g  # (3, V)
    seg = np.maximum(span, 0.0) * axis_g
    take = np.take
    axis_d, s, u = segment_segment_columns(
        take(start, ia, axis=1), take(seg, ia, axis=1), take(start, ib, axis=1), take(seg, ib, axis=1)
    )
    d = axis_d - radius_sum
    empty = span < 0
    d[take(empty, ia) | take(empty, ib)] = np.inf
    P = len(d) // 4
    best = np.argmin(d.reshape(P, 4), axis=1) + 4 * np.arange(P)
    va, vb, sb, ub = ia[best], ib[best], s[best], u[best]
    full = np.maximum(span, 0.0)
    sig = np.stack([lo[va] + sb * full[va], lo[vb] + ub * full[vb]], 1)
    xa = take(start, va, axis=1) + sb * take(seg, va, axis=1)
    xb = take(start, vb, axis=1) + ub * take(seg, vb, axis=1)
    x = np.stack([xa.T, xb.T], 1)
    legs = np.stack([g[va], g[vb]], 1)
    rows = _Rows(
        d[best],
        np.ones(P, bool),
        legs,
        np.zeros((P, 2), int),
        legs,
        sig,
        np.stack([sb * hb[va], ub * hb[vb]], 1),
        x,
        _unit((xa - xb).T),
    )
    # lower bounds: a leg part against a plate (its bounding sphere, and the slab of its faces)
    leg = cfg.leg
    half, rho = 0.5 * cfg.plate.thickness, math.hypot(cfg.plate.radius, 0.5 * cfg.plate.thickness)
    L = length[lp_g]
    lo_p = np.where(lp_shaft, leg.motor_length, 0.0)
    hi_p = np.where(lp_shaft, L, leg.motor_length)
    r_p = np.where(lp_shaft, leg.shaft_radius, leg.motor_radius)
    a0 = bottom[lp_g] + lo_p[:, None] * axis[lp_g] - p[lp_k]  # from the plate's centre
    dk = (hi_p - lo_p)[:, None] * axis[lp_g]
    normal = R[lp_k][:, :, 2]
    dist, _ = segment_point(a0, dk, np.zeros(3))
    h0 = np.einsum("ij,ij->i", a0, normal)
    h1 = h0 + np.einsum("ij,ij->i", dk, normal)
    slab = np.maximum(np.minimum(h0, h1), -np.maximum(h0, h1)) - half - r_p
    lp = np.maximum(dist - rho - r_p, slab)
    lp[hi_p < lo_p] = np.inf
    # plate against plate: bounding spheres, and each one's slab against the other's spread
    ka, kb = plate_pairs[:, 0], plate_pairs[:, 1]
    dc = p[kb] - p[ka]
    pp = np.sqrt(np.einsum("ij,ij->i", dc, dc)) - 2.0 * rho
    na, nb = R[ka][:, :, 2], R[kb][:, :, 2]
    c = np.einsum("ij,ij->i", na, nb)
    spread = cfg.plate.radius * np.sqrt(np.maximum(1.0 - c * c, 0.0)) + half * np.abs(c) + half
    h = np.maximum(np.abs(np.einsum("ij,ij->i", na, dc)), np.abs(np.einsum("ij,ij->i", nb, dc)))
    pp = np.maximum(pp, h - spread)
    bodies = StackBodies(cfg, bottom, top, axis, length, R, p)
    return bodies, rows, (lp.reshape(-1, 2), pp)


def _turned_clearance(am: AssemblerModel, plates, scene: Scene | None, engine: str) -> Clearance:
    """The clearance of a turned model's plates (:attr:`AssemblerModel.physical`): the original
    stack's at the same bodies, its derivatives in the turned model's plate order (a world twist
    of turned plate k is the same twist of original plate n−k)."""
    assert am.physical is not None
    original, flip = am.physical
    pa = plate_arrays(am, plates)
    bodies = PlateArrays(np.matmul(pa.R[::-1], flip.T), pa.p[::-1].copy())
    if scene is not None:
        scene = dataclasses.replace(scene, standing=tuple(sorted(am.n - k for k in scene.standing)))
    return dataclasses.replace(clearance(original, bodies, scene, engine), _reversed=True)


def clearance(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    scene: Scene | str | None = None,
    engine: str = "auto",
) -> Clearance:
    """The clearance of a pose: every checked pair's distance, the smallest and its two bodies.

    Args:
        am: the model (sizes and the clearance allowed come from its configuration).
        plates: world poses of plates 0..n, plate 0 first.
        scene: obstacles and floor (a :class:`~assembler_pin.collision.scene.Scene`, a path
            of a scene file, or None for the stack's own bodies only).
        engine: the stack's own pairs through the compiled kernel (``numba``), numpy
            (``numpy``) or ``auto`` (:func:`~assembler_pin.collision.kernel.self_kernel`); the
            answers agree to rounding.

    Returns:
        a :class:`Clearance` (distances [m], world frame).
    """
    global _calls
    scene = read_scene(scene)
    if am.physical is not None:  # a stack seen from its other end: its bodies are the original's
        return _turned_clearance(am, plates, scene, engine)
    _calls += 1
    if scene is not None and any(k > am.n for k in scene.standing):
        raise SceneError(f"scene standing {scene.standing} names a plate beyond plate {am.n}")
    kernel = self_kernel(_calls, engine)
    pa = plate_arrays(am, plates)
    if kernel is None:
        bodies, leg_rows, bounds = _numpy_pass(am, pa)
    else:
        bodies, leg_rows, bounds = _kernel_pass(am, pa, kernel)
    cfg = bodies.cfg
    names: Sequence[str] = stack_body_names(cfg.platforms)
    ids: dict[str, int] = {}
    exact = [leg_rows]
    if scene is not None:
        names = [*names, *(o.name for o in scene.obstacles)] + (["floor"] if scene.floor_z is not None else [])
        ids = {o.name: len(stack_body_names(cfg.platforms)) + i for i, o in enumerate(scene.obstacles)}
        if scene.floor_z is not None:
            exact.append(_floor(bodies, scene.floor_z, len(names) - 1, scene.standing))
        for o in scene.obstacles:
            if o.kind == "sphere":
                exact.append(_sphere(bodies, o, ids[o.name]))
    screened = _screened_pairs(bodies, scene, ids, bounds)
    horizon = cfg.clearance + NEAR
    for sc in screened:
        for i in np.nonzero(sc.rows.dist < horizon)[0]:
            _measure(sc, int(i))
    best_exact = min((float(np.min(e.dist)) for e in exact if len(e.dist)), default=math.inf)
    while True:  # the smallest distance exact: measure bounds below it until none is
        best = min(
            [best_exact] + [float(np.min(sc.rows.dist[sc.rows.exact])) for sc in screened if sc.rows.exact.any()]
        )
        pending = [(sc, int(i)) for sc in screened for i in np.nonzero(~sc.rows.exact & (sc.rows.dist < best))[0]]
        if not pending:
            break
        for sc, row in pending:
            _measure(sc, row)
    parts = exact + [sc.rows for sc in screened]
    dist = np.concatenate([r.dist for r in parts])
    exact_rows = np.concatenate([r.exact for r in parts])
    pairs = _static_rows(cfg)[2] if scene is None else np.concatenate([r.body for r in parts])
    if len(dist):
        dmin = float(np.min(dist))
        first = int(np.flatnonzero(dist <= dmin + 1e-12)[0])
        between = (names[pairs[first, 0]], names[pairs[first, 1]])
    else:
        dmin, between = math.inf, ("", "")
    return Clearance(dmin, between, cfg.clearance, names, pairs, dist, exact_rows, parts, bodies)
