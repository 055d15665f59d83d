"""A scene in the viewer: obstacles, the floor plane and the closest pair of bodies.

Obstacles (:class:`~assembler_pin.collision.scene.Obstacle`) are drawn as meshcat boxes,
cylinders and spheres at their poses, translucent stone; the floor as a thin translucent
brown slab whose top face is the floor plane. The closest pair is a cyan segment between the
two witness points of a :class:`~assembler_pin.collision.check.Clearance`, with a small ball
at each end. World frame O, metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import meshcat.geometry as mg
import numpy as np

from ..collision.check import Clearance
from ..collision.scene import Obstacle, Scene
from ..model.geometry import DIMENSIONS
from .camera import cylinder_between, translation
from .colors import CLOSEST_PAIR_RGBA, FLOOR_RGBA, OBSTACLE_RGBA, material

__all__ = [
    "FLOOR_THICKNESS",
    "ClosestPair",
    "closest_pair",
    "draw_closest_pair",
    "draw_scene",
    "obstacle_key",
    "obstacle_points",
]

#: Thickness of the drawn floor slab [m] (its top face is the floor plane).
FLOOR_THICKNESS = 0.004
#: Margin of the floor slab around everything drawn [m].
FLOOR_MARGIN = 0.25

# meshcat's cylinder is along its y axis; an obstacle cylinder is along its frame's z
_Y_TO_Z = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def obstacle_key(index: int, obstacle: Obstacle) -> str:
    """The meshcat node name of obstacle ``index``: ``<kind>_<index>`` (names may hold any
    printable character, a ``/`` too, so they name the node in the legend only)."""
    return f"{obstacle.kind}_{index}"


def _geometry(o: Obstacle):
    if o.kind == "box":
        return mg.Box(list(o.size))
    if o.kind == "cylinder":
        return mg.Cylinder(o.size[1], o.size[0])
    return mg.Sphere(o.size[0])


def _transform(o: Obstacle) -> np.ndarray:
    T = o.pose.homogeneous.copy()
    return T @ _Y_TO_Z if o.kind == "cylinder" else T


def obstacle_points(o: Obstacle) -> np.ndarray:
    """Points (m, 3) bounding the obstacle, world [m] (for framing the camera)."""
    if o.kind == "sphere":
        half = np.full(3, o.size[0])
    elif o.kind == "cylinder":
        half = np.array([o.size[0], o.size[0], 0.5 * o.size[1]])
    else:
        half = 0.5 * np.asarray(o.size, dtype=float)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
    return corners @ o.pose.rotation.T + o.pose.translation


def draw_scene(root, scene: Scene, around: np.ndarray) -> np.ndarray:
    """Draw ``scene`` under ``root``: each obstacle at ``root/<obstacle_key>``, the floor at
    ``root/floor`` (a slab under the points ``around`` and the obstacles, with a margin).
    Returns the obstacles' bounding points (m, 3) [m]."""
    root.delete()
    pts = [np.zeros((0, 3))]
    for k, o in enumerate(scene.obstacles):
        node = root[obstacle_key(k, o)]
        node.set_object(_geometry(o), material(OBSTACLE_RGBA))
        node.set_transform(_transform(o))
        pts.append(obstacle_points(o))
    points = np.concatenate(pts)
    if scene.floor_z is not None:
        xy = np.concatenate([np.asarray(around, dtype=float).reshape(-1, 3), points])[:, :2]
        lo, hi = xy.min(axis=0) - FLOOR_MARGIN, xy.max(axis=0) + FLOOR_MARGIN
        centre = np.array([*(0.5 * (lo + hi)), scene.floor_z - 0.5 * FLOOR_THICKNESS])
        node = root["floor"]
        node.set_object(mg.Box([*(hi - lo), FLOOR_THICKNESS]), material(FLOOR_RGBA))
        node.set_transform(translation(centre))
    return points


@dataclass(frozen=True)
class ClosestPair:
    """The closest pair of bodies as drawn.

    Attributes:
        a, b: the witness points on ``between[0]`` and ``between[1]`` (3,), world [m].
        distance: their clearance [m] (negative when the bodies overlap: then ``|a − b|``
            is the depth).
        between: the two bodies' names.
    """

    a: np.ndarray
    b: np.ndarray
    distance: float
    between: tuple[str, str]

    @property
    def label(self) -> str:
        """``closest pair: 0.0123 m between SP1 leg 3 and lower strut`` (metres)."""
        verb = "overlap" if self.distance < 0 else "closest pair"
        return f"{verb}: {self.distance:.4f} m between {self.between[0]} and {self.between[1]}"


def closest_pair(near: Clearance | None) -> ClosestPair | None:
    """The closest pair of a clearance (None when no pair is checked)."""
    if near is None:
        return None
    points = near.witness_points()
    if points is None:
        return None
    return ClosestPair(points[0], points[1], near.min_distance, near.between)


def draw_closest_pair(root, pair: ClosestPair | None) -> None:
    """A cyan segment ``root/segment`` from ``pair.a`` to ``pair.b`` and a ball at each end
    (``root/a``, ``root/b``, centred on the points); nothing for None."""
    root.delete()
    if pair is None:
        return
    ball = 0.4 * DIMENSIONS.motor_radius
    for key, p in (("a", pair.a), ("b", pair.b)):
        root[key].set_object(mg.Sphere(ball), material(CLOSEST_PAIR_RGBA))
        root[key].set_transform(translation(p))
    length = float(np.linalg.norm(pair.b - pair.a))
    if length > 1e-9:
        root["segment"].set_object(mg.Cylinder(length, 0.25 * ball), material(CLOSEST_PAIR_RGBA))
        root["segment"].set_transform(cylinder_between(pair.a, pair.b))
