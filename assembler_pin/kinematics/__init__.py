"""Kinematics of the stack: plate poses ↔ configuration, leg lengths (IK), FK, Jacobian.

Plate poses are given as ``n + 1`` world transforms (plate 0 first): ``pin.SE3``
objects, 4×4 arrays, or one (n+1, 4, 4) array. Internally they are held as
:class:`PlateArrays` (rotations ``R`` (n+1, 3, 3) and translations ``p`` (n+1, 3)) so
that everything per leg is vectorized with numpy.

Conventions: lengths in metres are pin-to-pin (universal-joint centre to ball-joint
centre); angles in radians; twists ordered ``[v, ω]`` as in Pinocchio.

Modules: :mod:`.poses` (PlateArrays, the rotation check, SE(3) ↔ TAA), :mod:`.legs` (the
leg measures, batched), :mod:`.configuration` (plates ↔ ``q``), :mod:`.fk` (forward
kinematics), :mod:`.jacobian` (Jacobians w.r.t. the leg lengths), :mod:`.deviation`
(the plate-deviation angle). Every name is importable from this package.
"""

from __future__ import annotations

from .configuration import (
    plates_from_q,
    platform_configurations,
    q_from_arrays,
    q_from_plates,
    rotations_to_quaternions,
    universal_joint_angles,
)
from .deviation import PlateDeviation, plate_deviation
from .fk import FKResult, StackFKResult, sp_forward_kinematics, stack_forward_kinematics
from .jacobian import ee_jacobian_wrt_lengths, sp_inverse_jacobian
from .legs import (
    LegState,
    deflection_cosines,
    directions_in_plates,
    leg_lengths,
    leg_points,
    leg_rise,
    leg_state,
    leg_vectors,
    relative_leg_directions,
    relative_leg_measures,
)
from .poses import (
    MAX_ROTATION_VECTOR,
    ORTHONORMAL_TOL,
    QUATERNION_NORM_TOL,
    PlateArrays,
    checked_goal,
    checked_rotations,
    even_screw_pose,
    nearest_rotations,
    plate_arrays,
    se3_to_taa,
    taa_to_se3,
    to_se3,
)

__all__ = [
    "MAX_ROTATION_VECTOR",
    "ORTHONORMAL_TOL",
    "QUATERNION_NORM_TOL",
    "FKResult",
    "LegState",
    "PlateArrays",
    "PlateDeviation",
    "StackFKResult",
    "checked_goal",
    "checked_rotations",
    "deflection_cosines",
    "directions_in_plates",
    "ee_jacobian_wrt_lengths",
    "even_screw_pose",
    "leg_lengths",
    "leg_points",
    "leg_rise",
    "leg_state",
    "leg_vectors",
    "nearest_rotations",
    "plate_arrays",
    "plate_deviation",
    "plates_from_q",
    "platform_configurations",
    "q_from_arrays",
    "q_from_plates",
    "relative_leg_directions",
    "relative_leg_measures",
    "rotations_to_quaternions",
    "se3_to_taa",
    "sp_forward_kinematics",
    "sp_inverse_jacobian",
    "stack_forward_kinematics",
    "taa_to_se3",
    "to_se3",
    "universal_joint_angles",
]
