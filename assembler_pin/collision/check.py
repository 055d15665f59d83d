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

The rows of a configuration and a scene (:class:`~assembler_pin.collision.layout.Layout`:
pairs, order, the kernel's inputs) are built once per configuration object and obstacle tuple;
a call fills one distance array.

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

from ..exceptions import SceneError
from ..kinematics import PlateArrays, plate_arrays
from ..model.assembler import AssemblerModel
from ..model.geometry import LEGS_PER_PLATFORM
from .bodies import StackBodies, leg_segments
from .closed import floor_pass, legs_all_parts, payload_centre, payload_pass, spheres_pass, up_normals
from .home import TIE
from .kernel import ROW_HB, ROW_NORMAL, ROW_RADIUS, ROW_SIGMA, ROW_XA, ROW_XB, own_pairs
from .layout import LEG, PLATE, Layout, layout_of
from .scene import Scene, read_scene
from .screens import coal_distance, coal_module, measure_leg, shapes_of, solids_pass

__all__ = ["NEAR", "Clearance", "clearance", "physical_bodies"]

logger = logging.getLogger(__name__)

#: Pairs whose screening bound is within this of the clearance are measured exactly [m].
NEAR = 0.05


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


def unit(v: np.ndarray) -> np.ndarray:
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
        if r.kind[i, 0] == LEG:
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
            at = np.nonzero(kind == PLATE)[0]
            np.add.at(out, (at, idx[at]), sign * np.hstack([n[at], np.cross(x[at], n[at])]))
            at = np.nonzero(kind == LEG)[0]
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
        point, normal = np.zeros((m, 2, 3)), up_normals(m)
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
        src.scene_rows += payload_pass(bodies, lay, src.dist)
    if lay.scene is None:
        return
    if lay.floor is not None:
        src.scene_rows += floor_pass(bodies, lay, src.dist)
    if len(lay.radii) or lay.solids:
        parts = legs_all_parts(bodies)
        if len(lay.radii):
            src.scene_rows += spheres_pass(bodies, lay, src.dist, parts)
        if lay.solids:
            src.solid_lb = solids_pass(bodies, lay, src.dist, parts)


def _measure_row(src: _Source, r: int) -> None:
    """coal's distance of the screened row ``r``, into the source's arrays."""
    lay, bodies = src.layout, src.bodies()
    plate, solids = shapes_of(lay)
    i = r - lay.X
    got: tuple | None
    if i < lay.Q:  # a leg against a plate it does not sit on
        g, k, tb, tt = (int(v) for v in lay.leg_plate[i])
        got = measure_leg(bodies, g, src.lp[i], (plate, bodies.R[k], bodies.p[k]), (tb == 1, tt == 1))
    elif i < lay.Q + lay.S:  # plate against plate
        a, b = (int(v) for v in lay.plate_pairs[i - lay.Q])
        got = (*coal_distance(plate, bodies.R[a], bodies.p[a], plate, bodies.R[b], bodies.p[b]), 0.0, 0.0, 0.0)
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
            got = measure_leg(bodies, j, src.solid_lb[o, j], fixed, trims)
        elif j == lay.G + lay.K:  # the payload
            ball = coal_module().Sphere(lay.cfg.payload.radius)
            got = (*coal_distance(ball, np.eye(3), payload_centre(bodies), *fixed), 0.0, 0.0, 0.0)
        else:
            k = j - lay.G
            got = (*coal_distance(plate, bodies.R[k], bodies.p[k], *fixed), 0.0, 0.0, 0.0)
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


def _kernel_pass(lay: Layout, pa: PlateArrays, dist: np.ndarray) -> _Source:
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
    lay = layout_of(cfg, scene)
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
