"""The bodies of one pose of the stack: leg capsules and plate cylinders, world frame.

A leg is two capsules on its axis (the bottom joint centre ``b`` to the top joint centre
``t``, unit direction ``u``, length ``L``): the motor from ``b`` to ``b + motor_length u``
(radius ``leg.motor_radius``) and the shaft from there to ``t`` (radius ``leg.shaft_radius``).
A plate is a solid flat cylinder of radius ``plate.radius`` and thickness ``plate.thickness``
about its frame's z axis, centred on its frame's origin (the plane of its joint centres).

Points of a leg are written by their distance ``σ`` from ``b`` along the axis [m]; a segment
of a leg runs from ``σ = lo`` to ``σ = hi = hc + hb L`` (``hb`` in {0, 1}: an end fixed to the
motor or following the top joint), which is what the derivatives need.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..common.labels import leg_label
from ..config.schema import AssemblerConfig
from ..kinematics import PlateArrays, plate_arrays
from ..kinematics.legs import leg_points
from ..model.assembler import AssemblerModel
from ..model.geometry import LEGS_PER_PLATFORM

__all__ = ["MOTOR", "SHAFT", "StackBodies", "leg_segments", "stack_bodies", "stack_body_names"]

#: Part codes of a leg's two capsules.
MOTOR, SHAFT = 0, 1


@dataclass(frozen=True)
class StackBodies:
    """Leg axes and plate frames of one pose, world frame (legs flattened ``g = 6 j + i``).

    Attributes:
        cfg: the configuration (sizes, pair rule).
        bottom, top: (6n, 3) joint centres [m].
        axis: (6n, 3) unit directions bottom → top.
        length: (6n,) pin-to-pin lengths [m].
        R: (n+1, 3, 3) plate rotations; p: (n+1, 3) plate origins [m].
    """

    cfg: AssemblerConfig
    bottom: np.ndarray
    top: np.ndarray
    axis: np.ndarray
    length: np.ndarray
    R: np.ndarray
    p: np.ndarray


def stack_bodies(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> StackBodies:
    """The leg axes and plate frames of the given plate poses (world, plate 0 first)."""
    pa = plate_arrays(am, plates)
    bottom, top = leg_points(am.geometry, pa.R, pa.p)
    bottom, top = bottom.reshape(-1, 3), top.reshape(-1, 3)
    vec = top - bottom
    length = np.sqrt(np.einsum("ij,ij->i", vec, vec))
    axis = vec / np.maximum(length, 1e-300)[:, None]
    return StackBodies(am.config, bottom, top, axis, length, pa.R, pa.p)


def leg_segments(
    bodies: StackBodies,
    legs: np.ndarray,
    part: np.ndarray,
    trim_bottom: np.ndarray | bool = False,
    trim_top: np.ndarray | bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The capsules of the given leg parts, trimmed by ``leg.node_zone`` at the ends asked.

    Args:
        legs: (m,) leg indices; part: (m,) :data:`MOTOR` or :data:`SHAFT`.
        trim_bottom, trim_top: (m,) or scalar: drop ``node_zone`` at that end.

    Returns:
        start (m, 3) [m], vector (m, 3) [m] (zero for an empty segment), lo (m,) and hi (m,)
        [m] (σ of the ends), hb (m,) (1 where ``hi`` follows the top joint), radius (m,) [m].
        A segment emptied by the trim has ``hi < lo`` (callers skip it).
    """
    leg = bodies.cfg.leg
    L = bodies.length[legs]
    motor = part == MOTOR
    lo = np.maximum(np.where(motor, 0.0, leg.motor_length), np.where(trim_bottom, leg.node_zone, 0.0))
    hi1 = np.where(motor, leg.motor_length, L)
    hi2 = np.where(trim_top, L - leg.node_zone, np.inf)
    use2 = hi2 < hi1
    hi = np.where(use2, hi2, hi1)
    hb = np.where(use2, 1.0, np.where(motor, 0.0, 1.0))
    u = bodies.axis[legs]
    start = bodies.bottom[legs] + lo[:, None] * u
    vector = np.maximum(hi - lo, 0.0)[:, None] * u
    radius = np.where(motor, leg.motor_radius, leg.shaft_radius)
    return start, vector, lo, hi, hb, radius


@functools.lru_cache(maxsize=8)
def stack_body_names(n: int) -> tuple[str, ...]:
    """Names of the stack's bodies: legs ``SPj leg i`` (6n, in ``g`` order), then ``plate k``."""
    legs = [leg_label(j, i) for j in range(n) for i in range(LEGS_PER_PLATFORM)]
    return tuple(legs + [f"plate {k}" for k in range(n + 1)])
