"""The closed-form rows of a clearance: the payload, the floor and the spheres.

Each pass measures every body of one kind at once (numpy, vectorized) and returns its rows'
closest points and normals for the derivatives: ``(first row, σ_a, dσ_a/dL, radius_a,
points (m, 2, 3), normals (m, 3))`` (σ, dσ/dL and the radius None for rows without a leg).
"""

from __future__ import annotations

import numpy as np

from ..model.geometry import LEGS_PER_PLATFORM
from .bodies import MOTOR, SHAFT, StackBodies, leg_segments
from .distance import cylinder_lowest_point, point_in_cylinder_distance, segment_point
from .layout import Layout

__all__ = [
    "best_parts",
    "floor_pass",
    "legs_all_parts",
    "payload_centre",
    "payload_pass",
    "spheres_pass",
    "unit",
    "up_normals",
]


def unit(v: np.ndarray) -> np.ndarray:
    norm = np.sqrt(np.einsum("...k,...k->...", v, v))
    fallback = np.broadcast_to(np.array([0.0, 0.0, 1.0]), v.shape)
    return np.where(norm[..., None] > 1e-15, v / np.maximum(norm, 1e-300)[..., None], fallback)


def legs_all_parts(bodies: StackBodies, trim_bottom=False, trim_top=False) -> tuple[np.ndarray, ...]:
    """Every leg's motor and shaft (rows 2g, 2g+1): leg, part and
    :func:`~assembler_pin.collision.bodies.leg_segments` (trims given per leg or for all)."""
    G = len(bodies.length)
    g = np.repeat(np.arange(G), 2)
    part = np.tile(np.array([MOTOR, SHAFT]), G)
    tb = np.repeat(np.asarray(trim_bottom), 2) if np.ndim(trim_bottom) else trim_bottom
    tt = np.repeat(np.asarray(trim_top), 2) if np.ndim(trim_top) else trim_top
    return (g, part, *leg_segments(bodies, g, part, tb, tt))


def best_parts(d: np.ndarray, s: np.ndarray, start, vec, lo, hi, hb, radius) -> tuple[np.ndarray, ...]:
    """Per leg, the closer of its two parts: distances ``d`` (..., 2G) [m] and the parameters
    ``s`` of the closest points on the parts (:func:`legs_all_parts`' rows) → the distance
    (..., G) [m], the closest point on the axis (..., G, 3) world [m], its σ [m], dσ/dL and
    the radius of the part [m]."""
    G = d.shape[-1] // 2
    pick = np.argmin(d.reshape(*d.shape[:-1], G, 2), axis=-1) + 2 * np.arange(G)
    best, sb = np.take_along_axis(d, pick, axis=-1), np.take_along_axis(s, pick, axis=-1)
    x = start[pick] + sb[..., None] * vec[pick]
    sigma = lo[pick] + sb * np.maximum(hi[pick] - lo[pick], 0.0)
    return best, x, sigma, sb * hb[pick], radius[pick]


def floor_pass(bodies: StackBodies, lay: Layout, dist: np.ndarray) -> list[tuple]:
    """Every leg and plate against the floor (a half-space below ``z``): exact, signed, written
    into ``dist`` at the floor's rows; but not the standing plates, nor a leg's ``node_zone``
    at a standing plate. Returns the rows' closest points (the row tuples above)."""
    assert lay.floor is not None
    at, floor_z, trim_bottom, trim_top, k = lay.floor
    _, _, start, vec, lo, hi, hb, radius = legs_all_parts(bodies, trim_bottom, trim_top)
    s = (vec[:, 2] < 0.0).astype(float)  # the lower end
    d = start[:, 2] + s * vec[:, 2] - floor_z - radius
    d[hi < lo] = np.inf
    best, x, sigma, hbest, rbest = best_parts(d, s, start, vec, lo, hi, hb, radius)
    G = len(best)
    dist[at : at + G] = best
    on_floor = x.copy()
    on_floor[:, 2] = floor_z
    out: list[tuple] = [(at, sigma, hbest, rbest, np.stack([x, on_floor], 1), up_normals(G))]
    if len(k):
        plate = lay.cfg.plate
        low, height = cylinder_lowest_point(bodies.p[k], bodies.R[k][:, :, 2], plate.radius, plate.thickness)
        dist[at + G : at + G + len(k)] = height - floor_z
        below = low.copy()
        below[:, 2] = floor_z
        out.append((at + G, None, None, None, np.stack([low, below], 1), up_normals(len(k))))
    if lay.W:
        c = payload_centre(bodies)
        low, below = c - [0.0, 0.0, lay.cfg.payload.radius], c.copy()
        below[2] = floor_z
        dist[at + G + len(k)] = low[2] - floor_z
        out.append((at + G + len(k), None, None, None, np.stack([low, below])[None], up_normals(1)))
    return out


