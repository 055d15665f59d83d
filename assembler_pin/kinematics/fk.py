"""Forward kinematics: leg lengths → plate poses, of one Stewart platform and of the stack.

Lengths in metres (pin-to-pin); poses ``pin.SE3``; twists ordered ``[v, ω]`` as in Pinocchio.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..common.validation import as_float_array
from ..config.bounds import check_bound
from ..exceptions import ConvergenceError, PoseError
from ..model.assembler import AssemblerModel
from ..model.geometry import LEGS_PER_PLATFORM
from .poses import PlateArrays, checked_platform_index, plate_arrays, to_se3

__all__ = ["FKResult", "StackFKResult", "sp_forward_kinematics", "stack_forward_kinematics"]

_ONES3 = np.ones(3)


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
    j = checked_platform_index(am, j)
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
