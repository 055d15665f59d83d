"""Exact statics of the stack under gravity and payload, from Pinocchio.

For plate poses given, the configuration ``q`` follows in closed form
(:func:`~assembler_pin.kinematics.q_from_plates`). Static equilibrium of the tree with
its loops closed reads

    g(q) = Sᵀ τ + J_cᵀ λ

with ``g`` Pinocchio's generalized gravity (every plate, motor, shaft and the payload),
``S`` the selection of the prismatic actuators, ``τ`` their generalized forces
(Pinocchio's sign: dV/dL, compression positive), ``J_c`` the Jacobian of the 3D ball
closures (shaft tip minus top-plate anchor, world axes) and ``λ`` the force the top plate
exerts on each shaft tip [N, world axes].

Only the rows of platform j's legs and of plate j+1's free-flyer involve platform j's
unknowns (6 τ + 18 λ), and those rows involve no other unknowns: a closure's two points
move together under any joint below plate j+1. The system is therefore block-diagonal,
one 24×24 block per platform, solved in one batched call. The paper's force (tension
positive) is ``-τ``. The root free-flyer's row of ``g`` is the wrench the base mount
supplies.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import cast

import numpy as np
import pinocchio as pin

from ..common.linalg import skew
from ..exceptions import ArgumentError, SingularConfigurationError
from ..kinematics import (
    LegState,
    PlateArrays,
    leg_vectors,
    plate_arrays,
    platform_configurations,
    q_from_arrays,
)
from ..model.assembler import AssemblerModel, checked_model
from ..model.platform import PlatformStatics, stack_gravity_terms
from .closed_form import is_singular, line_conditions
from .result import StaticsResult

__all__ = [
    "WHOLE_STACK_STATICS_MAX_PLATFORMS",
    "check_statics_arguments",
    "checked_data",
    "closure_jacobian_blocks",
    "gravity_terms",
    "solve_statics_pinocchio",
]


def leg_jacobians_t(columns: np.ndarray, top_points: np.ndarray) -> np.ndarray:
    """Transposed closure Jacobian blocks of the legs' own joints.

    ``columns`` (n, 6, 3, 6) are the world-frame Jacobian columns ``[v, ω]`` of each leg's
    (ux, uy, actuator) joints (:class:`~assembler_pin.model.platform.PlatformStatics`) at the
    pose whose world ball-joint centres are ``top_points`` (n, 6, 3). The closure of leg
    (j, i) is the shaft tip minus the top plate's anchor, in world axes; only leg (j, i)'s own
    joints and plate j+1's free-flyer move one of the two points without the other. A joint
    column moves the tip by ``v + ω × t``, i.e. the row ``vᵀ + ωᵀ skew(t)`` of the transpose.

    Returns:
        (n, 6, 3, 3): the leg's (ux, uy, actuator) rows × closure columns (world axes).
    """
    return columns[..., :3] + np.matmul(columns[..., 3:], skew(top_points))


def _plate_jacobians(top_columns: np.ndarray, top_points: np.ndarray) -> np.ndarray:
    """Closure Jacobian blocks of the top plates' free-flyers (see :func:`leg_jacobians_t`;
    the anchor moves by ``v + ω × t`` and enters the closure with a minus sign).

    Args:
        top_columns: (n, 6, 6) world-frame Jacobian rows × each top plate's free-flyer columns.

    Returns:
        (n, 6, 3, 6): closure rows × plate j+1's free-flyer columns.
    """
    return np.matmul(skew(top_points), top_columns[:, None, 3:]) - top_columns[:, None, :3]


def closure_jacobian_blocks(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> np.ndarray:
    """The closure Jacobian restricted to each platform's block (for inspection and tests).

    Returns:
        (n, 18, 24): rows (leg i, world axis) of platform j's closures; columns its 18 leg
        joints (ux, uy, actuator per leg) then the top plate's free-flyer (its own frame).
    """
    pa = plate_arrays(am, plates)
    _, top, vec, lengths = leg_vectors(am, pa)
    terms = gravity_terms(am, pa, vec, lengths)
    leg = leg_jacobians_t(terms.leg_columns, top).swapaxes(2, 3)
    plate = _plate_jacobians(terms.top_columns, top)
    n = am.n
    out = np.zeros((n, 6, 3, 24))
    for i in range(6):
        out[:, i, :, 3 * i : 3 * i + 3] = leg[:, i]
    out[:, :, :, 18:] = plate
    return out.reshape(n, 18, 24)


#: Up to this many platforms the whole-stack path (one Pinocchio call for all platforms on a
#: ``Data`` the caller owns, a few MB) is faster than one model per platform; above, the
#: per-platform path is the faster one (linear in n). Informative: the path is chosen by
#: passing ``data`` or not.
WHOLE_STACK_STATICS_MAX_PLATFORMS = 4


def checked_data(am: AssemblerModel, data: object) -> pin.Data:
    """``data`` when it is a Pinocchio ``Data`` of ``am.model`` (``am.create_data()`` or
    ``am.model.createData()``).

    Raises:
        ArgumentError: not a ``pin.Data``, or one of another model (its sizes differ).
    """
    if not isinstance(data, pin.Data):
        raise ArgumentError(
            f"data must be the pinocchio.Data of the whole-stack model (am.create_data()), got {type(data).__name__}"
        )
    if len(data.oMi) != am.model.njoints or data.g.shape != (am.model.nv,):
        raise ArgumentError(
            f"data belongs to another model ({len(data.oMi)} joints, nv = {data.g.shape[0]}); this stack's "
            f"model has {am.model.njoints} joints, nv = {am.model.nv}: create it with am.create_data()"
        )
    return data


def gravity_terms(
    am: AssemblerModel, pa: PlateArrays, vec: np.ndarray, lengths: np.ndarray, data: pin.Data | None = None
) -> PlatformStatics:
    """The Pinocchio terms of the statics: generalized gravity and joint Jacobians.

    Args:
        pa, vec, lengths: validated plate poses, their leg vectors (n, 6, 3) and lengths (n, 6) [m].
        data: None: one small model per platform, top down
            (:func:`~assembler_pin.model.platform.stack_gravity_terms`, each owning its
            ``Data``); a ``Data`` of the whole-stack model, owned by the caller:
            ``pin.computeGeneralizedGravity`` and ``pin.computeJointJacobians`` on it (its
            contents are overwritten). Both give the same terms (the tests hold them together).
    """
    if data is None:
        return stack_gravity_terms(am.stack_plan, pa.R, platform_configurations(am, pa, vec, lengths))
    model = am.model
    q = q_from_arrays(am, pa, vec, lengths)
    g = pin.computeGeneralizedGravity(model, data, q)
    J = pin.computeJointJacobians(model, data, q)
    top_columns = J[:, am.plate_rows_ff].transpose(1, 0, 2)
    return PlatformStatics(g[am.leg_idx_v], g[am.plate_rows_ff], J.T[am.leg_idx_v], top_columns, g[:6])


def check_statics_arguments(am: AssemblerModel, raise_on_singular: object, legs: object) -> None:
    """The arguments every statics entry point shares: a checked model, ``raise_on_singular``
    a bool, ``legs`` None or the LegState of an n-platform stack.

    Raises:
        ArgumentError: naming the argument and what it must be.
    """
    checked_model(am)
    if not isinstance(raise_on_singular, bool):
        raise ArgumentError(f"raise_on_singular must be True or False, got {type(raise_on_singular).__name__}")
    if legs is not None and not (isinstance(legs, LegState) and legs.lengths.shape == (am.n, 6)):
        raise ArgumentError(f"legs must be the LegState of these plates ({am.n} x 6 legs) or None")


def _checked_inputs(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    raise_on_singular: object,
    legs: object,
    data: object,
) -> tuple[PlateArrays, np.ndarray, np.ndarray, np.ndarray, pin.Data | None]:
    """The validated plates, top joint centres (n, 6, 3), leg vectors (n, 6, 3) and lengths
    (n, 6) [m], and the caller's ``Data`` of :func:`solve_statics_pinocchio` (ArgumentError, PoseError)."""
    check_statics_arguments(am, raise_on_singular, legs)
    if data is not None:
        data = checked_data(am, data)
    pa = plate_arrays(am, plates)
    if legs is None:
        _, top, vec, lengths = leg_vectors(am, pa)
    else:
        state = cast(LegState, legs)  # checked by check_statics_arguments
        top, lengths = state.top_points, state.lengths
        vec = state.top_points - state.bottom_points
    return pa, top, vec, lengths, data


