"""The clearance of a pose: the smallest distance between two bodies that must not touch.

:func:`clearance` measures every pair of :mod:`~assembler_pin.collision.pairs` (the stack's
own bodies) and, with a :class:`~assembler_pin.collision.scene.Scene`, every body against
every obstacle and the floor. It returns a :class:`Clearance`: the smallest distance, the
two bodies, every pair's distance, and :meth:`Clearance.gradient`, the derivatives of the
pair distances with respect to the plate poses.

**Which engine.** Capsule–capsule (every leg pair, ~1100 capsule pairs for four platforms),
capsule–sphere, capsule–floor, plate–floor and plate–sphere distances are closed forms
(:mod:`~assembler_pin.collision.distance`), vectorized in numpy (the stack's own pairs also
compiled: :mod:`~assembler_pin.collision.kernel`); a scene's pairs go in one pass per kind of
obstacle (every sphere together, every box and cylinder together). Plates against legs, plates
and boxes or cylinders, and legs against boxes or cylinders have no closed form here: a cheap
lower bound (bounding capsules and spheres, and the slabs between parallel faces: a plate's
two, a box's three pairs, a cylinder's caps) screens every such pair, and only those within
:data:`NEAR` of the clearance go to coal's GJK (``coal.distance``, ~1 µs per pair with shapes
made once, plus a few µs of Python around each call). Pinocchio's ``GeometryModel`` +
``computeDistances`` would run all ~1200 pairs of a four-platform stack in C++ at ~0.6 µs
each, and updating the 48 capsules' placements and lengths from Python costs more again: the
vectorized closed form is the faster of the two.

The rows of a configuration and a scene (``_Layout``: pairs, order, the kernel's inputs)
are built once per configuration object and obstacle tuple; a call fills one distance array.

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
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..config.schema import AssemblerConfig
from ..exceptions import SceneError
from ..kinematics import PlateArrays, plate_arrays
from ..model.assembler import AssemblerModel
from ..model.geometry import LEGS_PER_PLATFORM
from .bodies import MOTOR, SHAFT, StackBodies, leg_segments, stack_body_names
from .distance import (
    cylinder_lowest_point,
    point_in_cylinder_distance,
    segment_point,
    segment_segment,
)
from .home import TIE
from .kernel import ROW_HB, ROW_NORMAL, ROW_RADIUS, ROW_SIGMA, ROW_XA, ROW_XB, KernelInputs, kernel_inputs, own_pairs
from .pairs import pair_table
from .scene import Obstacle, Scene, read_scene

__all__ = ["GJK_TOLERANCE", "NEAR", "Clearance", "clearance", "physical_bodies"]

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
    radius: np.ndarray  # (m, 2) radius of the leg's capsule holding the point [m] (0: not a leg)
    point: np.ndarray  # (m, 2, 3) closest points (a leg's on its axis), world [m]
    normal: np.ndarray  # (m, 3) unit normal from body b to body a


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
    _source: _Source = field(repr=False)
    _reversed: bool = field(default=False, repr=False)  # plates given in the reverse order (a turned model)

    @functools.cached_property
    def _rows(self) -> _Rows:
        """Every row's closest points and normal (built on first use: the derivatives)."""
        return self._source.rows()

    @property
    def _bodies(self) -> StackBodies:
        return self._source.bodies()

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
        radius of the capsule (motor or shaft) the distance was measured on towards the other
        body (at the motor/shaft junction, the one that holds the pair's distance).
        """
        if not math.isfinite(self.min_distance) or not len(self.distances):
            return None
        r = self._rows
        i = int(np.flatnonzero(r.dist <= self.min_distance + TIE)[0])
        n = r.normal[i]
        a = r.point[i, 0].copy()
        if r.kind[i, 0] == _LEG:
            a -= r.radius[i, 0] * n
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
def _legs_all_parts(bodies: StackBodies, trim_bottom=False, trim_top=False) -> tuple[np.ndarray, ...]:
    """Every leg's motor and shaft (rows 2g, 2g+1): leg, part and
    :func:`~assembler_pin.collision.bodies.leg_segments` (trims given per leg or for all)."""
    G = len(bodies.length)
    g = np.repeat(np.arange(G), 2)
    part = np.tile(np.array([MOTOR, SHAFT]), G)
    tb = np.repeat(np.asarray(trim_bottom), 2) if np.ndim(trim_bottom) else trim_bottom
    tt = np.repeat(np.asarray(trim_top), 2) if np.ndim(trim_top) else trim_top
    return (g, part, *leg_segments(bodies, g, part, tb, tt))


def _best_parts(d: np.ndarray, s: np.ndarray, start, vec, lo, hi, hb, radius) -> tuple[np.ndarray, ...]:
    """Per leg, the closer of its two parts: distances ``d`` (..., 2G) [m] and the parameters
    ``s`` of the closest points on the parts (:func:`_legs_all_parts`' rows) → the distance
    (..., G) [m], the closest point on the axis (..., G, 3) world [m], its σ [m], dσ/dL and
    the radius of the part [m]."""
    G = d.shape[-1] // 2
    pick = np.argmin(d.reshape(*d.shape[:-1], G, 2), axis=-1) + 2 * np.arange(G)
    best, sb = np.take_along_axis(d, pick, axis=-1), np.take_along_axis(s, pick, axis=-1)
    x = start[pick] + sb[..., None] * vec[pick]
    sigma = lo[pick] + sb * np.maximum(hi[pick] - lo[pick], 0.0)
    return best, x, sigma, sb * hb[pick], radius[pick]


def _floor_pass(bodies: StackBodies, lay: _Layout, dist: np.ndarray) -> list[tuple]:
    """Every leg and plate against the floor (a half-space below ``z``): exact, signed, written
    into ``dist`` at the floor's rows; but not the standing plates, nor a leg's ``node_zone``
    at a standing plate. Returns the rows' closest points (:attr:`_Source.scene_rows`)."""
    assert lay.floor is not None
    at, floor_z, trim_bottom, trim_top, k = lay.floor
    _, _, start, vec, lo, hi, hb, radius = _legs_all_parts(bodies, trim_bottom, trim_top)
    s = (vec[:, 2] < 0.0).astype(float)  # the lower end
    d = start[:, 2] + s * vec[:, 2] - floor_z - radius
    d[hi < lo] = np.inf
    best, x, sigma, hbest, rbest = _best_parts(d, s, start, vec, lo, hi, hb, radius)
    G = len(best)
    dist[at : at + G] = best
    on_floor = x.copy()
    on_floor[:, 2] = floor_z
    out: list[tuple] = [(at, sigma, hbest, rbest, np.stack([x, on_floor], 1), _up(G))]
    if len(k):
        plate = lay.cfg.plate
        low, height = cylinder_lowest_point(bodies.p[k], bodies.R[k][:, :, 2], plate.radius, plate.thickness)
        dist[at + G : at + G + len(k)] = height - floor_z
        below = low.copy()
        below[:, 2] = floor_z
        out.append((at + G, None, None, None, np.stack([low, below], 1), _up(len(k))))
    if lay.W:
        c = payload_centre(bodies)
        low, below = c - [0.0, 0.0, lay.cfg.payload.radius], c.copy()
        below[2] = floor_z
        dist[at + G + len(k)] = low[2] - floor_z
        out.append((at + G + len(k), None, None, None, np.stack([low, below])[None], _up(1)))
    return out


def payload_centre(bodies: StackBodies) -> np.ndarray:
    """The payload's centre (3,), world [m]: ``payload.offset`` along plate n's +z."""
    return bodies.p[-1] + bodies.cfg.payload.offset * bodies.R[-1][:, 2]


def _payload_pass(bodies: StackBodies, lay: _Layout, dist: np.ndarray) -> list[tuple]:
    """The payload (a sphere on plate n) against every leg (not the last ``node_zone`` of the
    legs jointed to plate n) and plates 0..n-1: closed forms, exact, written into ``dist``.
    Returns the rows' closest points and normals (:attr:`_Source.scene_rows`)."""
    cfg, G, n = lay.cfg, lay.G, lay.K - 1
    c, rp = payload_centre(bodies), cfg.payload.radius
    top = np.arange(G) // LEGS_PER_PLATFORM == n - 1
    _, _, start, vec, lo, hi, hb, radius = _legs_all_parts(bodies, False, top)
    d_axis, s = segment_point(start, vec, c)
    d = d_axis - radius - rp
    d[hi < lo] = np.inf
    best, x, sigma, hbest, rbest = _best_parts(d, s, start, vec, lo, hi, hb, radius)
    nl = _unit(x - c)
    R, p = bodies.R[:n], bodies.p[:n]
    dc, closest = point_in_cylinder_distance(np.einsum("kji,kj->ki", R, c - p), cfg.plate.radius, cfg.plate.thickness)
    on_plate = p + np.einsum("kij,kj->ki", R, closest)
    nk = _unit(on_plate - c)
    nk = np.where((dc < 0)[:, None], -nk, nk)
    at = lay.payload_at
    dist[at : at + G], dist[at + G : at + G + n] = best, dc - rp
    legs = (at, sigma, hbest, rbest, np.stack([x, c + rp * nl], 1), nl)
    return [legs, (at + G, None, None, None, np.stack([on_plate, c + rp * nk], 1), nk)]


def _up(m: int) -> np.ndarray:
    up = np.zeros((m, 3))
    up[:, 2] = 1.0
    return up


def _spheres_pass(bodies: StackBodies, lay: _Layout, dist: np.ndarray, parts: tuple) -> list[tuple]:
    """Every leg and plate against every sphere, in one pass over (spheres × bodies): closed
    forms, exact, written into ``dist`` at the spheres' rows (per sphere: its G legs, then its
    plates). Returns the rows' closest points and normals (:attr:`_Source.scene_rows`)."""
    centre, r = lay.centres, lay.radii  # (N, 3), (N,) world [m]
    _, _, start, vec, lo, hi, hb, radius = parts
    d_axis, s = segment_point(start[None], vec[None], centre[:, None])  # (N, 2G)
    d = d_axis - radius - r[:, None]
    d[:, hi < lo] = np.inf
    best, x, sigma, hbest, rbest = _best_parts(d, s, start, vec, lo, hi, hb, radius)  # (N, G)
    n = _unit(x - centre[:, None])
    cfg, R, p = lay.cfg, bodies.R, bodies.p
    local = np.einsum("kji,skj->ski", R, centre[:, None] - p)  # Rᵀ (c - p), (N, K, 3)
    dc, closest = point_in_cylinder_distance(local, cfg.plate.radius, cfg.plate.thickness)
    on_plate = p + np.einsum("kij,skj->ski", R, closest)
    nk = _unit(on_plate - centre[:, None])
    nk = np.where((dc < 0)[..., None], -nk, nk)
    N, G, K, W = len(r), lay.G, lay.K, lay.W
    block = dist[lay.sphere_at : lay.sphere_at + N * (G + K + W)].reshape(N, G + K + W)
    block[:, :G] = best
    block[:, G : G + K] = dc - r[:, None]
    point = np.empty((N, G + K + W, 2, 3))
    point[:, :G, 0], point[:, :G, 1] = x, centre[:, None] + r[:, None, None] * n
    point[:, G : G + K, 0], point[:, G : G + K, 1] = on_plate, centre[:, None] + r[:, None, None] * nk
    sig, hbv, rad = np.zeros((N, G + K + W)), np.zeros((N, G + K + W)), np.zeros((N, G + K + W))
    sig[:, :G], hbv[:, :G], rad[:, :G] = sigma, hbest, rbest
    normal = np.concatenate([n, nk], axis=1)
    if W:  # the payload: two spheres
        c, rp = payload_centre(bodies), cfg.payload.radius
        gap = c - centre  # (N, 3)
        block[:, -1] = np.sqrt(np.einsum("ij,ij->i", gap, gap)) - rp - r
        npay = _unit(gap)
        point[:, -1, 0], point[:, -1, 1] = c - rp * npay, centre + r[:, None] * npay
        normal = np.concatenate([normal, npay[:, None]], axis=1)
    return [(lay.sphere_at, sig.ravel(), hbv.ravel(), rad.ravel(), point.reshape(-1, 2, 3), normal.reshape(-1, 3))]


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


_REQUEST: list = []  # coal's distance request, made once


def _coal_distance(shape_a, R_a, p_a, shape_b, R_b, p_b) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """coal's signed distance [m] of two shapes at their world poses, the witness points on
    each (3,), (3,) world [m] and the unit normal from b to a."""
    coal = _coal()
    if not _REQUEST:
        req = coal.DistanceRequest()
        req.gjk_tolerance = GJK_TOLERANCE
        req.gjk_max_iterations = 1000
        _REQUEST.append(req)
    res = coal.DistanceResult()
    d = coal.distance(shape_a, coal.Transform3s(R_a, p_a), shape_b, coal.Transform3s(R_b, p_b), _REQUEST[0], res)
    wa, wb = np.array(res.getNearestPoint1()), np.array(res.getNearestPoint2())
    return float(d), wa, wb, -np.array(res.normal)


def _measure_leg(
    bodies: StackBodies, g: int, lb: np.ndarray, other: tuple, trims: tuple[bool, bool] = (False, False)
) -> tuple | None:
    """One leg against a body coal measures (``other``: shape, R, p): both parts whose bound
    ``lb`` (2,) is finite (the capsules of
    :func:`~assembler_pin.collision.bodies.leg_segments`, trimmed at the bottom and the top
    as ``trims`` says), the closer one ``(d, x_a, x_b, n, σ_a, dσ_a/dL, radius_a)`` (x_a on
    the axis, world [m]); None for none."""
    axis = bodies.axis[g]
    turn = _z_to(axis)
    best = None
    legs, parts = np.array([g, g]), np.array([MOTOR, SHAFT])
    starts, _, los, his, hbs, radii = leg_segments(bodies, legs, parts, trims[0], trims[1])
    for part in (MOTOR, SHAFT):
        lo, hi, hb, radius = float(los[part]), float(his[part]), float(hbs[part]), float(radii[part])
        if not math.isfinite(lb[part]) or hi < lo:
            continue
        length = max(hi - lo, 1e-12)
        start, vec = starts[part], (hi - lo) * axis
        d, wa, wb, n = _coal_distance(_coal().Capsule(radius, length), turn, start + 0.5 * vec, *other)
        s = min(max(float(np.dot(wa - start, axis)) / length, 0.0), 1.0)
        if best is None or d < best[0]:
            best = (d, start + s * vec, wb, n, lo + s * (hi - lo), s * hb, radius)
    return best


def _solids_pass(bodies: StackBodies, lay: _Layout, dist: np.ndarray, parts: tuple) -> np.ndarray:
    """Lower bounds of every leg and plate against every box and cylinder, in one pass over
    (obstacles × bodies), written into ``dist`` at the obstacles' rows (per obstacle: its G
    legs, the smaller bound of their two parts, then its plates). A leg part is held in its
    capsule, a plate in its bounding sphere; each obstacle in its bounding capsule and between
    the two faces of each of its slabs (a box's three, a cylinder's caps): the larger bound.
    Returns the legs' bounds per part (N, G, 2) [m] (:func:`_measure_leg`)."""
    c0, cv, cr = lay.cores  # (N, 3), (N, 3), (N,) world [m]
    centre, axes, half = lay.slabs  # (N, 3), (N, 3, 3) axes as columns, (N, 3) [m]
    _, _, start, vec, lo, hi, _, radius = parts
    d_axis = segment_segment(start[None], vec[None], c0[:, None], cv[:, None])[0]  # (N, 2G)
    h0 = np.matmul(start[None] - centre[:, None], axes)  # (N, 2G, 3): the ends along each axis
    h1 = h0 + np.matmul(vec[None], axes)
    slab = np.maximum(np.minimum(h0, h1), -np.maximum(h0, h1)) - half[:, None]
    lb = np.maximum(d_axis - cr[:, None], slab.max(axis=2)) - radius
    lb[:, hi < lo] = np.inf
    lb = lb.reshape(len(cr), lay.G, 2)
    rho = math.hypot(lay.cfg.plate.radius, 0.5 * lay.cfg.plate.thickness)
    d_plate = segment_point(c0[:, None], cv[:, None], bodies.p)[0] - cr[:, None]  # (N, K)
    h = np.abs(np.matmul(bodies.p[None] - centre[:, None], axes)) - half[:, None]
    width = lay.G + lay.K + lay.W
    block = dist[lay.solid_at : lay.solid_at + len(cr) * width].reshape(len(cr), width)
    block[:, : lay.G] = lb.min(axis=2)
    block[:, lay.G : lay.G + lay.K] = np.maximum(d_plate, h.max(axis=2)) - rho
    if lay.unchecked is not None:  # a support obstacle and a standing plate: never measured
        block[lay.unchecked] = np.inf
    if lay.W:  # the payload's centre held the same way, less its radius
        c = payload_centre(bodies)
        d_c = segment_point(c0, cv, c[None])[0] - cr
        h_c = (np.abs(np.einsum("nji,nj->ni", axes, c - centre)) - half).max(axis=1)
        block[:, -1] = np.maximum(d_c, h_c) - lay.cfg.payload.radius
    return lb


# ---------------------------------------------------------------- the rows of a scene
@dataclass(frozen=True)
class _Layout:
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


def _block(m: int, body: tuple, kind: tuple, index: tuple) -> tuple[np.ndarray, ...]:
    """Static columns of ``m`` rows: each of ``body``, ``kind``, ``index`` a pair of (m,) arrays
    or scalars."""
    columns = (body, kind, index)
    return tuple(np.stack([np.broadcast_to(a, m), np.broadcast_to(b, m)], 1).astype(int) for a, b in columns)


def _build_layout(cfg: AssemblerConfig, scene: Scene | None) -> _Layout:
    t = pair_table(cfg)
    G, K = LEGS_PER_PLATFORM * cfg.platforms, cfg.platforms + 1
    legs, plates = np.arange(G), np.arange(K)
    n, W = cfg.platforms, int(cfg.payload.radius > 0)
    own = (*stack_body_names(n), *(("payload",) if W else ()))
    names = tuple(own)
    blocks = [_block(len(t.leg_a), (t.leg_a, t.leg_b), (_LEG, _LEG), (t.leg_a, t.leg_b))]
    payload_at = -1
    if W:  # the payload, on plate n, against every leg and the plates below plate n
        payload_at = len(t.leg_a)
        blocks.append(_block(G, (legs, len(own) - 1), (_LEG, _PLATE), (legs, n)))
        blocks.append(_block(n, (G + plates[:n], len(own) - 1), (_PLATE, _PLATE), (plates[:n], n)))
    obstacles = () if scene is None else scene.obstacles
    floor = None
    if scene is not None:
        names = (*own, *(o.name for o in obstacles)) + (("floor",) if scene.floor_z is not None else ())
    ids = {o.name: len(own) + i for i, o in enumerate(obstacles)}

    def rows() -> int:
        return sum(len(b[0]) for b in blocks)

    def against(oid: int, k: np.ndarray = plates) -> None:
        blocks.append(_block(G, (legs, oid), (_LEG, _FIXED), (legs, 0)))
        blocks.append(_block(len(k), (G + k, oid), (_PLATE, _FIXED), (k, 0)))
        if W:
            blocks.append(_block(1, (len(own) - 1, oid), (_PLATE, _FIXED), (n, 0)))

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
    blocks.append(_block(len(g), (g, G + k), (_LEG, _PLATE), (g, k)))
    ka, kb = t.plate_pairs[:, 0], t.plate_pairs[:, 1]
    blocks.append(_block(len(ka), (G + ka, G + kb), (_PLATE, _PLATE), (ka, kb)))
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
    return _Layout(
        cfg,
        scene,
        names,
        pairs,
        kind,
        index,
        exact,
        G,
        K,
        len(t.leg_a),
        len(g),
        len(ka),
        X,
        kernel_inputs(cfg),
        payload_at,
        unchecked,
        W,
        lay_leg_plate,
        t.plate_pairs,
        floor,
        sphere_at,
        np.array([o.pose.translation for o in spheres], dtype=float).reshape(-1, 3),
        np.array([o.size[0] for o in spheres], dtype=float),
        solid_at,
        solids,
        (
            np.array([c[0] for c in cores], dtype=float).reshape(-1, 3),
            np.array([c[1] for c in cores], dtype=float).reshape(-1, 3),
            np.array([c[2] for c in cores], dtype=float),
        ),
        (
            np.array([o.pose.translation for o in solids], dtype=float).reshape(-1, 3),
            np.array([o.pose.rotation for o in solids], dtype=float).reshape(-1, 3, 3),
            np.array([_half_widths(o) for o in solids], dtype=float).reshape(-1, 3),
        ),
    )


def _half_widths(o: Obstacle) -> tuple[float, float, float]:
    """Half the width of a box or a cylinder between the faces of its slabs, along its own
    axes [m] (a cylinder has one slab, its caps: ``inf`` across it)."""
    if o.kind == "box":
        return (0.5 * o.size[0], 0.5 * o.size[1], 0.5 * o.size[2])
    return (math.inf, math.inf, 0.5 * o.size[1])


_LAYOUTS: dict[tuple, _Layout] = {}


def _layout(cfg: AssemblerConfig, scene: Scene | None) -> _Layout:
    """The rows of ``cfg`` and ``scene``, built once per configuration object and obstacle
    tuple (by identity: a scene rebuilt from its file builds them again), floor and standing."""
    key = (id(cfg),) if scene is None else (id(cfg), id(scene.obstacles), scene.floor_z, scene.standing)
    hit = _LAYOUTS.get(key)
    if hit is not None and hit.cfg is cfg and (scene is None or (hit.scene and hit.scene.obstacles is scene.obstacles)):
        return hit
    lay = _build_layout(cfg, scene)
    if len(_LAYOUTS) >= 16:
        _LAYOUTS.pop(next(iter(_LAYOUTS)))
    _LAYOUTS[key] = lay
    return lay


_SHAPES: dict[int, tuple] = {}


def _shapes(lay: _Layout) -> tuple:
    """coal's plate cylinder and the layout's boxes and cylinders (shape, R, p), made once per
    layout."""
    hit = _SHAPES.get(id(lay))
    if hit is None or hit[0] is not lay:
        plate = _coal().Cylinder(lay.cfg.plate.radius, max(lay.cfg.plate.thickness, 1e-9))
        solids = [(_obstacle_shape(o), o.pose.rotation, o.pose.translation) for o in lay.solids]
        hit = (lay, plate, solids)
        if len(_SHAPES) >= 16:
            _SHAPES.pop(next(iter(_SHAPES)))
        _SHAPES[id(lay)] = hit
    return hit[1], hit[2]


# ---------------------------------------------------------------- one call
class _Source:
    """The arrays of one clearance: the plate poses, the legs' joint centres and directions
    (``btu`` (3, G, 3)) and lengths, the leg-pair rows (:data:`~assembler_pin.collision.kernel.ROW_WIDTH`
    columns), every row's distance and exactness, the legs' bounds per part against plates
    and obstacles, the scene's closed-form rows' points and what coal measured. The bodies and
    every row's closest points are built from them on first use."""

    __slots__ = (
        "R",
        "_bodies",
        "btu",
        "dist",
        "exact",
        "got",
        "layout",
        "legs",
        "length",
        "lp",
        "lp_row",
        "p",
        "scene_rows",
        "solid_lb",
    )

    def __init__(self, layout, R, p, btu, length, legs, dist, lp, exact) -> None:
        self.layout, self.R, self.p, self.btu, self.length = layout, R, p, btu, length
        self.legs, self.dist, self.lp = legs, dist, lp
        self.lp_row: np.ndarray | None = None  # (Q, 2) the nearer part, its end nearest the plate or -1
        self.exact = exact
        self.solid_lb: np.ndarray | None = None
        # (first row, σ_a, dσ_a/dL, radius_a or None, points (m, 2, 3), normals (m, 3))
        self.scene_rows: list[tuple] = []
        self.got: dict[int, tuple] = {}  # coal's rows: (x_a, x_b, n, σ_a, dσ_a/dL, radius_a)
        self._bodies: StackBodies | None = None

    def bodies(self) -> StackBodies:
        """The stack's bodies (world frame)."""
        if self._bodies is None:
            b = self.btu
            self._bodies = StackBodies(self.layout.cfg, b[0], b[1], b[2], self.length, self.R, self.p)
        return self._bodies

    def rows(self) -> _Rows:
        """Every row with its closest points and normal."""
        lay, legs = self.layout, self.legs
        m, P = lay.m, lay.P
        sigma, hb, radius = np.zeros((m, 2)), np.zeros((m, 2)), np.zeros((m, 2))
        point, normal = np.zeros((m, 2, 3)), _up(m)
        point[:P, 0], point[:P, 1] = legs[:, ROW_XA : ROW_XA + 3], legs[:, ROW_XB : ROW_XB + 3]
        normal[:P] = legs[:, ROW_NORMAL : ROW_NORMAL + 3]
        sigma[:P], hb[:P] = legs[:, ROW_SIGMA : ROW_SIGMA + 2], legs[:, ROW_HB : ROW_HB + 2]
        radius[:P] = legs[:, ROW_RADIUS : ROW_RADIUS + 2]
        self._leg_plate_rows(sigma, hb, radius, point, normal)
        for at, sig, h, rad, pt, nm in self.scene_rows:
            stop = at + len(pt)
            if sig is not None:
                sigma[at:stop, 0], hb[at:stop, 0], radius[at:stop, 0] = sig, h, rad
            point[at:stop], normal[at:stop] = pt, nm
        for r, (xa, xb, n, sig, h, rad) in self.got.items():
            point[r, 0], point[r, 1], normal[r], sigma[r, 0], hb[r, 0], radius[r, 0] = xa, xb, n, sig, h, rad
        return _Rows(self.dist, self.exact, lay.pairs, lay.kind, lay.index, sigma, hb, radius, point, normal)

    def _leg_plate_rows(self, sigma, hb, radius, point, normal) -> None:
        """The closest points of the leg–plate rows exact by the closed form (a part's end over
        the disc: the point below it on the face), into the rows' arrays."""
        lay = self.layout
        if self.lp_row is None:
            return
        rows = np.flatnonzero(self.lp_row[:, 1] >= 0)
        if not len(rows):
            return
        g, k, tb, tt = (lay.leg_plate[rows, c] for c in range(4))
        part = self.lp_row[rows, 0]
        bodies = self.bodies()
        _, _, lo, hi, hbs, rad = leg_segments(bodies, g, part, tb == 1, tt == 1)
        end = self.lp_row[rows, 1]
        s = np.where(end == 1, hi, lo)
        x = bodies.bottom[g] + s[:, None] * bodies.axis[g]
        nk = self.R[k][:, :, 2]
        h = np.einsum("ij,ij->i", x - self.p[k], nk)
        up = np.where(h >= 0, 1.0, -1.0)[:, None] * nk  # from the plate to the leg
        half = 0.5 * lay.cfg.plate.thickness
        r = lay.X + rows
        sigma[r, 0], hb[r, 0], radius[r, 0] = s, np.where(end == 1, hbs, 0.0), rad
        point[r, 0], point[r, 1], normal[r] = x, x - (np.abs(h) - half)[:, None] * up, up


def _scene_pass(src: _Source) -> None:
    """The payload's rows and the scene's: the floor and the spheres exactly, the boxes' and
    cylinders' bounds."""
    lay = src.layout
    bodies = src.bodies()
    if lay.W:
        src.scene_rows += _payload_pass(bodies, lay, src.dist)
    if lay.scene is None:
        return
    if lay.floor is not None:
        src.scene_rows += _floor_pass(bodies, lay, src.dist)
    if len(lay.radii) or lay.solids:
        parts = _legs_all_parts(bodies)
        if len(lay.radii):
            src.scene_rows += _spheres_pass(bodies, lay, src.dist, parts)
        if lay.solids:
            src.solid_lb = _solids_pass(bodies, lay, src.dist, parts)


def _measure_row(src: _Source, r: int) -> None:
    """coal's distance of the screened row ``r``, into the source's arrays."""
    lay, bodies = src.layout, src.bodies()
    plate, solids = _shapes(lay)
    i = r - lay.X
    got: tuple | None
    if i < lay.Q:  # a leg against a plate it does not sit on
        g, k, tb, tt = (int(v) for v in lay.leg_plate[i])
        got = _measure_leg(bodies, g, src.lp[i], (plate, bodies.R[k], bodies.p[k]), (tb == 1, tt == 1))
    elif i < lay.Q + lay.S:  # plate against plate
        a, b = (int(v) for v in lay.plate_pairs[i - lay.Q])
        got = (*_coal_distance(plate, bodies.R[a], bodies.p[a], plate, bodies.R[b], bodies.p[b]), 0.0, 0.0, 0.0)
    else:  # a leg or a plate against a box or a cylinder
        o, j = divmod(i - lay.Q - lay.S, lay.G + lay.K + lay.W)
        fixed = solids[o]
        if j < lay.G:
            assert src.solid_lb is not None
            trims = (False, False)
            if lay.solids[o].support:  # the floor's rule at the standing plates' joints
                platform = j // LEGS_PER_PLATFORM
                standing = lay.scene.standing if lay.scene is not None else ()
                trims = (platform in standing, platform + 1 in standing)
            got = _measure_leg(bodies, j, src.solid_lb[o, j], fixed, trims)
        elif j == lay.G + lay.K:  # the payload
            ball = _coal().Sphere(lay.cfg.payload.radius)
            got = (*_coal_distance(ball, np.eye(3), payload_centre(bodies), *fixed), 0.0, 0.0, 0.0)
        else:
            k = j - lay.G
            got = (*_coal_distance(plate, bodies.R[k], bodies.p[k], *fixed), 0.0, 0.0, 0.0)
    src.exact[r] = True
    if got is None:
        src.dist[r] = np.inf
        return
    src.dist[r] = got[0]
    src.got[r] = got[1:]


def _measure_near(src: _Source, horizon: float) -> None:
    """coal measures the screened rows within ``horizon`` [m], then those whose bound is below
    the smallest distance until none is: the smallest distance is exact."""
    lay, dist = src.layout, src.dist
    X = lay.X
    best = float(dist[:X].min()) if X else math.inf
    if lay.m == X:
        return
    screened, exact = dist[X:], src.exact[X:]
    if exact.any():
        best = min(best, float(screened[exact].min()))
    todo = np.flatnonzero((screened < horizon) & ~exact)
    while True:
        if len(todo):
            for i in todo.tolist():
                _measure_row(src, X + i)
            best = min(best, float(screened[todo].min()))
        todo = np.flatnonzero((screened < best) & ~exact)
        if not len(todo):
            return


def _kernel_pass(lay: _Layout, pa: PlateArrays, dist: np.ndarray) -> _Source:
    """The stack's own rows from the compiled kernel: leg pairs exact, the coal pairs' bounds
    (written into ``dist``), exact too for a leg and a plate whose nearer part has its end
    nearest the plate over the disc (:attr:`~assembler_pin.collision.kernel.OwnPairs.lp_end`)
    while the other part's bound is no nearer. Every array is made for this call: the
    clearance owns them."""
    exact = lay.exact.copy()
    own = own_pairs(lay.kernel_inputs, pa.R, pa.p, dist, lay.X, exact)
    src = _Source(lay, pa.R, pa.p, own.btu, own.length, own.legs, dist, own.lp, exact)
    src.lp_row = own.lp_row
    return src


def physical_bodies(
    am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray
) -> tuple[AssemblerModel, PlateArrays]:
    """The model whose bodies the plates carry and the plates in its order: ``am`` and the
    plates, or for a stack seen from its other end
    (:attr:`~assembler_pin.model.assembler.AssemblerModel.physical`) the original stack and the
    same bodies' plates (plate k there is plate n−k here, its frame turned back)."""
    pa = plate_arrays(am, plates)
    if am.physical is None:
        return am, pa
    original, flip = am.physical
    return original, PlateArrays(np.matmul(pa.R[::-1], flip.T), pa.p[::-1].copy())


def _turned_clearance(am: AssemblerModel, plates, scene: Scene | None) -> Clearance:
    """The clearance of a turned model's plates (:attr:`AssemblerModel.physical`): the original
    stack's at the same bodies, its derivatives in the turned model's plate order (a world twist
    of turned plate k is the same twist of original plate n−k)."""
    original, bodies = physical_bodies(am, plates)
    if scene is not None:
        scene = dataclasses.replace(scene, standing=tuple(sorted(am.n - k for k in scene.standing)))
    return dataclasses.replace(clearance(original, bodies, scene), _reversed=True)


def clearance(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    scene: Scene | str | None = None,
) -> Clearance:
    """The clearance of a pose: every checked pair's distance, the smallest and its two bodies.

    Args:
        am: the model (sizes and the clearance allowed come from its configuration).
        plates: world poses of plates 0..n, plate 0 first.
        scene: obstacles and floor (a :class:`~assembler_pin.collision.scene.Scene`, a path
            of a scene file, or None for the stack's own bodies only).

    Returns:
        a :class:`Clearance` (distances [m], world frame).
    """
    scene = read_scene(scene)
    if am.physical is not None:  # a stack seen from its other end: its bodies are the original's
        return _turned_clearance(am, plates, scene)
    if scene is not None and any(k > am.n for k in scene.standing):
        raise SceneError(f"scene standing {scene.standing} names a plate beyond plate {am.n}")
    pa = plate_arrays(am, plates)
    cfg = am.config
    lay = _layout(cfg, scene)
    dist = np.empty(lay.m)
    src = _kernel_pass(lay, pa, dist)
    if scene is not None or lay.W:
        _scene_pass(src)
    _measure_near(src, cfg.clearance + NEAR)
    if len(dist):
        dmin = float(dist.min())
        first = int(np.argmax(dist <= dmin + TIE))
        pair = lay.pairs[first]
        between = (lay.names[pair[0]], lay.names[pair[1]])
    else:
        dmin, between = math.inf, ("", "")
    return Clearance(dmin, between, cfg.clearance, lay.names, lay.pairs, dist, src.exact, src)
