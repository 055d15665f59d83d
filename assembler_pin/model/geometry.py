"""Geometry of the stack: joint anchor points, home pose and body dimensions.

Frames: every plate k has a frame at its centre, z along the plate normal. Plate 0 is
the base; the world frame O has z up and gravity along -z. Stewart platform (SP) j joins
plate j (bottom) to plate j+1 (top).

Plate k carries three joint nodes on a circle of radius ``node_radius`` at angles
``90° + 60°·k + 120°·m`` (m = 0, 1, 2). A node holds two leg ends ``node_spacing``
apart. Leg ``i = 2m`` of SP j runs from bottom node m (end at +spacing/2) to the top
node at +60°; leg ``i = 2m + 1`` from bottom node m (end at -spacing/2) to the top node
at -60°. All arrays below are indexed ``[platform j, leg i, ...]``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..config.schema import AssemblerConfig

__all__ = [
    "LEGS_PER_PLATFORM",
    "BodyDimensions",
    "LegGeometry",
    "home_plates",
    "leg_geometry",
    "reach_bound",
    "rotation_z_to",
]

LEGS_PER_PLATFORM = 6


@dataclass(frozen=True)
class BodyDimensions:
    """Sizes of the bodies used for inertias and display [m].

    The motor is a solid cylinder from the bottom joint centre to twice its centre of
    mass distance; the shaft a solid cylinder from the top joint centre down to twice its
    own. Plates are thin discs of the node radius. The payload is shown as a cube.
    """

    motor_radius: float = 0.016
    shaft_radius: float = 0.006
    plate_thickness: float = 0.01
    node_sphere_radius: float = 0.012
    payload_size: float = 0.08


DIMENSIONS = BodyDimensions()


@dataclass(frozen=True)
class LegGeometry:
    """Anchor points and home directions of every leg.

    Attributes:
        bottom_in_plate: (n, 6, 3) bottom joint centres in the bottom plate's frame [m].
        top_in_plate: (n, 6, 3) top joint centres in the top plate's frame [m].
        home_direction: (n, 6, 3) unit leg direction in the home pose, in the bottom
            plate's frame (equal to the top plate's frame at home: plates are parallel).
        leg_base_rotation: (n, 6, 3, 3) rotation from the bottom plate's frame to the
            universal joint's frame, whose z axis is the home direction.
    """

    bottom_in_plate: np.ndarray
    top_in_plate: np.ndarray
    home_direction: np.ndarray
    leg_base_rotation: np.ndarray


def _circle_points(radius: float, angles_rad: np.ndarray) -> np.ndarray:
    return np.stack(
        [radius * np.cos(angles_rad), radius * np.sin(angles_rad), np.zeros_like(angles_rad)],
        axis=-1,
    )


def rotation_z_to(direction: np.ndarray) -> np.ndarray:
    """Smallest rotation taking the unit z axis onto ``direction`` (a unit 3-vector)."""
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    z = np.array([0.0, 0.0, 1.0])
    axis = np.cross(z, d)
    s = np.linalg.norm(axis)
    if s < 1e-12:
        return np.eye(3) if d[2] > 0 else pin.exp3(np.array([np.pi, 0.0, 0.0]))
    return pin.exp3(axis / s * np.arctan2(s, float(d @ z)))


def leg_geometry(cfg: AssemblerConfig) -> LegGeometry:
    """Anchor points and home directions of every leg of the stack (see module doc)."""
    n = cfg.platforms
    r = cfg.plate.node_radius
    half = 0.5 * cfg.node_spacing
    third = np.deg2rad(60.0)
    bottom_angles = np.empty((n, LEGS_PER_PLATFORM))
    top_angles = np.empty((n, LEGS_PER_PLATFORM))
    for j in range(n):
        for m in range(3):
            node = np.deg2rad(90.0 + 60.0 * j + 120.0 * m)
            bottom_angles[j, 2 * m] = node + half
            top_angles[j, 2 * m] = node + third - half
            bottom_angles[j, 2 * m + 1] = node - half
            top_angles[j, 2 * m + 1] = node - third + half
    bottom = _circle_points(r, bottom_angles)
    top = _circle_points(r, top_angles)
    h = cfg.home_height
    home_vec = top + np.array([0.0, 0.0, h]) - bottom
    home_dir = home_vec / np.linalg.norm(home_vec, axis=-1, keepdims=True)
    rot = np.array([[rotation_z_to(home_dir[j, i]) for i in range(LEGS_PER_PLATFORM)] for j in range(n)])
    return LegGeometry(bottom, top, home_dir, rot)


def home_plates(cfg: AssemblerConfig, base: pin.SE3 | None = None) -> list[pin.SE3]:
    """World poses of plates 0..n in the home pose (every leg at mid-stroke, plates parallel).

    Args:
        base: pose of plate 0 in the world (default identity).
    """
    base = pin.SE3.Identity() if base is None else base
    step = pin.SE3(np.eye(3), np.array([0.0, 0.0, cfg.home_height]))
    plates = [base.copy()]
    for _ in range(cfg.platforms):
        plates.append(plates[-1] * step)
    return plates


@functools.lru_cache(maxsize=64)
def reach_bound(cfg: AssemblerConfig) -> float:
    """An upper bound on the distance from plate 0's origin to plate n's [m].

    Plate j+1's origin is ``p_j + b_i + L_i u_i - R_{j+1} t_i`` for any of its legs, so one
    platform spans at most ``|b_i| + max_length + |t_i|``; a goal farther away is unreachable.
    Cached per configuration (immutable): every helper-arm solve asks for it.
    """
    geo = leg_geometry(cfg)
    span = np.linalg.norm(geo.bottom_in_plate, axis=-1) + np.linalg.norm(geo.top_in_plate, axis=-1)
    return float(np.sum(span.max(axis=1) + cfg.leg.max_length))
