"""Plate poses ↔ configuration ``q``: of the whole-stack model and of each platform's own model.

All in closed form (no Pinocchio ``Data``). The universal joint of each leg holds the two
angles (ux, uy) that point it at its top joint (:func:`universal_joint_angles`, the one
formula), its actuator the pin-to-pin length [m].
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..common.validation import as_float_array
from ..exceptions import PoseError
from ..model.assembler import AssemblerModel
from .legs import leg_vectors
from .poses import QUATERNION_NORM_TOL, PlateArrays, plate_arrays

__all__ = [
    "plates_from_q",
    "platform_configurations",
    "q_from_arrays",
    "q_from_plates",
    "rotations_to_quaternions",
    "universal_joint_angles",
]


def q_from_plates(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> np.ndarray:
    """The full configuration ``q`` that puts the plates at the given world poses.

    Closed form: the root free-flyer holds plate 0's pose, each plate free-flyer the pose
    relative to the plate below (composed after the joint's home placement), each leg's
    universal joint the two angles that point it at its top joint, and its actuator the
    pin-to-pin length.
    """
    pa = plate_arrays(am, plates)
    _, _, vec, lengths = leg_vectors(am, pa)
    return q_from_arrays(am, pa, vec, lengths)


def universal_joint_angles(
    vec: np.ndarray, R_bottom: np.ndarray, base_rotation: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The two angles (ux, uy) of each leg's universal joint that point the leg at its top joint.

    The joint turns about x first, then about y, from its base frame (whose z is the leg's
    rest axis): the leg direction in that frame ``d = R_baseᵀ R_bottomᵀ vec`` gives
    ``ux = atan2(-d_y, d_z)`` and ``uy = atan2(d_x, √(d_y² + d_z²))``.

    Args:
        vec: (n, 6, 3) bottom → top leg vectors, world frame [m].
        R_bottom: (n, 3, 3) rotation of each platform's bottom plate (its model's frame).
        base_rotation: (n, 6, 3, 3) or (6, 3, 3) each universal joint's base frame in its plate.

    Returns:
        ux, uy: (n, 6) [rad].
    """
    d = np.matmul(np.matmul(vec, R_bottom)[:, :, None, :], base_rotation)[:, :, 0, :]
    return np.arctan2(-d[..., 1], d[..., 2]), np.arctan2(d[..., 0], np.hypot(d[..., 1], d[..., 2]))


def q_from_arrays(am: AssemblerModel, pa: PlateArrays, vec: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """:func:`q_from_plates` for validated plates and their leg vectors (n, 6, 3) and lengths (n, 6) [m]."""
    n = am.n
    q = np.empty(am.nq)
    R, p = pa.R, pa.p
    Rb_T = R[:-1].transpose(0, 2, 1)
    # root free-flyer: plate 0's world pose
    q[0:3] = p[0]
    q[3:7] = pin.Quaternion(R[0]).coeffs()
    # then per platform (see AssemblerModel._check_order): 6 legs x (ux, uy, L), plate j+1 free-flyer
    body = q[7:].reshape(n, 25)
    legs = body[:, :18].reshape(n, 6, 3)
    # plate j+1 relative to plate j, after the joint's home placement (a pure translation)
    body[:, 18:21] = np.matmul(Rb_T, (p[1:] - p[:-1])[..., None])[..., 0] - am.plate_placement_p
    rel_R = np.matmul(Rb_T, R[1:])
    for j in range(n):
        body[j, 21:25] = pin.Quaternion(rel_R[j]).coeffs()
    legs[..., 0], legs[..., 1] = universal_joint_angles(vec, R[:-1], am.geometry.leg_base_rotation)
    legs[..., 2] = lengths
    return q


def plates_from_q(am: AssemblerModel, q: np.ndarray) -> PlateArrays:
    """World poses of the plates for a whole-stack configuration (the inverse of
    :func:`q_from_plates`): plate 0 from the root free-flyer, plate j+1 = plate j · its joint's
    home placement · its free-flyer, in closed form (no Pinocchio data of the whole stack)."""
    q = as_float_array(q, "q", (am.nq,))
    if not np.all(np.isfinite(q)):
        raise PoseError(f"q contains NaN or infinite values (at index {int(np.argmax(~np.isfinite(q)))})")
    starts = np.array([int(k) + 3 for k in am.plate_idx_q])  # each free-flyer's quaternion (x, y, z, w)
    norms = np.linalg.norm(q[starts[:, None] + np.arange(4)], axis=1)
    off = np.abs(norms - 1.0) > QUATERNION_NORM_TOL
    if off.any():
        k = int(np.argmax(off))
        raise PoseError(
            f"q: the quaternion of plate {k} (q[{starts[k]}:{starts[k] + 4}]) has norm {norms[k]:.6g}; "
            f"it must be a unit quaternion (to {QUATERNION_NORM_TOL:g})"
        )
    poses = [pin.XYZQUATToSE3(q[0:7])]
    for j in range(am.n):
        k = int(am.plate_idx_q[j + 1])
        poses.append(poses[-1] * am.plate_joint_placement[j + 1] * pin.XYZQUATToSE3(q[k : k + 7]))
    return PlateArrays.from_se3(poses)


def rotations_to_quaternions(R: np.ndarray) -> np.ndarray:
    """(m, 3, 3) rotation matrices → (m, 4) unit quaternions ``(x, y, z, w)`` (Pinocchio's
    order), vectorized (the largest of the four candidate denominators per matrix)."""
    if R.shape[0] <= 32:  # a few matrices: Pinocchio's own conversion is faster than the vectorized one
        return np.array([pin.Quaternion(r).coeffs() for r in R]).reshape(-1, 4)
    m00, m11, m22 = R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]
    trace = m00 + m11 + m22
    cand = np.stack([trace, m00, m11, m22], axis=1)
    k = np.argmax(cand, axis=1)
    out = np.empty((R.shape[0], 4))
    for case in range(4):
        sel = k == case
        if not sel.any():
            continue
        r = R[sel]
        if case == 0:
            s = 2.0 * np.sqrt(1.0 + trace[sel])
            out[sel] = np.stack(
                [(r[:, 2, 1] - r[:, 1, 2]) / s, (r[:, 0, 2] - r[:, 2, 0]) / s, (r[:, 1, 0] - r[:, 0, 1]) / s, 0.25 * s],
                axis=1,
            )
        else:
            a, b, c = case - 1, case % 3, (case + 1) % 3
            s = 2.0 * np.sqrt(1.0 + r[:, a, a] - r[:, b, b] - r[:, c, c])
            vec = np.empty((r.shape[0], 3))
            vec[:, a] = 0.25 * s
            vec[:, b] = (r[:, b, a] + r[:, a, b]) / s
            vec[:, c] = (r[:, c, a] + r[:, a, c]) / s
            out[sel] = np.concatenate([vec, ((r[:, c, b] - r[:, b, c]) / s)[:, None]], axis=1)
    return out


def platform_configurations(am: AssemblerModel, pa: PlateArrays, vec: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(n, nq) the configuration of each platform's own model
    (:class:`~assembler_pin.model.platform.PlatformModel`), its plate frames turned by
    ``Rz(60°·j)``: root free-flyer = plate j, the legs' (ux, uy, length), top free-flyer =
    plate j+1 relative to plate j after the joint's home placement."""
    pm = am.platform_models[0]
    n = am.n
    turns = am.stack_plan.turns
    Rb = np.matmul(pa.R[:-1], turns)  # turned bottom frames
    Rt = np.matmul(pa.R[1:], turns)
    q = np.empty((n, pm.model.nq))
    q[:, 0:3] = pa.p[:-1]
    rel_R = np.matmul(Rb.transpose(0, 2, 1), Rt)
    quats = rotations_to_quaternions(np.concatenate([Rb, rel_R]))
    q[:, 3:7] = quats[:n]
    q[:, pm.leg_idx_q[:, 0]], q[:, pm.leg_idx_q[:, 1]] = universal_joint_angles(vec, Rb, pm.leg_base_rotation)
    q[:, pm.leg_idx_q[:, 2]] = lengths
    k = pm.top_idx_q
    q[:, k : k + 3] = np.matmul(Rb.transpose(0, 2, 1), (pa.p[1:] - pa.p[:-1])[..., None])[..., 0] - pm.rest_offset
    q[:, k + 3 : k + 7] = quats[n:]
    return q
