"""The loaded pose of commanded leg lengths, and the lengths to command for a wanted pose.

With legs of axial stiffness ``k = leg.stiffness`` (:mod:`assembler_pin.compliance.elastic`), commanding
lengths ``L0`` does not put the plates at the rigid pose of ``L0`` (its forward kinematics):
gravity, the payload and any wrench on the EE stretch or compress every leg by ``F / k``.

* :func:`loaded_pose` — the nonlinear elastic equilibrium of commanded lengths: the plates, the
  EE's sag from the rigid pose, the leg forces ``F = k (L - L0)`` (tension positive).
* :func:`compensated_lengths` — the commanded lengths whose loaded equilibrium is a given pose:
  ``L0 = L - F / k`` with ``F`` the statics forces of that pose (a leg in compression is
  commanded longer than it ends up), confirmed by :func:`loaded_pose`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..common.labels import leg_label
from ..common.validation import as_float_array
from ..config.bounds import BOUNDS, check_bound
from ..exceptions import LoadError, OptionsError, SingularConfigurationError
from ..kinematics import PlateArrays, leg_vectors, plate_arrays, stack_forward_kinematics
from ..model.assembler import AssemblerModel
from ..statics.closed_form import CONDITION_LIMIT
from ..statics.derivatives import PoseDerivatives, pose_derivatives
from ..statics.engine import solve_statics
from .elastic import line_conditions, solve_equilibrium

__all__ = [
    "MAX_WRENCH",
    "CompensatedLengths",
    "LoadedPose",
    "SagGradient",
    "compensated_lengths",
    "loaded_pose",
    "sag_and_gradient",
]

#: Largest force [N] or moment [N·m] component of an EE wrench accepted (bounds key ``elastic.wrench``).
MAX_WRENCH = BOUNDS["elastic.wrench"].high


@dataclass(frozen=True)
class LoadedPose:
    """The elastic equilibrium of commanded leg lengths (:func:`loaded_pose`).

    Attributes:
        plates: the loaded plate poses (the last iterate when not ``success``).
        rigid: the rigid pose of the commanded lengths (stack forward kinematics).
        translation, rotation: (3,) the EE's sag, loaded against rigid [m, rad], world axes
            (rotation vector ``log3(R_loaded R_rigidᵀ)``).
        forces: (n, 6) leg forces ``k (L - L0)`` [N], tension positive.
        lengths: (n, 6) the loaded pin-to-pin lengths [m]; commanded: (n, 6) ``L0`` [m].
        iterations: Newton steps; residual: the last step's size [m] (distance left).
        success: converged to a stable equilibrium with no singular platform; message: why not.
    """

    plates: PlateArrays
    rigid: PlateArrays
    translation: np.ndarray
    rotation: np.ndarray
    forces: np.ndarray
    lengths: np.ndarray
    commanded: np.ndarray
    iterations: int
    residual: float
    success: bool
    message: str

    def __repr__(self) -> str:
        return (
            f"LoadedPose(success={self.success}, EE sag {1e3 * float(np.linalg.norm(self.translation)):.4f} mm "
            f"{np.rad2deg(float(np.linalg.norm(self.rotation))):.4f} deg, max|F| "
            f"{float(np.abs(self.forces).max()):.3f} N, {self.iterations} steps, message={self.message!r})"
        )

    @classmethod
    def failed(
        cls, plates: PlateArrays, rigid: PlateArrays, rest: np.ndarray, iterations: int, step: float, message: str
    ) -> LoadedPose:
        """No equilibrium: NaN sag and forces, ``success`` false and why."""
        nan3, nan = np.full(3, np.nan), np.full(rest.shape, np.nan)
        return cls(plates, rigid, nan3, nan3, nan, nan, rest, iterations, step, False, message)

    def to_dict(self) -> dict:
        """The loaded pose as JSON-ready lists (NaN for a failed one: write it with ``dumps``)."""
        return {
            "success": self.success,
            "message": self.message,
            "sag": {"translation": self.translation.tolist(), "rotation": self.rotation.tolist()},
            "leg_forces": self.forces.tolist(),
            "lengths": self.lengths.tolist(),
            "commanded": self.commanded.tolist(),
            "plates": self.plates.as_matrices().tolist(),
            "iterations": self.iterations,
            "residual_m": self.residual,
        }


def _checked_wrench(wrench: npt.ArrayLike | None) -> np.ndarray | None:
    if wrench is None:
        return None
    w = as_float_array(wrench, "EE wrench (six numbers fx fy fz mx my mz)", (6,), error=LoadError)
    if not np.all(np.isfinite(w)):
        raise LoadError(f"EE wrench contains NaN or infinite values: {w.tolist()}")
    check_bound("elastic.wrench", float(np.abs(w).max()), "the largest |component| of the EE wrench", LoadError)
    return w


def loaded_pose(
    am: AssemblerModel,
    lengths: npt.ArrayLike,
    wrench: npt.ArrayLike | None = None,
    base: pin.SE3 | npt.ArrayLike | None = None,
    tol: float = 1e-12,
    max_iterations: int = 30,
) -> LoadedPose:
    """The plates' elastic equilibrium under gravity, payload and ``wrench`` for commanded lengths.

    Newton's method on the plate poses (SE(3) increments, the exact tangent stiffness of
    :mod:`assembler_pin.compliance.elastic`) from the rigid pose of ``lengths``.

    Args:
        lengths: (n, 6) commanded (unloaded) pin-to-pin lengths [m].
        wrench: (6,) ``[f, m]`` applied to the EE plate [N, N·m], world axes, moment about
            the EE origin (default none).
        base: plate 0's world pose (default identity).
        tol: largest Newton step accepted as converged [m] (rotations times the node radius).

    Raises:
        PoseError: malformed lengths or base. LoadError: a non-finite or absurd wrench, ``tol``
            or ``max_iterations`` (bounds keys ``elastic.*``).
    """
    w = _checked_wrench(wrench)
    check_bound("elastic.tol", tol, "tol", LoadError)
    max_iterations = int(check_bound("elastic.max_iterations", max_iterations, "max_iterations", LoadError))
    rest = as_float_array(lengths, "leg lengths", (am.n, 6))
    fk = stack_forward_kinematics(am, rest, base=base)
    rigid = fk.plates
    k = float(am.config.leg.stiffness)
    if not fk.success:
        return LoadedPose.failed(
            rigid, rigid, rest, 0, math.inf, f"the commanded lengths have no rigid pose: {fk.message}"
        )
    eq = solve_equilibrium(am, rigid.R, rigid.p, rest, k, wrench=w, tol=tol, max_iterations=max_iterations)
    message = eq.message
    if message is None:
        cond = line_conditions(eq.terms.lines)[1]
        if not cond.max() <= CONDITION_LIMIT:
            message = f"the loaded pose puts platform {int(np.argmax(cond))} at a singular configuration"
        elif not eq.stable:
            message = "the loaded equilibrium is not stable (the stack buckles under this load)"
    plates = PlateArrays(eq.R, eq.p)
    if message is not None:
        return LoadedPose.failed(plates, rigid, rest, eq.iterations, eq.step, message)
    now = leg_vectors(am, plates)[3]  # at the final pose (the terms are one tiny step behind it)
    return LoadedPose(
        plates,
        rigid,
        eq.p[-1] - rigid.p[-1],
        pin.log3(eq.R[-1] @ rigid.R[-1].T),
        k * (now - rest),
        now,
        rest,
        eq.iterations,
        eq.step,
        True,
        "converged",
    )


@dataclass(frozen=True)
class CompensatedLengths:
    """Commanded lengths that put the loaded stack at a given pose (:func:`compensated_lengths`).

    Attributes:
        lengths: (n, 6) the lengths to command [m]; geometric: (n, 6) the pose's own lengths [m].
        forces: (n, 6) the statics forces of the pose [N, tension positive].
        check: the :class:`LoadedPose` of ``lengths`` (the confirmation).
        error: largest distance of a loaded plate from the wanted pose [m] (rotations
            times the node radius).
        within_stroke: every commanded length is within the legs' stroke.
        success: the check converged, ``error`` ≤ ``tolerance`` and ``within_stroke``;
            message: "ok" or why not.
    """

    lengths: np.ndarray
    geometric: np.ndarray
    forces: np.ndarray
    check: LoadedPose
    error: float
    within_stroke: bool
    success: bool
    message: str

    def __repr__(self) -> str:
        return (
            f"CompensatedLengths(success={self.success}, largest correction "
            f"{1e3 * float(np.abs(self.lengths - self.geometric).max()):.4f} mm, plates within "
            f"{self.error:.2g} m, message={self.message!r})"
        )


def _plate_distance(am: AssemblerModel, a: PlateArrays, b: PlateArrays) -> float:
    """Largest distance between the plates of two poses [m] (rotations times the node radius)."""
    M = np.matmul(a.R, np.swapaxes(b.R, 1, 2))
    vee = np.stack([M[:, 2, 1] - M[:, 1, 2], M[:, 0, 2] - M[:, 2, 0], M[:, 1, 0] - M[:, 0, 1]], axis=1)
    angle = np.arctan2(0.5 * np.linalg.norm(vee, axis=1), 0.5 * (np.trace(M, axis1=1, axis2=2) - 1.0))
    return max(float(np.abs(a.p - b.p).max()), am.config.plate.node_radius * float(angle.max()))


def stroke_problem(am: AssemblerModel, commanded: np.ndarray) -> str | None:
    """Why commanded leg lengths (n, 6) [m] cannot be commanded: the legs outside the stroke,
    the worst named; None when every one is within it."""
    leg = am.config.leg
    over = np.maximum(leg.min_length - commanded, commanded - leg.max_length)
    if over.max() <= 0:
        return None
    j, i = np.unravel_index(int(np.argmax(over)), over.shape)
    return (
        f"{int((over > 0).sum())} commanded length(s) outside the stroke [{leg.min_length:g}, {leg.max_length:g}] m, "
        f"the worst {leg_label(int(j), int(i))} at {commanded[j, i]:.6f} m"
    )


def compensated_lengths(
    am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray, tolerance: float = 1e-9
) -> CompensatedLengths:
    """The commanded lengths ``L - F / k`` whose loaded equilibrium is ``plates`` (to ``tolerance``
    [m]), ``F`` the statics forces (:func:`~assembler_pin.statics.engine.solve_statics`, tension
    positive) and ``L`` the pose's lengths; confirmed by :func:`loaded_pose`. A leg in
    compression is commanded longer than it ends up, one in tension shorter; ``success`` also
    needs every commanded length within the stroke (a servo cannot be commanded beyond it).

    Raises:
        PoseError: malformed plates. SingularConfigurationError: the pose is singular.
        LoadError: ``tolerance`` not in [1e-12, 1e-3] m.
    """
    check_bound("compensated.tolerance", tolerance, "tolerance", LoadError)
    pa = plate_arrays(am, plates)
    statics = solve_statics(am, pa, raise_on_singular=True)
    geometric = leg_vectors(am, pa)[3]
    cmd = geometric - statics.forces / float(am.config.leg.stiffness)
    check = loaded_pose(am, cmd, base=pa.se3(0), tol=min(1e-12, 1e-3 * tolerance))
    error = _plate_distance(am, check.plates, pa) if check.success else math.inf
    stroke = stroke_problem(am, cmd)
    if not check.success:
        message = check.message
    elif error > tolerance:
        message = f"the loaded pose of the compensated lengths is {error:.3g} m from the pose (> {tolerance:g} m)"
    else:
        message = stroke or "ok"
    return CompensatedLengths(cmd, geometric, statics.forces, check, error, stroke is None, message == "ok", message)


@dataclass(frozen=True)
class SagGradient:
    """The EE's linear sag of a pose and its gradient (:func:`sag_and_gradient`).

    Attributes:
        sag: ``|δp|`` [m], the length of the EE origin's first-order displacement under the
            pose's own loads (gravity and payload) with legs of stiffness ``k``.
        translation: (3,) ``δp`` [m], world axes.
        gradient: (6n,) ``∂ sag / ∂η`` [m per (m, rad)], per plate 1..n its six coordinates in
            ``chart`` order ``[v, ω]`` (see :func:`sag_and_gradient`).
        chart: ``"world"`` or ``"local"``.
    """

    sag: float
    translation: np.ndarray
    gradient: np.ndarray
    chart: str


def _point_rows(force: np.ndarray, point: np.ndarray) -> np.ndarray:
    """(..., 6) ``[f, x × f]``: the row ``f · (v + ω × x)`` of a point force f at x on a plate."""
    return np.concatenate([force, np.cross(point, force)], axis=-1)


def sag_and_gradient(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    chart: str = "world",
    derivatives: PoseDerivatives | None = None,
) -> SagGradient:
    """The EE's sag under gravity and payload, linear in the legs' compliance, and its gradient.

    Every leg stretches by ``F / k`` (``F`` the statics forces of the pose, tension positive,
    ``k = leg.stiffness``); the plates move by ``y = A⁻¹ F / k`` with ``A = ∂L/∂η`` the legs'
    length Jacobian, and the EE origin by ``δp = v_n + ω_n × p_n`` (the elastic compliance
    ``Σ k ∇L ∇Lᵀ`` under the pose's own loads; the load-dependent stiffness, about 1e-4 of
    it at 1e6 N/m, is left out). The measure is ``sag = |δp|`` [m].

    The gradient is exact (adjoint of ``A y = F / k``): ``chart="world"`` gives it per world
    twist ``η_k = (v, ω)`` of plate k (``T_k ← exp6(η_k) T_k``, the columns of
    :func:`~assembler_pin.statics.derivatives.pose_derivatives`, so ``gradient @ B`` is the optimizer's
    chart gradient for its ``B``); ``chart="local"`` per body twist ``ξ_k``
    (``T_k ← T_k exp6(ξ_k)``, the optimizer's chart at its reference). ``derivatives``: the
    pose's :func:`~assembler_pin.statics.derivatives.pose_derivatives` when the caller has them already
    (the optimizer's force rows), else computed here.

    Raises:
        PoseError: malformed plates. SingularConfigurationError: a singular platform.
        OptionsError: an unknown chart.
    """
    if chart not in ("world", "local"):
        raise OptionsError(f"chart must be 'world' or 'local', got {chart!r}")
    pa = plate_arrays(am, plates)
    n, k = am.n, float(am.config.leg.stiffness)
    legs = _leg_points(am, pa)
    cond = line_conditions(np.concatenate([legs[2], np.cross(legs[1] - pa.p[1:, None, :], legs[2])], axis=2))[1]
    if not cond.max() <= CONDITION_LIMIT:
        worst = int(np.argmax(cond))
        why = f"platform {worst} is at a singular configuration (condition number {cond[worst]:.3g}): no sag"
        raise SingularConfigurationError(why, float(cond[worst]), worst)
    d = pose_derivatives(am, pa) if derivatives is None else derivatives
    A = d.d_lengths.reshape(6 * n, 6 * n)
    y = np.linalg.solve(A, d.forces.ravel() / k).reshape(n, 6)
    p_ee = pa.p[n]
    dp = y[-1, :3] + np.cross(y[-1, 3:], p_ee)
    sag = float(np.linalg.norm(dp))
    e = dp / sag if sag > 0 else np.zeros(3)
    ds_dy = np.zeros(6 * n)
    ds_dy[-6:] = np.r_[e, np.cross(p_ee, e)]
    lam = np.linalg.solve(A.T, ds_dy).reshape(n, 6)  # the adjoint, one per leg
    gradient = lam.ravel() @ d.d_forces.reshape(6 * n, 6 * n) / k
    gradient -= _curvature_rows(pa, legs, y, lam).ravel()
    gradient[-6:] += _point_rows(np.cross(e, y[-1, 3:]), p_ee)  # δp's own p_n
    if chart == "local":
        action = np.array([pa.se3(j).action for j in range(1, n + 1)])
        gradient = np.einsum("ja,jab->jb", gradient.reshape(n, 6), action).ravel()
    return SagGradient(sag, dp, gradient, chart)


def _leg_points(am: AssemblerModel, pa: PlateArrays) -> tuple[np.ndarray, ...]:
    """(b, t, u, L): bottom and top joints (n, 6, 3) [m, world], unit directions, lengths (n, 6) [m]."""
    geo = am.geometry
    b = np.matmul(geo.bottom_in_plate, np.swapaxes(pa.R[:-1], 1, 2)) + pa.p[:-1, None, :]
    t = np.matmul(geo.top_in_plate, np.swapaxes(pa.R[1:], 1, 2)) + pa.p[1:, None, :]
    L = np.linalg.norm(t - b, axis=-1)
    return b, t, (t - b) / L[..., None], L


def _curvature_rows(pa: PlateArrays, legs: tuple[np.ndarray, ...], y: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """(n, 6) ``λᵀ ∂(A y)/∂η``: each leg's second derivative of its length along the plates'
    motion ``y`` (n, 6) and a world twist, weighted by ``λ`` (n, 6), as point forces at its joints
    (``legs``: :func:`_leg_points`)."""
    b, t, u, L = legs
    y0 = np.vstack([np.zeros((1, 6)), y])  # plate 0 stays
    move_b = y0[:-1, None, :3] + np.cross(y0[:-1, None, 3:], b)
    move_t = y0[1:, None, :3] + np.cross(y0[1:, None, 3:], t)
    dd = move_t - move_b
    g = lam[..., None] * (dd - (dd * u).sum(-1, keepdims=True) * u) / L[..., None]
    f_t = g + lam[..., None] * np.cross(u, y0[1:, None, 3:])
    f_b = -g - lam[..., None] * np.cross(u, y0[:-1, None, 3:])
    rows = _point_rows(f_t, t).sum(axis=1)
    rows[:-1] += _point_rows(f_b[1:], b[1:]).sum(axis=1)  # platform j's bottom is on plate j
    return rows
