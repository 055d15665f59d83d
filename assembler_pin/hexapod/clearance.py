"""The hexapod's clearance: every stack's own (:func:`~assembler_pin.collision.clearance`, with
the scene), the stacks' bodies against each other, and the body against the stacks and the scene.

Bodies (:mod:`assembler_pin.collision.bodies`): a leg is two capsules (motor, shaft), a plate a
flat cylinder; the body is a flat cylinder of ``hexapod.body_radius`` and
``hexapod.body_thickness`` resting on the EE plates: its axis is the world z turned with the
body, its bottom face ``plate.thickness / 2`` above the centre of the EE plates' origins. The
body is not checked against the EE plates it is fixed to, nor against the last ``node_zone``
of the legs that end at them. Capsule pairs are measured in closed form; a pair with a plate or
the body by coal, in the order of a lower bound (bounding spheres), until the bound exceeds the
smallest distance found: the minimum is exact.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np
import pinocchio as pin

from ..collision import Scene, clearance, read_scene
from ..collision.bodies import MOTOR, SHAFT, leg_segments, stack_bodies
from ..collision.distance import cylinder_lowest_point, segment_point, segment_segment
from ..kinematics import PlateArrays
from ..model.assembler import AssemblerModel

__all__ = ["HexapodClearance", "hexapod_clearance", "machine_clearance"]


@dataclass(frozen=True)
class HexapodClearance:
    """The smallest distance [m] between two bodies that must not touch, their names and the
    allowed smallest distance (the configuration's ``clearance``)."""

    min_distance: float
    between: tuple[str, str]
    limit: float

    @property
    def clear(self) -> bool:
        return self.min_distance >= self.limit

    @property
    def message(self) -> str:
        a, b = self.between
        return f"{a} and {b} are {self.min_distance:.4g} m apart < clearance {self.limit:g} m"

    def to_dict(self) -> dict:
        return {"min_distance": self.min_distance, "between": list(self.between), "limit": self.limit}


@dataclass(frozen=True)
class _Capsules:
    start: np.ndarray  # (m, 3) [m]
    vector: np.ndarray  # (m, 3) [m]
    radius: np.ndarray  # (m,) [m]
    names: list[str]


def _capsules(am: AssemblerModel, pa: PlateArrays, stack: int, trim_last: bool = False) -> _Capsules:
    bodies = stack_bodies(am, pa)
    legs = np.tile(np.arange(6 * am.n), 2)
    part = np.repeat([MOTOR, SHAFT], 6 * am.n)
    trim = trim_last & (legs >= 6 * (am.n - 1))
    start, vector, _, _, _, radius = leg_segments(bodies, legs, part, trim_top=trim)
    names = [
        f"stack {stack} SP{g // 6 + 1} leg {g % 6 + 1} {'motor' if k == MOTOR else 'shaft'}"
        for g, k in zip(legs, part, strict=True)
    ]
    return _Capsules(start, vector, radius, names)


_Solid = tuple[object, np.ndarray, np.ndarray]  # a coal shape, its rotation and its centre [m]


def _coal_distance(
    shape_a: object, R_a: np.ndarray, p_a: np.ndarray, shape_b: object, R_b: np.ndarray, p_b: np.ndarray
) -> float:
    import coal  # delays coal

    req = coal.DistanceRequest()
    req.gjk_tolerance = 1e-10
    res = coal.DistanceResult()
    return float(coal.distance(shape_a, coal.Transform3s(R_a, p_a), shape_b, coal.Transform3s(R_b, p_b), req, res))


def _z_to(u: np.ndarray) -> np.ndarray:
    """A rotation whose z axis is the unit vector ``u``."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, u)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(u, x), u])


def _capsule_solid(c: _Capsules, m: int) -> _Solid:
    import coal  # delays coal

    length = float(np.linalg.norm(c.vector[m]))
    u = c.vector[m] / length if length > 0 else np.array([0.0, 0.0, 1.0])
    return coal.Capsule(float(c.radius[m]), length), _z_to(u), c.start[m] + 0.5 * c.vector[m]


@dataclass(frozen=True)
class _Disc:
    """A flat cylinder: centre (3,), rotation (3, 3) (axis its z), radius, thickness [m]."""

    name: str
    centre: np.ndarray
    R: np.ndarray
    radius: float
    thickness: float

    @property
    def sphere(self) -> float:
        return math.hypot(self.radius, 0.5 * self.thickness)

    def solid(self) -> _Solid:
        import coal  # delays coal

        return coal.Cylinder(self.radius, self.thickness), self.R, self.centre


_Pair = tuple[float, Callable[[], float], tuple[str, str]]


def _to_capsule(disc: _Disc, caps: _Capsules, m: int) -> float:
    return _coal_distance(*disc.solid(), *_capsule_solid(caps, m))


def _to_disc(disc: _Disc, other: _Disc) -> float:
    return _coal_distance(*disc.solid(), *other.solid())


def _to_solid(disc: _Disc, shape: object, R: np.ndarray, p: np.ndarray) -> float:
    return _coal_distance(*disc.solid(), shape, R, p)


def _disc_pairs(disc: _Disc, caps: _Capsules, discs: list[_Disc], best: float) -> list[_Pair]:
    """(lower bound, exact distance, names) of a disc against capsules and discs, those whose
    bound is below ``best`` (the others cannot be the closest). A capsule's bound is the larger
    of the bounding sphere's and the disc's slab's (``|z| ≤ thickness / 2`` in its frame)."""
    out: list[_Pair] = []
    d, _ = segment_point(caps.start, caps.vector, disc.centre)
    axis = disc.R[:, 2]
    z0, z1 = (caps.start - disc.centre) @ axis, (caps.start + caps.vector - disc.centre) @ axis
    half = 0.5 * disc.thickness
    slab = np.maximum(0.0, np.maximum(np.minimum(z0, z1) - half, -half - np.maximum(z0, z1)))
    bounds = np.maximum(d - disc.sphere, slab) - caps.radius
    for m in np.flatnonzero(bounds < best):
        out.append((float(bounds[m]), partial(_to_capsule, disc, caps, int(m)), (disc.name, caps.names[m])))
    for other in discs:
        bound = float(np.linalg.norm(disc.centre - other.centre)) - disc.sphere - other.sphere
        if bound < best:
            out.append((bound, partial(_to_disc, disc, other), (disc.name, other.name)))
    return out


def _body_disc(am: AssemblerModel, plates: np.ndarray, turn: np.ndarray) -> _Disc:
    hc, plate = am.config.hexapod, am.config.plate
    up = turn[:, 2]
    centre = plates[:, -1, :3, 3].mean(axis=0) + (0.5 * plate.thickness + 0.5 * hc.body_thickness) * up
    return _Disc("body", centre, turn, hc.body_radius, hc.body_thickness)


def _scene_pairs(body: _Disc, scene: Scene | None) -> list[_Pair]:
    if scene is None:
        return []
    import coal  # delays coal

    out: list[_Pair] = []
    if scene.floor_z is not None:
        z = float(cylinder_lowest_point(body.centre, body.R[:, 2], body.radius, body.thickness)[1]) - scene.floor_z
        out.append((z, partial(float, z), ("body", "floor")))
    for o in scene.obstacles:
        shapes = {"box": lambda s: coal.Box(*s), "cylinder": lambda s: coal.Cylinder(s[0], s[1])}
        shape = shapes.get(o.kind, lambda s: coal.Sphere(s[0]))(o.size)
        R, p = o.pose.rotation, o.pose.translation
        out.append((-math.inf, partial(_to_solid, body, shape, R, p), ("body", o.name)))
    return out


def hexapod_clearance(am: AssemblerModel, result, scene: Scene | str | None = None) -> HexapodClearance:
    """The clearance (module doc) of a :class:`~assembler_pin.hexapod.stand.HexapodStand`'s
    equilibrium among ``scene``'s obstacles and floor (a scene, a scene file, or None: the
    machine's own bodies)."""
    return machine_clearance(am, result.plates, pin.exp3(result.body_displacement[3:]), read_scene(scene))


def machine_clearance(
    am: AssemblerModel, plates: np.ndarray, turn: np.ndarray, scene: Scene | None
) -> HexapodClearance:
    """The clearance (module doc) of the plates ``plates`` (k, n+1, 4, 4), the body turned by
    ``turn`` (3, 3) from the world axes, among ``scene``'s obstacles and floor."""
    k = plates.shape[0]
    pas = [PlateArrays(plates[i, :, :3, :3], plates[i, :, :3, 3]) for i in range(k)]
    best, between = math.inf, ("", "")
    for i, pa in enumerate(pas):
        own = clearance(am, pa, scene)
        if own.min_distance < best:
            best, between = own.min_distance, (f"stack {i} {own.between[0]}", f"stack {i} {own.between[1]}")
    caps = [_capsules(am, pa, i) for i, pa in enumerate(pas)]
    radius, thickness = am.config.plate.radius, am.config.plate.thickness
    discs = [
        [_Disc(f"stack {i} plate {j}", pa.p[j], pa.R[j], radius, thickness) for j in range(am.n + 1)]
        for i, pa in enumerate(pas)
    ]
    pairs: list[_Pair] = []
    for i in range(k):
        for j in range(i + 1, k):
            a_, b_ = caps[i], caps[j]
            d = segment_segment(a_.start[:, None], a_.vector[:, None], b_.start[None], b_.vector[None])[0]
            d = d - a_.radius[:, None] - b_.radius[None]
            a, b = np.unravel_index(int(np.argmin(d)), d.shape)
            if d[a, b] < best:
                best, between = float(d[a, b]), (caps[i].names[a], caps[j].names[b])
            for disc in discs[i]:
                pairs += _disc_pairs(disc, caps[j], discs[j], best)
            for disc in discs[j]:
                pairs += _disc_pairs(disc, caps[i], [], best)
    body = _body_disc(am, plates, turn)
    trimmed = [_capsules(am, pa, i, trim_last=True) for i, pa in enumerate(pas)]
    for i in range(k):
        pairs += _disc_pairs(body, trimmed[i], discs[i][:-1], best)
    pairs += _scene_pairs(body, scene)
    for bound, exact, names in sorted(pairs, key=lambda t: t[0]):
        if bound >= best:
            break
        distance = exact()
        if distance < best:
            best, between = distance, names
    return HexapodClearance(float(best), between, float(am.config.clearance))
