"""Jacobians with respect to the leg lengths: of one platform's top plate, and of the EE.

Twists ordered ``[v, ω]`` as in Pinocchio; lengths [m], angles [rad].
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..exceptions import SingularConfigurationError
from ..model.assembler import AssemblerModel
from .legs import relative_leg_directions
from .poses import PlateArrays, checked_platform_index, plate_arrays

#: Largest condition number of a platform's inverse Jacobian that is inverted (beyond it: no inverse).
CONDITION_LIMIT = 1e12

__all__ = ["ee_jacobian_wrt_lengths", "sp_inverse_jacobian"]


def sp_inverse_jacobian(am: AssemblerModel, j: int, top_in_bottom: pin.SE3) -> np.ndarray:
    """dL/dξ of platform j (6×6): leg-length rates for a local twist ξ = [v, ω] of the top
    plate (pose perturbed as ``top_in_bottom * exp6(ξ)``), bottom plate fixed [m/m, m/rad]."""
    j = checked_platform_index(am, j)
    geo = am.geometry
    R, p = top_in_bottom.rotation, top_in_bottom.translation
    _, _, _, u_top = relative_leg_directions(geo.bottom_in_plate[j], geo.top_in_plate[j], R, p)
    return np.hstack([u_top, np.cross(geo.top_in_plate[j], u_top)])


def ee_jacobian_wrt_lengths(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> np.ndarray:
    """Jacobian of the end-effector twist with respect to the 6n leg lengths.

    Returns:
        (6, 6n) matrix mapping leg-length rates (flattened ``[j, i]``) [m/s] to the EE
        plate's twist ``[v, ω]`` expressed in world-aligned axes at the EE plate origin
        (Pinocchio's LOCAL_WORLD_ALIGNED) [m/s, rad/s].
    """
    pa = plate_arrays(am, plates)
    n = am.n
    ee = pa.se3(n)
    jac = np.zeros((6, 6 * n))
    rot6 = np.zeros((6, 6))
    rot6[:3, :3] = rot6[3:, 3:] = ee.rotation
    for j in range(n):
        rel = pa.se3(j).actInv(pa.se3(j + 1))
        inverse = sp_inverse_jacobian(am, j, rel)
        condition = np.linalg.cond(inverse) if np.isfinite(inverse).all() else np.inf
        if not condition <= CONDITION_LIMIT:
            raise SingularConfigurationError(
                f"platform {j} is singular (coinciding joints or parallel leg lines, condition number "
                f"{condition:.3g}): the EE Jacobian w.r.t. the leg lengths does not exist there",
                float(condition),
                j,
            )
        local_twist_per_length = np.linalg.inv(inverse)
        plate_to_ee = pa.se3(j + 1).actInv(ee)
        jac[:, 6 * j : 6 * j + 6] = rot6 @ plate_to_ee.inverse().action @ local_twist_per_length
    return jac
