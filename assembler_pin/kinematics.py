"""Kinematics of the stack: plate poses ↔ configuration, leg lengths (IK), FK, Jacobian.

Plate poses are given as ``n + 1`` world transforms (plate 0 first): ``pin.SE3``
objects, 4×4 arrays, or one (n+1, 4, 4) array. Internally they are held as
:class:`PlateArrays` (rotations ``R`` (n+1, 3, 3) and translations ``p`` (n+1, 3)) so
that everything per leg is vectorized with numpy.

Conventions: lengths in metres are pin-to-pin (universal-joint centre to ball-joint
centre); angles in radians; twists ordered ``[v, ω]`` as in Pinocchio.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from .bounds import check_bound
from .exceptions import ConvergenceError, PoseError
from .geometry import LEGS_PER_PLATFORM
from .linalg import cross
from .model import AssemblerModel
from .validation import as_float_array

__all__ = [
    "FKResult",
    "LegState",
    "PlateArrays",
    "PlateDeviation",
    "StackFKResult",
    "checked_goal",
    "checked_rotations",
    "ee_jacobian_wrt_lengths",
    "leg_state",
    "leg_vectors",
    "plate_arrays",
    "plate_deviation",
    "plates_from_q",
    "platform_configurations",
    "q_from_plates",
    "se3_to_taa",
    "sp_forward_kinematics",
    "sp_inverse_jacobian",
    "stack_forward_kinematics",
    "taa_to_se3",
    "to_se3",
]

#: How far from orthonormal (largest entry of ``RᵀR - I``) and from det +1 a given rotation
#: may be; beyond it a pose is refused, never projected onto SO(3).
ORTHONORMAL_TOL = 1e-9

#: How far from 1 the norm of a quaternion in ``q`` may be.
QUATERNION_NORM_TOL = 1e-9

#: Largest rotation-vector component accepted in a TAA pose [rad]: beyond it exp3 loses
#: every digit of the angle (a rotation never needs more than π).
MAX_ROTATION_VECTOR = 1e6
_ONES3 = np.ones(3)


@dataclass(frozen=True)
class PlateArrays:
    """World poses of plates 0..n as arrays: ``R`` (n+1, 3, 3), ``p`` (n+1, 3) [m]."""

    R: np.ndarray
    p: np.ndarray

    def __len__(self) -> int:
        return self.R.shape[0]

    def __repr__(self) -> str:
        return f"PlateArrays({len(self)} plates, EE at {np.round(self.p[-1], 4).tolist()} m)"

    @classmethod
    def from_se3(cls, poses: Sequence[pin.SE3]) -> PlateArrays:
        """From a list of world poses (trusted: no validation, see :func:`plate_arrays`)."""
        return cls(np.array([m.rotation for m in poses]), np.array([m.translation for m in poses]))

    def se3(self, k: int) -> pin.SE3:
        """Pose of plate k in the world as ``pin.SE3``."""
        return pin.SE3(self.R[k].copy(), self.p[k].copy())

    def as_se3(self) -> list[pin.SE3]:
        return [self.se3(k) for k in range(len(self))]

    def as_matrices(self) -> np.ndarray:
        """(n+1, 4, 4) homogeneous transforms."""
        out = np.zeros((len(self), 4, 4))
        out[:, :3, :3] = self.R
        out[:, :3, 3] = self.p
        out[:, 3, 3] = 1.0
        return out


def _rotation_errors(R: np.ndarray) -> tuple[np.ndarray, tuple[int, float, float] | None]:
    """For (m, 3, 3) matrices: |RᵀR − I| of each, and (index, |RᵀR − I|, det) of the first that
    is not a rotation to :data:`ORTHONORMAL_TOL` (orthonormal, det +1), None when all are."""
    err = np.abs(np.matmul(R.transpose(0, 2, 1), R) - np.eye(3)).max(axis=(1, 2))
    det = np.linalg.det(R)
    wrong = ~((err <= ORTHONORMAL_TOL) & (np.abs(det - 1.0) <= ORTHONORMAL_TOL))
    if not wrong.any():
        return err, None
    k = int(np.argmax(wrong))
    return err, (k, float(err[k]), float(det[k]))


def to_se3(pose: pin.SE3 | npt.ArrayLike, what: str = "pose") -> pin.SE3:
    """Validate one pose (``pin.SE3`` or 4×4 homogeneous matrix) and return it as SE3.

    A rotation within :data:`ORTHONORMAL_TOL` of orthonormal (and of det +1) is projected
    onto SO(3); one further off is refused.

    Raises:
        PoseError: not 4×4, not finite, last row not [0 0 0 1], or not a rotation.
    """
    matrix = pose.homogeneous if isinstance(pose, pin.SE3) else as_float_array(pose, f"{what} (a 4x4 matrix)", (4, 4))
    if not np.all(np.isfinite(matrix)):
        raise PoseError(f"{what} contains NaN or infinite values")
    if not np.abs(matrix[3] - [0.0, 0.0, 0.0, 1.0]).max() <= 1e-12:
        raise PoseError(f"{what}: the last row must be [0, 0, 0, 1], got {matrix[3].tolist()}")
    rot = matrix[:3, :3]
    errors, wrong = _rotation_errors(rot[None])
    if wrong is not None:
        _, err, det = wrong
        raise PoseError(
            f"{what}: the 3x3 block is not a rotation (|RᵀR - I| = {err:.2g}, det = "
            f"{det:.3g}); it must be orthonormal to {ORTHONORMAL_TOL} with det +1"
        )
    if errors[0] > 1e-14:
        rot = nearest_rotations(rot[None])[0]
    return pin.SE3(rot, matrix[:3, 3].copy())


def nearest_rotations(R: np.ndarray) -> np.ndarray:
    """(m, 3, 3) matrices → the nearest rotations (Frobenius norm), by SVD with det +1."""
    u, _, vt = np.linalg.svd(R)
    d = np.sign(np.linalg.det(np.matmul(u, vt)))
    u[:, :, 2] *= d[:, None]
    return np.matmul(u, vt)


def taa_to_se3(taa: npt.ArrayLike, degrees: bool = False, what: str = "goal") -> pin.SE3:
    """A pose from the paper's translation-axis-angle vector ``(x, y, z, rx, ry, rz)``.

    Args:
        taa: translation [m] then rotation vector θ·w [rad, or deg with ``degrees``].
        degrees: the rotation vector is in degrees.

    Raises:
        PoseError: not six finite numbers.
    """
    arr = as_float_array(taa, f"{what} (six numbers X Y Z RX RY RZ)", (6,))
    if not np.all(np.isfinite(arr)):
        raise PoseError(f"{what} contains NaN or infinite values: {arr.tolist()}")
    rotvec = np.deg2rad(arr[3:]) if degrees else arr[3:]
    angle = float(np.abs(rotvec).max())
    if angle > MAX_ROTATION_VECTOR:
        raise PoseError(
            f"{what}: rotation vector component {angle:.3g} rad is out of range "
            f"(at most {MAX_ROTATION_VECTOR:g} rad; a rotation needs no more than π)"
        )
    return pin.SE3(pin.exp3(rotvec), arr[:3].copy())


def se3_to_taa(pose: pin.SE3) -> np.ndarray:
    """The translation-axis-angle vector ``(p, θ·w)`` of a pose [m, rad]."""
    return np.concatenate([pose.translation, pin.log3(pose.rotation)])


def plate_arrays(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> PlateArrays:
    """Validate ``n + 1`` plate poses (plate 0 first) and return them as arrays.

    Raises:
        PoseError: wrong count of plates or a malformed pose.
    """
    if isinstance(plates, PlateArrays):
        if not plates.__dict__.get("_checked", False):
            _check_plate_arrays(plates, am.n + 1)
        return plates
    if isinstance(plates, (list, tuple)) and plates and all(isinstance(m, pin.SE3) for m in plates):
        matrices = np.array([m.homogeneous for m in plates])
    elif isinstance(plates, (list, tuple, np.ndarray)):
        matrices = as_float_array(plates, "plate poses (n+1 4x4 matrices)")
    else:
        raise PoseError("plate poses must be a list of n+1 SE3 poses or 4x4 matrices, plate 0 first")
    if matrices.ndim != 3 or matrices.shape[1:] != (4, 4):
        raise PoseError(f"plate poses must be n+1 4x4 matrices, plate 0 first; got shape {matrices.shape}")
    if matrices.shape[0] != am.n + 1:
        raise PoseError(f"expected {am.n + 1} plate poses (plates 0..{am.n}), got {matrices.shape[0]}")
    return PlateArrays(*checked_rotations(matrices))


def _check_plate_arrays(pa: PlateArrays, count: int) -> None:
    """A PlateArrays built by the caller: ``count`` finite poses whose ``R`` are rotations
    (orthonormal and det +1 to :data:`ORTHONORMAL_TOL`); marked checked once it passes.

    Raises:
        PoseError: naming the first plate that fails.
    """
    R, p = pa.R, pa.p
    if not (isinstance(R, np.ndarray) and isinstance(p, np.ndarray)) or R.dtype.kind != "f" or p.dtype.kind != "f":
        raise PoseError("PlateArrays.R and .p must be float arrays of shape (n+1, 3, 3) and (n+1, 3)")
    if R.shape != (count, 3, 3) or p.shape != (count, 3):
        raise PoseError(
            f"expected {count} plate poses (plates 0..{count - 1}): PlateArrays.R of shape ({count}, 3, 3) and "
            f".p of shape ({count}, 3), got {R.shape} and {p.shape}"
        )
    bad = ~(np.isfinite(R).all(axis=(1, 2)) & np.isfinite(p).all(axis=1))
    if bad.any():
        raise PoseError(f"PlateArrays: plate {int(np.argmax(bad))} contains NaN or infinite values")
    _, wrong = _rotation_errors(R)
    if wrong is not None:
        k, err, det = wrong
        raise PoseError(
            f"PlateArrays: R[{k}] is not a rotation (|RᵀR - I| = {err:.2g}, det = {det:.3g}); "
            f"it must be orthonormal with det +1 to {ORTHONORMAL_TOL:g}"
        )
    object.__setattr__(pa, "_checked", True)


def checked_goal(goal: object, what: str = "goal") -> pin.SE3:
    """An EE goal given as ``pin.SE3`` or a 4×4 matrix, checked by :func:`to_se3`.

    Raises:
        PoseError: naming ``what``: not a pose, not finite, or not a rotation.
    """
    if not isinstance(goal, (pin.SE3, np.ndarray, list, tuple)):
        raise PoseError(f"{what} must be a pin.SE3 or a 4x4 matrix, got {type(goal).__name__}")
    return to_se3(goal, what)


def checked_rotations(matrices: np.ndarray, what: str = "plate") -> tuple[np.ndarray, np.ndarray]:
    """(m, 4, 4) homogeneous matrices → (R (m, 3, 3), p (m, 3)), checked all at once: finite,
    last row ``[0, 0, 0, 1]`` (to 1e-12), rotation orthonormal and of det +1 to
    :data:`ORTHONORMAL_TOL` (then projected onto SO(3) where not exact to 1e-14).

    Raises:
        PoseError: naming the first pose that fails.
    """
    bad = ~np.isfinite(matrices).all(axis=(1, 2))
    if bad.any():
        raise PoseError(f"{what} {int(np.argmax(bad))} contains NaN or infinite values")
    last = np.abs(matrices[:, 3] - np.array([0.0, 0.0, 0.0, 1.0])).max(axis=1) > 1e-12
    if last.any():
        k = int(np.argmax(last))
        raise PoseError(f"{what} {k}: the last row must be [0, 0, 0, 1], got {matrices[k, 3].tolist()}")
    R = matrices[:, :3, :3].copy()
    errors, wrong = _rotation_errors(R)
    if wrong is not None:
        k, err, det = wrong
        raise PoseError(
            f"{what} {k}: the 3x3 block is not a rotation (|RᵀR - I| = {err:.2g}, det = {det:.3g}); "
            f"it must be orthonormal to {ORTHONORMAL_TOL} with det +1"
        )
    inexact = errors > 1e-14
    if inexact.any():
        R[inexact] = nearest_rotations(R[inexact])
    return R, matrices[:, :3, 3].copy()


# ---------------------------------------------------------------------- legs (IK)
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


def _angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle between unit vectors along the last axis [rad]."""
    return np.arccos(np.clip(np.einsum("...k,...k->...", a, b), -1.0, 1.0))