def _own_ball_forces(terms: PlatformStatics, top: np.ndarray) -> np.ndarray:
    """Each leg's rows: ``J_legᵀ λ_i = g_leg - e_z τ_i``, with J_leg's columns the tip
    velocities of (ux, uy, actuator). The actuator's column is the leg axis u and the other
    two are orthogonal to it, so ``J_legᵀ⁻¹ e_z = u``: ``λ_i = own_i - τ_i u_i``. Returns
    ``own`` (n, 6, 3), the ball forces of the legs' weight alone [N, world axes].

    Raises:
        SingularConfigurationError: a universal joint at gimbal lock.
    """
    try:
        jac_t = leg_jacobians_t(terms.leg_columns, top)
        return np.linalg.solve(jac_t, terms.g_legs[..., None])[..., 0]
    except np.linalg.LinAlgError:
        raise SingularConfigurationError(
            "a universal joint is at gimbal lock (a leg at 90° from its home direction); its forces are not defined",
            float("inf"),
            -1,
        ) from None


def solve_statics_pinocchio(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    raise_on_singular: bool = False,
    legs: LegState | None = None,
    data: pin.Data | None = None,
) -> StaticsResult:
    """Actuator and ball-joint forces holding the stack still at the given plate poses, from
    Pinocchio's generalized gravity and closure Jacobians: the reference of the compiled
    engine :func:`~assembler_pin.statics.engine.solve_statics` (the tests hold the two to 1e-10 N),
    and its path when the caller passes a ``Data``.

    Each platform's 24×24 block is solved by eliminating every leg's own 3×3 closure
    block (invertible away from universal-joint gimbal lock): with ``w = J_legᵀ⁻¹ e_z``
    (the leg axis) the ball force is ``λ_i = J_legᵀ⁻¹ g_leg - τ_i w_i``, and the plate's
    free-flyer rows leave a 6×6 system for the six actuator forces.

    Args:
        plates: world poses of plates 0..n, or a state carrying them
            (see :func:`~assembler_pin.kinematics.plate_arrays`).
        raise_on_singular: raise :class:`SingularConfigurationError` instead of returning
            a result flagged ``singular``.
        legs: the leg state of these plates when the caller has it already (saves
            recomputing the joint centres).
        data: a Pinocchio ``Data`` of the whole-stack model that the caller owns
            (``am.create_data()``): the Pinocchio terms are then computed on it in one call,
            faster up to :data:`WHOLE_STACK_STATICS_MAX_PLATFORMS` platforms. Default: one
            model per platform (no whole-stack ``Data`` is touched). Same forces either way.
    """
    pa, top, vec, lengths, data = _checked_inputs(am, plates, raise_on_singular, legs, data)
    terms = gravity_terms(am, pa, vec, lengths, data)
    own = _own_ball_forces(terms, top)
    axis = vec / lengths[..., None]
    # Plate j+1's free-flyer rows (its local frame, moments about its origin): the shafts
    # push the plate with -λ_i at the anchors t_i, so g_ff = -Σ_i [λ_i; t_i × λ_i] (anchors
    # and forces in the plate's axes). With λ_i = own_i - τ_i u_i this is W τ = F + g_ff,
    # W's columns the legs' lines [u_i; t_i × u_i] and F the wrench of the own_i. W is the
    # negated block of the former reduced system J_ffᵀ J_c, so its condition number is the same.
    local = np.matmul(np.stack([axis, own], axis=2), pa.R[1:, None])  # (n, 6, 2, 3): Rᵀ u_i, Rᵀ own_i
    lines = np.matmul(local, am.top_line_map)  # (n, 6, 2, 6): rows [a, t_i × a]
    lines_t = lines[:, :, 0]  # Wᵀ
    rhs = lines[:, :, 1].sum(axis=1) + terms.g_top
    inverse_t, condition = line_conditions(lines_t)  # ‖W‖₁ ‖W⁻¹‖₁
    tau = np.matmul(rhs[:, None], inverse_t)[:, 0]
    singular = is_singular(condition, raise_on_singular)
    ball = own - tau[..., None] * axis
    base = (terms.base_wrench_local.reshape(2, 3) @ pa.R[0].T).ravel()  # root free-flyer wrench, world axes
    return StaticsResult(-tau, ball, base, condition, singular)
