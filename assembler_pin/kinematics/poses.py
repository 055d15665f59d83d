"""Plate poses: :class:`PlateArrays`, the one rotation check, SE(3) and TAA conversions.

Plate poses are given as ``n + 1`` world transforms (plate 0 first): ``pin.SE3`` objects,
4×4 arrays, or one (n+1, 4, 4) array. Internally they are held as :class:`PlateArrays`
(rotations ``R`` (n+1, 3, 3) and translations ``p`` (n+1, 3) [m]) so that everything per
leg is vectorized with numpy. Angles in radians.
"""

from __future__ import annotations

import operator
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import SupportsIndex, overload

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..common.validation import as_float_array
from ..config.bounds import BOUNDS
from ..exceptions import ArgumentError, PoseError
from ..model.assembler import AssemblerModel, checked_model

__all__ = [
    "MAX_ROTATION_VECTOR",
    "ORTHONORMAL_TOL",
    "QUATERNION_NORM_TOL",
    "PlateArrays",
    "checked_goal",
    "checked_rotations",
    "even_screw_pose",
    "nearest_rotations",
    "plate_arrays",
    "se3_to_taa",
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


@dataclass(frozen=True)
class PlateArrays:
    """World poses of plates 0..n as arrays: ``R`` (n+1, 3, 3), ``p`` (n+1, 3) [m].

    A sequence of plates, as a list of ``pin.SE3`` (``am.home``) is: ``plates[k]`` is plate k's
    world pose as ``pin.SE3`` (``plates[-1]`` the EE plate), ``plates[i:j]`` the plates i..j-1
    as :class:`PlateArrays`, and iterating gives the poses in order, plate 0 first.
    """

    R: np.ndarray
    p: np.ndarray

    def __len__(self) -> int:
        return self.R.shape[0]

    @overload
    def __getitem__(self, k: SupportsIndex) -> pin.SE3: ...
    @overload
    def __getitem__(self, k: slice) -> PlateArrays: ...
    def __getitem__(self, k: SupportsIndex | slice) -> pin.SE3 | PlateArrays:
        """Plate ``k``'s world pose (negative counts from the EE plate), or a slice of plates."""
        if isinstance(k, slice):
            return PlateArrays(self.R[k].copy(), self.p[k].copy())
        i = operator.index(k)  # TypeError for a float or a string, as a list raises
        if not -len(self) <= i < len(self):
            raise IndexError(f"plate index {i} out of range for {len(self)} plates (0..{len(self) - 1})")
        return self.se3(i)

    def __iter__(self) -> Iterator[pin.SE3]:
        return (self.se3(k) for k in range(len(self)))

    def __repr__(self) -> str:
        return f"PlateArrays({len(self)} plates, EE at {np.round(self.p[-1], 4).tolist()} m)"

    @classmethod
    def from_se3(cls, poses: Sequence[pin.SE3]) -> PlateArrays:
        """From a list of world poses (trusted: no validation, see :func:`plate_arrays`)."""
        return cls(np.array([m.rotation for m in poses]), np.array([m.translation for m in poses]))

    def se3(self, k: int) -> pin.SE3:
        """Pose of plate k in the world as ``pin.SE3`` (``plates[k]`` is the same)."""
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
        PoseError: not 4×4, not finite, bottom row not [0 0 0 1], or not a rotation.
    """
    if not isinstance(pose, pin.SE3) and _six_numbers(pose):
        raise PoseError(
            f"{what}: six numbers are not a pose here; for x y z [m] and a rotation vector [rad] use "
            "ap.kinematics.taa_to_se3([x, y, z, rx, ry, rz]) (degrees=True for degrees)"
        )
    matrix = pose.homogeneous if isinstance(pose, pin.SE3) else as_float_array(pose, f"{what} (a 4x4 matrix)", (4, 4))
    if not np.all(np.isfinite(matrix)):
        raise PoseError(f"{what} contains NaN or infinite values")
    check_translations(matrix[:3, 3], what)
    if not np.abs(matrix[3] - [0.0, 0.0, 0.0, 1.0]).max() <= 1e-12:
        raise PoseError(f"{what}: the bottom row must be [0, 0, 0, 1], got {matrix[3].tolist()}")
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


def _six_numbers(value: object) -> bool:
    """``value`` reads as six numbers (an x y z rx ry rz vector given where a pose belongs)."""
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 6:
        return False
    try:
        return np.asarray(value, dtype=float).shape == (6,)
    except (TypeError, ValueError):
        return False


def nearest_rotations(R: np.ndarray) -> np.ndarray:
    """(m, 3, 3) matrices → the nearest rotations (Frobenius norm), by SVD with det +1."""
    u, _, vt = np.linalg.svd(R)
    d = np.sign(np.linalg.det(np.matmul(u, vt)))
    u[:, :, 2] *= d[:, None]
    return np.matmul(u, vt)


def checked_platform_index(am: AssemblerModel, j: object) -> int:
    """``j`` when it is an integer platform index 0..n-1 (not a boolean or a float).

    Raises:
        PoseError: naming the index given and the allowed range.
    """
    import numbers

    if isinstance(j, bool) or not isinstance(j, numbers.Integral) or not 0 <= int(j) < am.n:
        shown = repr(j) if len(repr(j)) <= 30 else repr(j)[:27] + "..."
        raise PoseError(f"platform index must be an integer in 0..{am.n - 1}, got {shown}")
    return int(j)


def check_translations(p: np.ndarray, what: str) -> None:
    """Refuse positions farther than the ``pose.translation`` bound from the origin (every
    coordinate; the statics lose their digits far away, and path lengths overflow).

    Args:
        p: positions (..., 3) [m], already finite.

    Raises:
        PoseError: naming the first one out of range and the bound.
    """
    high = BOUNDS["pose.translation"].high
    far = np.abs(p).reshape(-1, 3).max(axis=1) > high if p.size else np.zeros(0, bool)
    if far.any():
        k = int(np.argmax(far))
        coord = float(np.abs(p.reshape(-1, 3)[k]).max())
        where = f" {k}" if p.ndim > 1 else ""
        raise PoseError(
            f"{what}{where}: a coordinate of {coord:.3g} m is out of range "
            f"(every coordinate within ±{high:g} m, the pose.translation limit)"
        )


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
    check_translations(arr[:3], what)
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


def plate_arrays(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray | object) -> PlateArrays:
    """Validate ``n + 1`` plate poses (plate 0 first) and return them as arrays.

    ``plates`` may also be a result that carries them in its ``plates`` attribute (a
    :class:`~assembler_pin.state.StackState`, e.g. ``result.optimized``, or a successful
    stack FK result).

    Raises:
        ArgumentError: ``am`` is not an :class:`AssemblerModel` (e.g. the arguments swapped).
        PoseError: wrong count of plates or a malformed pose.
    """
    if isinstance(am, (list, tuple, np.ndarray, PlateArrays)) or hasattr(am, "plates"):
        checked_model(am)  # plates where the model belongs: the arguments swapped
    plates = _carried_plates(plates)
    if isinstance(plates, PlateArrays):
        if len(plates.p) != am.n + 1:
            raise PoseError(f"expected {am.n + 1} plate poses (plates 0..{am.n}), got {len(plates.p)}")
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


def _carried_plates(plates: object) -> object:
    """The :class:`PlateArrays` an object carries as ``plates`` (a state, an FK result),
    else ``plates`` itself.

    Raises:
        ArgumentError: ``plates`` is the model (the arguments swapped).
        PoseError: a result that carries plates but says it failed (``success`` false).
    """
    if isinstance(plates, AssemblerModel):
        raise ArgumentError(
            "plates must be the n+1 plate poses, got the AssemblerModel: the model comes first (am, plates)"
        )
    carried = getattr(plates, "plates", None)
    if not isinstance(carried, PlateArrays) or isinstance(plates, (list, tuple, np.ndarray)):
        return plates
    if getattr(plates, "success", True) is False:
        why = getattr(plates, "message", "")
        raise PoseError(f"{type(plates).__name__} did not succeed, its plates are no pose: {why}")
    return carried


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
    bottom row ``[0, 0, 0, 1]`` (to 1e-12), rotation orthonormal and of det +1 to
    :data:`ORTHONORMAL_TOL` (then projected onto SO(3) where not exact to 1e-14).

    Raises:
        PoseError: naming the first pose that fails.
    """
    bad = ~np.isfinite(matrices).all(axis=(1, 2))
    if bad.any():
        raise PoseError(f"{what} {int(np.argmax(bad))} contains NaN or infinite values")
    check_translations(matrices[:, :3, 3], what)
    last = np.abs(matrices[:, 3] - np.array([0.0, 0.0, 0.0, 1.0])).max(axis=1) > 1e-12
    if last.any():
        k = int(np.argmax(last))
        raise PoseError(f"{what} {k}: the bottom row must be [0, 0, 0, 1], got {matrices[k, 3].tolist()}")
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


def even_screw_pose(am: AssemblerModel, goal: pin.SE3) -> list[pin.SE3]:
    """The even screw pose: plate k at ``base·exp6(k/n · log6(base⁻¹·goal))`` (every platform
    the same relative transform), plate n at the goal; world poses. The one definition (the
    helper arm's repair start and the solver's ``screw`` start)."""
    base, n = am.home[0], am.n
    screw = pin.log6(base.actInv(goal))
    return [base * pin.exp6(screw * (k / n)) for k in range(n)] + [goal.copy()]