def payload_centre(bodies: StackBodies) -> np.ndarray:
    """The payload's centre (3,), world [m]: ``payload.offset`` along plate n's +z."""
    return bodies.p[-1] + bodies.cfg.payload.offset * bodies.R[-1][:, 2]


def payload_pass(bodies: StackBodies, lay: Layout, dist: np.ndarray) -> list[tuple]:
    """The payload (a sphere on plate n) against every leg (not the last ``node_zone`` of the
    legs jointed to plate n) and plates 0..n-1: closed forms, exact, written into ``dist``.
    Returns the rows' closest points and normals (the row tuples above)."""
    cfg, G, n = lay.cfg, lay.G, lay.K - 1
    c, rp = payload_centre(bodies), cfg.payload.radius
    top = np.arange(G) // LEGS_PER_PLATFORM == n - 1
    _, _, start, vec, lo, hi, hb, radius = legs_all_parts(bodies, False, top)
    d_axis, s = segment_point(start, vec, c)
    d = d_axis - radius - rp
    d[hi < lo] = np.inf
    best, x, sigma, hbest, rbest = best_parts(d, s, start, vec, lo, hi, hb, radius)
    nl = unit(x - c)
    R, p = bodies.R[:n], bodies.p[:n]
    dc, closest = point_in_cylinder_distance(np.einsum("kji,kj->ki", R, c - p), cfg.plate.radius, cfg.plate.thickness)
    on_plate = p + np.einsum("kij,kj->ki", R, closest)
    nk = unit(on_plate - c)
    nk = np.where((dc < 0)[:, None], -nk, nk)
    at = lay.payload_at
    dist[at : at + G], dist[at + G : at + G + n] = best, dc - rp
    legs = (at, sigma, hbest, rbest, np.stack([x, c + rp * nl], 1), nl)
    return [legs, (at + G, None, None, None, np.stack([on_plate, c + rp * nk], 1), nk)]


def up_normals(m: int) -> np.ndarray:
    up = np.zeros((m, 3))
    up[:, 2] = 1.0
    return up


def spheres_pass(bodies: StackBodies, lay: Layout, dist: np.ndarray, parts: tuple) -> list[tuple]:
    """Every leg and plate against every sphere, in one pass over (spheres × bodies): closed
    forms, exact, written into ``dist`` at the spheres' rows (per sphere: its G legs, then its
    plates). Returns the rows' closest points and normals (the row tuples above)."""
    centre, r = lay.centres, lay.radii  # (N, 3), (N,) world [m]
    _, _, start, vec, lo, hi, hb, radius = parts
    d_axis, s = segment_point(start[None], vec[None], centre[:, None])  # (N, 2G)
    d = d_axis - radius - r[:, None]
    d[:, hi < lo] = np.inf
    best, x, sigma, hbest, rbest = best_parts(d, s, start, vec, lo, hi, hb, radius)  # (N, G)
    n = unit(x - centre[:, None])
    cfg, R, p = lay.cfg, bodies.R, bodies.p
    local = np.einsum("kji,skj->ski", R, centre[:, None] - p)  # Rᵀ (c - p), (N, K, 3)
    dc, closest = point_in_cylinder_distance(local, cfg.plate.radius, cfg.plate.thickness)
    on_plate = p + np.einsum("kij,skj->ski", R, closest)
    nk = unit(on_plate - centre[:, None])
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
        npay = unit(gap)
        point[:, -1, 0], point[:, -1, 1] = c - rp * npay, centre + r[:, None] * npay
        normal = np.concatenate([normal, npay[:, None]], axis=1)
    return [(lay.sphere_at, sig.ravel(), hbv.ravel(), rad.ravel(), point.reshape(-1, 2, 3), normal.reshape(-1, 3))]
