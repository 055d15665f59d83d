"""The screened rows of a clearance: lower bounds, and coal's distance for the near ones.

Plates against legs and plates, and legs or plates against boxes and cylinders, have no
closed form here: a cheap lower bound (bounding capsules and spheres, slabs between parallel
faces) screens them, and coal's GJK (``coal.distance``) measures those near the clearance.
"""

from __future__ import annotations

import math

import numpy as np

from .bodies import MOTOR, SHAFT, StackBodies, leg_segments
from .closed import payload_centre
from .distance import segment_point, segment_segment
from .layout import Layout
from .scene import Obstacle

__all__ = [
    "GJK_TOLERANCE",
    "coal_distance",
    "coal_module",
    "measure_leg",
    "obstacle_shape",
    "shapes_of",
    "solids_pass",
    "z_to",
]

#: coal's GJK tolerance [m] (the default, 1e-6, leaves the distance noisy at that level: too
#: coarse for derivatives held to central differences). The penetration depth of overlapping
#: pairs comes from coal's EPA at its default tolerance: its derivative is good to ~1e-3.
GJK_TOLERANCE = 1e-10


def coal_module():
    import coal  # shipped with pin; imported on the first pair that needs it

    return coal


def obstacle_shape(o: Obstacle):
    coal = coal_module()
    if o.kind == "box":
        return coal.Box(*o.size)
    return coal.Cylinder(o.size[0], o.size[1])


def z_to(u: np.ndarray) -> np.ndarray:
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


def coal_distance(shape_a, R_a, p_a, shape_b, R_b, p_b) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """coal's signed distance [m] of two shapes at their world poses, the witness points on
    each (3,), (3,) world [m] and the unit normal from b to a."""
    coal = coal_module()
    if not _REQUEST:
        req = coal.DistanceRequest()
        req.gjk_tolerance = GJK_TOLERANCE
        req.gjk_max_iterations = 1000
        _REQUEST.append(req)
    res = coal.DistanceResult()
    d = coal.distance(shape_a, coal.Transform3s(R_a, p_a), shape_b, coal.Transform3s(R_b, p_b), _REQUEST[0], res)
    wa, wb = np.array(res.getNearestPoint1()), np.array(res.getNearestPoint2())
    return float(d), wa, wb, -np.array(res.normal)


def measure_leg(
    bodies: StackBodies, g: int, lb: np.ndarray, other: tuple, trims: tuple[bool, bool] = (False, False)
) -> tuple | None:
    """One leg against a body coal measures (``other``: shape, R, p): both parts whose bound
    ``lb`` (2,) is finite (the capsules of
    :func:`~assembler_pin.collision.bodies.leg_segments`, trimmed at the bottom and the top
    as ``trims`` says), the closer one ``(d, x_a, x_b, n, σ_a, dσ_a/dL, radius_a)`` (x_a on
    the axis, world [m]); None for none."""
    axis = bodies.axis[g]
    turn = z_to(axis)
    best = None
    legs, parts = np.array([g, g]), np.array([MOTOR, SHAFT])
    starts, _, los, his, hbs, radii = leg_segments(bodies, legs, parts, trims[0], trims[1])
    for part in (MOTOR, SHAFT):
        lo, hi, hb, radius = float(los[part]), float(his[part]), float(hbs[part]), float(radii[part])
        if not math.isfinite(lb[part]) or hi < lo:
            continue
        length = max(hi - lo, 1e-12)
        start, vec = starts[part], (hi - lo) * axis
        d, wa, wb, n = coal_distance(coal_module().Capsule(radius, length), turn, start + 0.5 * vec, *other)
        s = min(max(float(np.dot(wa - start, axis)) / length, 0.0), 1.0)
        if best is None or d < best[0]:
            best = (d, start + s * vec, wb, n, lo + s * (hi - lo), s * hb, radius)
    return best


def solids_pass(bodies: StackBodies, lay: Layout, dist: np.ndarray, parts: tuple) -> np.ndarray:
    """Lower bounds of every leg and plate against every box and cylinder, in one pass over
    (obstacles × bodies), written into ``dist`` at the obstacles' rows (per obstacle: its G
    legs, the smaller bound of their two parts, then its plates). A leg part is held in its
    capsule, a plate in its bounding sphere; each obstacle in its bounding capsule and between
    the two faces of each of its slabs (a box's three, a cylinder's caps): the larger bound.
    Returns the legs' bounds per part (N, G, 2) [m] (:func:`measure_leg`)."""
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


_SHAPES: dict[int, tuple] = {}


def shapes_of(lay: Layout) -> tuple:
    """coal's plate cylinder and the layout's boxes and cylinders (shape, R, p), made once per
    layout."""
    hit = _SHAPES.get(id(lay))
    if hit is None or hit[0] is not lay:
        plate = coal_module().Cylinder(lay.cfg.plate.radius, max(lay.cfg.plate.thickness, 1e-9))
        solids = [(obstacle_shape(o), o.pose.rotation, o.pose.translation) for o in lay.solids]
        hit = (lay, plate, solids)
        if len(_SHAPES) >= 16:
            _SHAPES.pop(next(iter(_SHAPES)))
        _SHAPES[id(lay)] = hit
    return hit[1], hit[2]