def leg_vectors(am: AssemblerModel, pa: PlateArrays) -> tuple[np.ndarray, ...]:
    """Bottom and top joint centres (n, 6, 3), bottom→top vectors (n, 6, 3) and lengths (n, 6),
    world frame [m].

    Raises:
        PoseError: two joint centres of a leg coincide.
    """
    geo = am.geometry
    bottom = np.matmul(geo.bottom_in_plate, pa.R[:-1].transpose(0, 2, 1)) + pa.p[:-1, None, :]
    top = np.matmul(geo.top_in_plate, pa.R[1:].transpose(0, 2, 1)) + pa.p[1:, None, :]
    vec = top - bottom
    lengths = np.sqrt((vec * vec).sum(axis=2))
    if lengths.min() < 1e-9:
        raise PoseError("plate poses put a leg's two joint centres on top of each other")
    return bottom, top, vec, lengths


def leg_state(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> LegState:
    """Leg lengths, directions, deflections and rise of every leg for given plate poses."""
    pa = plate_arrays(am, plates)
    bottom, top, vec, lengths = leg_vectors(am, pa)
    directions = vec / lengths[..., None]
    in_bottom = np.matmul(directions, pa.R[:-1])
    in_top = np.matmul(directions, pa.R[1:])
    home = am.geometry.home_direction
    deflection = np.stack([_angle_between(in_bottom, home), _angle_between(in_top, home)], axis=-1)
    rise = in_bottom[..., 2] * lengths
    return LegState(bottom, top, lengths, directions, in_bottom, in_top, deflection, rise)


# ---------------------------------------------------------------------- configuration
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


def q_from_arrays(am: AssemblerModel, pa: PlateArrays, vec: np.ndarray, lengths: np.ndarray) -> np.ndarray:
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
    # leg direction in each universal joint's base frame: d = R_baseᵀ R_bottomᵀ vec
    d = np.matmul(np.matmul(vec, R[:-1])[:, :, None, :], am.geometry.leg_base_rotation)[:, :, 0, :]
    legs[..., 0] = np.arctan2(-d[..., 1], d[..., 2])
    legs[..., 1] = np.arctan2(d[..., 0], np.hypot(d[..., 1], d[..., 2]))
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
    (:class:`~assembler_pin.platform_model.PlatformModel`), its plate frames turned by
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
    # leg direction in each universal joint's base frame
    d = np.matmul(np.matmul(vec, Rb)[:, :, None, :], pm.leg_base_rotation)[:, :, 0, :]
    q[:, pm.leg_idx_q[:, 0]] = np.arctan2(-d[..., 1], d[..., 2])
    q[:, pm.leg_idx_q[:, 1]] = np.arctan2(d[..., 0], np.hypot(d[..., 1], d[..., 2]))
    q[:, pm.leg_idx_q[:, 2]] = lengths
    k = pm.top_idx_q
    q[:, k : k + 3] = np.matmul(Rb.transpose(0, 2, 1), (pa.p[1:] - pa.p[:-1])[..., None])[..., 0] - pm.rest_offset
    q[:, k + 3 : k + 7] = quats[n:]
    return q


# ---------------------------------------------------------------------- forward kinematics
@dataclass
class FKResult:
    """Result of one Stewart platform's forward kinematics.

    The mechanism's own assembly mode — the one it is built in and moves in continuously
    from home while its legs stay in the stroke — is where all of these hold:

    * every top joint is above its bottom joint in the bottom plate's frame (rise > 0);
    * every bottom joint is below its top joint in the top plate's frame (each leg meets the
      top plate from below);
    * the top plate is turned less than 90° from the bottom plate (angle of the relative
      rotation, so both its tilt and its twist about the plate normal are under 90°);
    * each leg's direction is less than 90° from its home direction at both joints (a
      joint cannot fold its leg past the plate).

    Lengths of a platform's stroke have many other solutions (mirror images, plates turned
    upside down or twisted by more than 90°, legs crossing); FK reports success only in
    this mode. These rules are per platform: a stack whose platforms each stay in the mode
    may still, over many platforms, bend its EE plate below the base.

    Attributes:
        pose: top plate in the bottom plate's frame (the last iterate if not converged).
        success: True only when the length residual is below the tolerance and the
            solution is in the mechanism's assembly mode (above).
        iterations: Newton iterations used.
        residual: largest |L_i(pose) - L_i| [m].
        message: why it failed, or "converged".
    """

    pose: pin.SE3
    success: bool
    iterations: int
    residual: float
    message: str

    def __repr__(self) -> str:
        return (
            f"FKResult(success={self.success}, {self.iterations} iterations, residual {self.residual:.2e} m, "
            f"top at {np.round(self.pose.translation, 4).tolist()} m, message={self.message!r})"
        )

    def raise_if_failed(self) -> pin.SE3:
        """Return ``pose``, or raise :class:`ConvergenceError` when not successful."""
        if not self.success:
            raise ConvergenceError(self.message, self.iterations, self.residual)
        return self.pose


def sp_inverse_jacobian(am: AssemblerModel, j: int, top_in_bottom: pin.SE3) -> np.ndarray:
    """dL/dξ of platform j (6×6): leg-length rates for a local twist ξ = [v, ω] of the top
    plate (pose perturbed as ``top_in_bottom * exp6(ξ)``), bottom plate fixed [m/m, m/rad]."""
    geo = am.geometry
    R, p = top_in_bottom.rotation, top_in_bottom.translation
    vec = geo.top_in_plate[j] @ R.T + p - geo.bottom_in_plate[j]
    u_top = (vec / np.linalg.norm(vec, axis=1, keepdims=True)) @ R
    return np.hstack([u_top, np.cross(geo.top_in_plate[j], u_top)])


#: Longest leg length FK accepts [m]: far beyond any stroke, short of float overflow in the solve.
_MAX_LEG_LENGTH = 1e3


def _check_lengths(lengths: npt.ArrayLike, shape: tuple[int, ...]) -> np.ndarray:
    arr = as_float_array(lengths, "leg lengths", shape)
    if not all(0.0 < x <= _MAX_LEG_LENGTH for x in arr.ravel().tolist()):  # NaN fails the test
        raise PoseError(f"leg lengths must be > 0 and at most {_MAX_LEG_LENGTH:g} m (finite)")
    return arr


def sp_forward_kinematics(
    am: AssemblerModel,
    j: int,
    lengths: npt.ArrayLike,
    guess: pin.SE3 | None = None,
    tol: float = 1e-12,
    max_iterations: int = 30,
) -> FKResult:
    """Forward kinematics of platform j: six leg lengths → top plate pose in the bottom frame.

    Newton's method on the length residual with the platform's inverse Jacobian
    (:func:`sp_inverse_jacobian`), updating the pose on SE(3) with ``pin.exp6``.

    Args:
        j: platform index (0..n-1); the anchors differ per platform.
        lengths: (6,) pin-to-pin lengths [m].
        guess: initial top-in-bottom pose; default the home pose.
        tol: required largest length residual [m].
        max_iterations: Newton iterations before giving up.
    """
    target = _check_lengths(lengths, (LEGS_PER_PLATFORM,))
    if not 0 <= j < am.n:
        raise PoseError(f"platform index must be in 0..{am.n - 1}, got {j}")
    return _platform_fk(am, j, target, guess, tol, max_iterations)


def _platform_fk(
    am: AssemblerModel, j: int, target: np.ndarray, guess: pin.SE3 | None, tol: float, max_iterations: int
) -> FKResult:
    """Newton FK of platform j for validated target lengths (6,).

    Residual ``f_i = |x_i - b_i|² - L_i²`` (no square roots in the loop). The pose is
    perturbed on the left, ``T ← exp6(ξ) T`` with ξ a twist in the bottom plate's frame,
    so that the Jacobian rows are ``2 [v_i, b_i × v_i]`` with ``v_i = x_i - b_i`` and the
    bottom anchors ``b_i`` constant (one product with ``am.fk_jacobian_map[j]``). The
    reported residual is the exact length error.
    """
    top_h = am.top_anchor_homogeneous[j]  # (6, 4)
    bottom = am.geometry.bottom_in_plate[j]
    jacobian_map = am.fk_jacobian_map[j]
    if guess is None:
        # start from the home pose moved by one linearized step
        # (the inverse of the home Jacobian is a constant per platform)
        home_step = am.fk_home_inverse_jacobian[j].dot(target - am.config.leg.mid_length)
        pose = pin.exp6(home_step) * am.plate_joint_placement[j + 1]
    else:
        pose = _projected_guess(guess)
    from scipy.linalg.lapack import dgesv  # imported on first use: keeps `import assembler_pin` fast

    target_sq = target * target
    # |L - L*| <= |L² - L*²| / (L + L*) <= |f| / L*: converged when max |f| / L* <= tol
    inv_target = 1.0 / target
    iterations, failure = max_iterations, None
    for it in range(max_iterations + 1):
        vec = top_h.dot(pose.homogeneous[:3].T) - bottom  # x_i - b_i, (6, 3)
        length_sq = (vec * vec).dot(_ONES3)
        err = target_sq - length_sq
        # (a NaN here can only mean a non-finite pose, which fails the final residual test)
        if max(map(abs, (err * inv_target).tolist())) <= tol:
            iterations = it
            break
        if it == max_iterations:
            break
        # ξ solves 2 [v_i, b_i × v_i] ξ = f
        _, _, step, info = dgesv(jacobian_map.dot(vec.ravel()).reshape(6, 6), err)
        if info != 0 or not math.isfinite(step.dot(step)):  # a step beyond 1e154 counts as divergence
            failure = f"did not converge: SP{j} forward kinematics diverged (singular Jacobian)"
            break
        pose = pin.exp6(step) * pose
    # the loop always leaves right after evaluating vec at the current pose
    residual = float(np.abs(np.sqrt(length_sq) - target).max())
    message = failure
    if message is None and not residual <= tol:
        off = f"{1e3 * residual:.3g} mm" if math.isfinite(residual) else "not finite"
        message = (
            f"did not converge: SP{j} forward kinematics, length residual {off} after {max_iterations} "
            f"iterations (tolerance {tol:.1g} m)"
        )
    elif message is None:
        message = _foreign_mode(am, j, pose, vec)
    return FKResult(pose, message is None, iterations, residual, message or "converged")


def _projected_guess(guess: object) -> pin.SE3:
    """An FK starting pose on SE(3): the guess's rotation through its unit quaternion, so that
    chained FK calls (each starting from the last answer) never accumulate rounding.

    Raises:
        PoseError: the guess is not a finite ``pin.SE3``.
    """
    if not isinstance(guess, pin.SE3):
        what = type(guess).__name__
        raise PoseError(f"an FK guess must be a pin.SE3 (top plate in the bottom plate's frame), got {what}")
    if not np.all(np.isfinite(guess.homogeneous)):
        raise PoseError("the FK guess contains NaN or infinite values")
    quat = pin.Quaternion(guess.rotation)
    norm = quat.norm()
    if not norm > 0.0:
        raise PoseError("the FK guess's rotation block is not a rotation")
    quat.normalize()
    return pin.SE3(quat.matrix(), guess.translation.copy())


def _foreign_mode(am: AssemblerModel, j: int, pose: pin.SE3, vec: np.ndarray) -> str | None:
    """Why the converged pose of platform j is not the mechanism's assembly mode (the rules of
    :class:`FKResult`), None when it is. ``vec``: (6, 3) bottom→top leg vectors, bottom frame."""
    R = pose.rotation
    home = am.geometry.home_direction[j]
    in_top = vec.dot(R)  # leg vectors in the top plate's frame
    why = None
    if vec[:, 2].min() <= 0.0:
        why = "a top joint below its bottom joint"
    elif in_top[:, 2].min() <= 0.0:
        why = "a leg meeting the top plate from above"
    elif not np.trace(R) > 1.0:  # cos(angle) = (tr R - 1) / 2
        angle = math.degrees(math.acos(min(1.0, max(-1.0, 0.5 * (np.trace(R) - 1.0)))))
        why = f"the top plate turned {angle:.0f}° from the bottom plate (at most 90°)"
    elif min((vec * home).sum(axis=1).min(), (in_top * home).sum(axis=1).min()) <= 0.0:
        why = "a leg deflected 90° or more from its home direction"
    if why is None:
        return None
    return f"assembly mode: SP{j} forward kinematics converged to another assembly mode ({why})"


@dataclass
class StackFKResult:
    """Result of the whole stack's forward kinematics.

    Attributes:
        plates: world poses of plates 0..n (meaningful only where ``success``).
        success: every platform converged.
        platforms: the per-platform :class:`FKResult`.
        message: "converged" or the first failure.
    """

    plates: PlateArrays
    success: bool
    platforms: list[FKResult] = field(default_factory=list)
    message: str = "converged"

    @property
    def iterations(self) -> int:
        return sum(r.iterations for r in self.platforms)

    def __repr__(self) -> str:
        res = f"{self.residual:.2e} m" if self.platforms else "-"
        return (
            f"StackFKResult(success={self.success}, {len(self.plates) - 1} platforms, EE at "
            f"{np.round(self.plates.p[-1], 4).tolist()} m, residual {res}, message={self.message!r})"
        )

    @property
    def residual(self) -> float:
        return max(r.residual for r in self.platforms)

    def raise_if_failed(self) -> PlateArrays:
        """Return ``plates``, or raise :class:`ConvergenceError` when not successful."""
        if not self.success:
            raise ConvergenceError(self.message, self.iterations, self.residual)
        return self.plates


def stack_forward_kinematics(
    am: AssemblerModel,
    lengths: npt.ArrayLike,
    base: pin.SE3 | npt.ArrayLike | None = None,
    guess: PlateArrays | Sequence | None = None,
    tol: float = 1e-12,
    max_iterations: int = 30,
) -> StackFKResult:
    """Forward kinematics of the stack: (n, 6) leg lengths → world poses of all plates.

    Each platform is solved by :func:`sp_forward_kinematics` in its bottom plate's frame
    and chained serially from the base (the paper's eq. 4).

    Args:
        lengths: (n, 6) pin-to-pin lengths [m], platform 0 first.
        base: world pose of plate 0 (default identity).
        guess: plate poses to start each platform from (default: home).
    """
    check_bound("fk.tol", tol, "tol", PoseError)
    check_bound("fk.max_iterations", max_iterations, "max_iterations", PoseError)
    L = _check_lengths(lengths, (am.n, LEGS_PER_PLATFORM))
    base_pose = pin.SE3.Identity() if base is None else to_se3(base, "base pose")
    guesses: list[pin.SE3 | None] = [None] * am.n
    if guess is not None:
        ga = plate_arrays(am, guess)
        guesses = [ga.se3(j).actInv(ga.se3(j + 1)) for j in range(am.n)]
    # relative poses are independent given the lengths: solve each platform alone
    results = [_platform_fk(am, j, L[j], guesses[j], tol, max_iterations) for j in range(am.n)]
    plates = [base_pose]
    for res in results:
        plates.append(plates[-1] * res.pose)
    pa = PlateArrays.from_se3(plates)
    failed = [r for r in results if not r.success]
    return StackFKResult(pa, not failed, results, failed[0].message if failed else "converged")


# ---------------------------------------------------------------------- plate deviation
@dataclass(frozen=True)
class PlateDeviation:
    """The plate-deviation angle λ_k of paper eq. 9 and the vectors it is made of.

    Attributes:
        angles: (n,) λ_k, k = 1..n: angle between ``p_k - p_{k-1}`` and plate k's rest
            direction on plate k-1 [rad].
        step_dir: (n, 3) unit ``p_k - p_{k-1}``, world; step_length: (n,) its length [m].
        rest_dir: (n, 3) unit rest direction of plate k on plate k-1, world.
        sin, cos: (n,) sine and cosine of λ_k.
    """

    angles: np.ndarray
    step_dir: np.ndarray
    step_length: np.ndarray
    rest_dir: np.ndarray
    sin: np.ndarray
    cos: np.ndarray


def plate_deviation(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> PlateDeviation:
    """λ_k of every plate (paper eq. 9), the one definition used by the objective and its gradient."""
    pa = plate_arrays(am, plates)
    rest = am.plate_placement_p
    rest_dir = np.matmul(pa.R[:-1], (rest / np.linalg.norm(rest, axis=1, keepdims=True))[..., None])[..., 0]
    step = pa.p[1:] - pa.p[:-1]
    step_length = np.linalg.norm(step, axis=1)
    step_dir = step / step_length[:, None]
    sin = np.linalg.norm(cross(step_dir, rest_dir), axis=1)
    cos = np.einsum("jk,jk->j", step_dir, rest_dir)
    return PlateDeviation(np.arctan2(sin, cos), step_dir, step_length, rest_dir, sin, cos)


# ---------------------------------------------------------------------- Jacobian
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
        local_twist_per_length = np.linalg.inv(sp_inverse_jacobian(am, j, rel))
        plate_to_ee = pa.se3(j + 1).actInv(ee)
        jac[:, 6 * j : 6 * j + 6] = rot6 @ plate_to_ee.inverse().action @ local_twist_per_length
    return jac
