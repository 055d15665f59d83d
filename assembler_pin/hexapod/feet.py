"""Feet resting on a floor: what a foot's wrench must satisfy, and the static stability margin.

A foot plate rests flat on the horizontal floor through its bottom face, ``plate.thickness / 2``
below its origin. The ground's wrench on it ``w = [f, m]`` (world axes, moment about the plate's
origin) is admissible when

* the normal force pushes: ``f_z ≥ 0`` (a foot that would pull lifts off);
* Coulomb friction holds it: ``|f_xy| ≤ μ f_z``;
* the centre of pressure (the point of the floor about which the moment has no horizontal
  part) lies inside the plate's disc of radius ``plate.radius``.

The support polygon is the convex hull of the contact discs (the feet on the floor); the static
stability margin is the signed distance from the floor projection of the machine's centre of
mass to its edge [m], positive inside: the hull of the disc centres grown by the disc radius,
so the margin is ``radius + signed distance to the hull of the centres``.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

__all__ = ["centre_of_pressure", "foot_violations", "stability_margin"]


def centre_of_pressure(wrench: np.ndarray, foot: np.ndarray, depth: float) -> np.ndarray:
    """(2,) the centre of pressure's horizontal offset [m] from the foot's origin ``foot`` (3,)
    of the ground's ``wrench`` (6,) (moment about ``foot``), the floor ``depth`` [m] below
    ``foot``; NaN when the normal force is not positive."""
    f, m = wrench[:3], wrench[3:]
    if not f[2] > 0:
        return np.full(2, np.nan)
    m_floor = m + np.cross([0.0, 0.0, depth], f)  # about the floor point under the origin
    return np.array([-m_floor[1], m_floor[0]]) / f[2]


def foot_violations(
    i: int, wrench: np.ndarray, foot: np.ndarray, friction: float, radius: float, depth: float, tol: float
) -> list[str]:
    """What foot ``i``'s ground wrench breaks (module doc), one line each; ``tol`` [N] absorbs
    round-off."""
    f = wrench[:3]
    out = []
    if f[2] < -tol:
        out.append(f"foot {i} would pull on the floor (normal force {f[2]:.4g} N)")
        return out
    tangential = float(np.hypot(f[0], f[1]))
    if tangential > friction * f[2] + tol:
        out.append(f"foot {i} slips: tangential force {tangential:.4g} N > friction {friction:g} x normal {f[2]:.4g} N")
    cop = centre_of_pressure(wrench, foot, depth)
    off = float(np.hypot(*cop))
    if f[2] > tol and off > radius:
        out.append(f"foot {i} rolls on its edge: centre of pressure {off:.4g} m from its centre > {radius:g} m")
    return out


def _signed_distance(point: np.ndarray, centres: np.ndarray) -> float:
    """Signed distance [m] from ``point`` (2,) to the convex hull of ``centres`` (m, 2),
    positive inside (a point or a segment has no inside: minus the distance to it)."""
    try:
        hull = ConvexHull(centres)
        vertices = centres[hull.vertices]
    except (QhullError, ValueError):  # fewer than three points, or all on one line
        vertices = None
    if vertices is None:
        far = centres[int(np.argmax(np.linalg.norm(centres - centres[0], axis=1)))]
        along = (centres - centres[0]) @ (far - centres[0])
        ends = centres[[int(np.argmin(along)), int(np.argmax(along))]]
        d = ends[1] - ends[0]
        t = 0.0 if not d.any() else float(np.clip((point - ends[0]) @ d / (d @ d), 0.0, 1.0))
        return -float(np.linalg.norm(point - (ends[0] + t * d)))
    a, b = vertices, np.roll(vertices, -1, axis=0)
    edge = b - a
    t = np.clip(np.einsum("ij,ij->i", point - a, edge) / np.einsum("ij,ij->i", edge, edge), 0.0, 1.0)
    distance = float(np.linalg.norm(point - (a + t[:, None] * edge), axis=1).min())
    # scipy's 2-D hull vertices run counter-clockwise: inside is left of every edge
    inside = bool(np.all(edge[:, 0] * (point - a)[:, 1] - edge[:, 1] * (point - a)[:, 0] >= 0.0))
    return distance if inside else -distance


def stability_margin(com_xy: np.ndarray, feet_xy: np.ndarray, radius: float) -> float:
    """The static stability margin [m] (module doc) of a centre of mass over ``com_xy`` (2,)
    standing on the contact discs of radius ``radius`` [m] centred at ``feet_xy`` (m, 2);
    ``-inf`` with no foot on the floor."""
    if len(feet_xy) == 0:
        return -np.inf
    return radius + _signed_distance(np.asarray(com_xy, float), np.asarray(feet_xy, float))
