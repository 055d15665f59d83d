"""THE leg measures of the stack: joint centres, lengths, directions, deflections, rise.

Every leg quantity that follows from plate poses is computed here (the paper's IK, eq. 3),
batched over any leading axes: the kinematics, the constraints, the helper arm's limits
and the optimizer's derivatives use these functions. Arrays are indexed
``[..., platform j, leg i]``; lengths in metres (pin-to-pin: universal-joint centre to
ball-joint centre), directions are unit vectors bottom → top.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..exceptions import PoseError
from ..model.assembler import AssemblerModel
from ..model.geometry import LegGeometry
from .legs_kernel import compiled_leg_arrays
from .poses import PlateArrays, plate_arrays

__all__ = [
    "LegState",
    "deflection_cosines",
    "directions_in_plates",
    "leg_lengths",
    "leg_points",
    "leg_rise",
    "leg_state",
    "leg_vectors",
    "reference_leg_state",
    "relative_leg_directions",
    "relative_leg_measures",
]


@dataclass(frozen=True)
class LegState:
    """Everything per leg that follows from the plate poses (the paper's IK, eq. 3).

    Arrays are indexed ``[platform j, leg i]``.

    Attributes:
        bottom_points, top_points: (n, 6, 3) joint centres in the world [m].
        lengths: (n, 6) pin-to-pin lengths [m].
        directions: (n, 6, 3) unit vectors bottom → top, world frame.
        dir_in_bottom, dir_in_top: (n, 6, 3) the same direction in the bottom / top
            plate's frame.
        deflection: (n, 6, 2) angle from the home direction at the bottom (universal)
            and top (ball) joint, each in its own plate's frame [rad].
        rise: (n, 6) height of the top joint above the bottom joint in the bottom
            plate's frame [m] (continuous translation needs > 0).
    """

    bottom_points: np.ndarray
    top_points: np.ndarray
    lengths: np.ndarray
    directions: np.ndarray
    dir_in_bottom: np.ndarray
    dir_in_top: np.ndarray
    deflection: np.ndarray
    rise: np.ndarray


def leg_points(geo: LegGeometry, R: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bottom (universal) and top (ball) joint centres of every leg in the frame the plate
    poses are given in.

    Args:
        geo: the stack's leg geometry (anchors in the plate frames).
        R: (..., n+1, 3, 3) plate rotations; p: (..., n+1, 3) plate origins [m].

    Returns:
        bottom, top: (..., n, 6, 3) [m].
    """
    bottom = np.matmul(geo.bottom_in_plate, np.swapaxes(R[..., :-1, :, :], -1, -2)) + p[..., :-1, None, :]
    top = np.matmul(geo.top_in_plate, np.swapaxes(R[..., 1:, :, :], -1, -2)) + p[..., 1:, None, :]
    return bottom, top


def leg_lengths(vectors: np.ndarray) -> np.ndarray:
    """Pin-to-pin lengths (...) of bottom → top leg vectors (..., 3) [m]."""
    return np.sqrt(np.einsum("...k,...k->...", vectors, vectors))


def directions_in_plates(
    directions: np.ndarray, R_bottom: np.ndarray, R_top: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Unit leg directions (..., n, 6, 3) expressed in the bottom and in the top plate's frame.

    Args:
        directions: in the frame of the rotations (world, or the bottom plate's for relative poses).
        R_bottom, R_top: (..., n, 3, 3) rotations of each platform's bottom and top plate.

    Returns:
        (Rᵀ_bottom u, Rᵀ_top u), each (..., n, 6, 3).
    """
    return np.matmul(directions, R_bottom), np.matmul(directions, R_top)


def deflection_cosines(in_bottom: np.ndarray, in_top: np.ndarray, home: np.ndarray) -> np.ndarray:
    """Cosines (..., n, 6, 2) of each leg's deflection from its home direction ``home``
    (n, 6, 3) at the bottom (universal) and top (ball) joint, each in its own plate's frame."""
    return np.stack([np.einsum("...k,...k->...", in_bottom, home), np.einsum("...k,...k->...", in_top, home)], axis=-1)


def leg_rise(in_bottom: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Height (..., n, 6) of each top joint above its bottom joint in the bottom plate's
    frame [m] (continuous translation needs > 0), from the directions in the bottom frame."""
    return in_bottom[..., 2] * lengths


def relative_leg_measures(
    geo: LegGeometry, rotations: np.ndarray, translations: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lengths, deflection cosines and rise of every leg, from relative plate poses.

    Args:
        geo: the stack's leg geometry (anchors in the plate frames, home directions).
        rotations: (..., n or 1, 3, 3) top plate in the bottom plate's frame (one per
            platform, or one for all); translations: (..., n or 1, 3) [m].

    Returns:
        lengths (..., n, 6) [m], cos_deflection (..., n, 6, 2) (bottom, top joint),
        rise (..., n, 6): the top joint's height above the bottom joint, bottom frame [m].
    """
    _, lengths, u, in_top = relative_leg_directions(geo.bottom_in_plate, geo.top_in_plate, rotations, translations)
    return lengths, deflection_cosines(u, in_top, geo.home_direction), leg_rise(u, lengths)


def relative_leg_directions(
    bottom: np.ndarray, top: np.ndarray, rotations: np.ndarray, translations: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Leg vectors, lengths and directions of platforms given by the relative pose of their
    top plate, all in the bottom plate's frame (the bottom plate's frame is the poses' frame).

    Args:
        bottom: (..., 6, 3) bottom joint centres in the bottom plate [m]; top: (..., 6, 3) top
            joint centres in the top plate [m].
        rotations: (..., 3, 3) top plate in the bottom plate's frame; translations: (..., 3) [m].

    Returns:
        vec (..., 6, 3) [m], lengths (..., 6) [m], u (..., 6, 3) unit directions (bottom
        frame), u_top (..., 6, 3) the same directions in the top plate's frame.
    """
    vec = np.matmul(top, np.swapaxes(rotations, -1, -2)) + translations[..., None, :] - bottom
    lengths = leg_lengths(vec)
    u = vec / lengths[..., None]
    return vec, lengths, u, np.matmul(u, rotations)


def leg_vectors(am: AssemblerModel, pa: PlateArrays) -> tuple[np.ndarray, ...]:
    """Bottom and top joint centres (n, 6, 3), bottom→top vectors (n, 6, 3) and lengths (n, 6),
    world frame [m].

    Raises:
        PoseError: two joint centres of a leg coincide.
    """
    bottom, top = leg_points(am.geometry, pa.R, pa.p)
    vec = top - bottom
    lengths = leg_lengths(vec)
    if lengths.min() < 1e-9:
        raise PoseError("plate poses put a leg's two joint centres on top of each other")
    return bottom, top, vec, lengths


def leg_state(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> LegState:
    """Leg lengths, directions, deflections and rise of every leg for given plate poses, in
    one compiled call (:mod:`~assembler_pin.kinematics.legs_kernel`).

    Raises:
        PoseError: malformed poses, or two joint centres of a leg coincide.
    """
    return LegState(*compiled_leg_arrays(am, plate_arrays(am, plates)))


def reference_leg_state(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> LegState:
    """:func:`leg_state` composed of this module's numpy functions: the tests' reference."""
    pa = plate_arrays(am, plates)
    bottom, top, vec, lengths = leg_vectors(am, pa)
    directions = vec / lengths[..., None]
    in_bottom, in_top = directions_in_plates(directions, pa.R[:-1], pa.R[1:])
    cos = deflection_cosines(in_bottom, in_top, am.geometry.home_direction)
    deflection = np.arccos(np.clip(cos, -1.0, 1.0))
    rise = leg_rise(in_bottom, lengths)
    return LegState(bottom, top, lengths, directions, in_bottom, in_top, deflection, rise)
