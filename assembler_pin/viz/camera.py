"""Frames and the camera: the one frame-along-an-axis helper, and a side camera framing points.

Everything in the world frame O (z up), metres. meshcat's orbit camera always turns about the
world origin, so :func:`point_camera` translates the whole scene by ``-target`` and places the
camera relative to it.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import meshcat
import numpy as np
import numpy.typing as npt

from .colors import BACKGROUND_RGB

__all__ = [
    "CAMERA_FOV_DEG",
    "Camera",
    "camera_for_points",
    "cylinder_between",
    "frame_along_axis",
    "point_camera",
    "translation",
]

CAMERA_FOV_DEG = 75.0
"""Vertical field of view of meshcat's default perspective camera [deg]."""


@dataclass(frozen=True)
class Camera:
    """A camera pose for meshcat: look at ``target`` from ``position`` (world, [m])."""

    target: np.ndarray
    position: np.ndarray


DEFAULT_ELEVATION_DEG = 35.0
"""How far above the horizontal the default camera looks down [deg]: high enough that the
floor grid reads as a floor (foreshortened by sin 35° = 0.57, not to a band), low enough that
the plates stay apart."""


def camera_for_points(
    points: npt.ArrayLike,
    elevation_deg: float = DEFAULT_ELEVATION_DEG,
    azimuth_deg: float = -90.0,
    margin: float = 1.15,
    aspect: float = 4.0 / 3.0,
) -> Camera:
    """A side camera framing every point: z up, looking horizontally at the box centre.

    Args:
        points: (m, 3) world points to frame [m].
        elevation_deg: camera height angle above the horizontal [deg].
        azimuth_deg: direction of the camera from the target in the x–y plane [deg];
            -90° looks from -y towards +y (x to the right, z up: the paper's side view).
        margin: factor on the distance that just fits the points.
        aspect: expected width / height of the window.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    target = 0.5 * (lo + hi)
    radius_v = 0.5 * (hi[2] - lo[2])
    radius_h = 0.5 * max(hi[0] - lo[0], hi[1] - lo[1])
    half_fov = math.radians(CAMERA_FOV_DEG) / 2
    fit_v = radius_v / math.tan(half_fov)
    fit_h = radius_h / (math.tan(half_fov) * aspect)
    distance = margin * max(fit_v, fit_h, 0.2) + radius_h  # + radius_h: the near side is closer
    el, az = math.radians(elevation_deg), math.radians(azimuth_deg)
    direction = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    return Camera(target, target + distance * direction)


def frame_along_axis(axis: npt.ArrayLike, origin: npt.ArrayLike, column: int = 2) -> np.ndarray:
    """A right-handed 4×4 frame at ``origin`` whose axis ``column`` (0 x, 1 y, 2 z) points
    along ``axis`` (any length; a zero vector stands for world z). The turn about that axis
    is arbitrary (every caller draws a shape symmetric about it)."""
    a = np.asarray(axis, dtype=float)
    norm = float(np.linalg.norm(a))
    a = a / norm if norm > 0 else np.array([0.0, 0.0, 1.0])
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(helper, a)
    u /= np.linalg.norm(u)
    T = np.eye(4)
    T[:3, column] = a
    T[:3, (column + 1) % 3] = u  # cyclic order keeps the frame right-handed
    T[:3, (column + 2) % 3] = np.cross(a, u)
    T[:3, 3] = np.asarray(origin, dtype=float)
    return T


def cylinder_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """4×4 transform placing meshcat's y-axis cylinder (centred) between points a and b [m]."""
    return frame_along_axis(b - a, 0.5 * (a + b), column=1)


def translation(p: npt.ArrayLike) -> np.ndarray:
    """The 4×4 translation by ``p`` [m]."""
    T = np.eye(4)
    T[:3, 3] = np.asarray(p, dtype=float)
    return T


def point_camera(vis: meshcat.Visualizer, cam: Camera, roots: Iterable[str], show_grid: bool = True) -> np.ndarray:
    """Aim meshcat's camera: translate the grid, the axes and every ``roots`` path by
    ``-cam.target``, put the camera at ``cam.position`` relative to it, set the neutral
    background. Returns the scene's offset (3,) [m]."""
    offset = -np.asarray(cam.target, dtype=float)
    shift = translation(offset)
    for root in ["/Grid", "/Axes", *roots]:
        vis[root].set_transform(shift)
    rel = cam.position - cam.target
    vis["/Cameras/default"].set_transform(np.eye(4))
    # three.js is y-up: world (x, y, z) -> (x, z, -y)
    vis["/Cameras/default/rotated/<object>"].set_property("position", [rel[0], rel[2], -rel[1]])
    vis["/Grid"].set_property("visible", show_grid)
    vis["/Background"].set_property("top_color", BACKGROUND_RGB[0].tolist())
    vis["/Background"].set_property("bottom_color", BACKGROUND_RGB[1].tolist())
    return offset
