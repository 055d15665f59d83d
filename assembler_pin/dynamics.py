"""Inverse dynamics of the stack: the actuator forces that produce a motion of the closed loops.

The equations are those of :mod:`assembler_pin.statics.pinocchio_statics` with Pinocchio's generalized gravity
``g(q)`` replaced by the recursive Newton–Euler torques of the tree,

    RNEA(q, v, a) = M(q) a + C(q, v) v + g(q) = Sᵀ τ + J_cᵀ λ,

where ``v`` and ``a`` are the joint velocities and accelerations of the motion with every loop
closed (each shaft tip moves with its top-plate anchor), so gravity, the payload and the
inertia of every plate, motor and shaft are included. The closure Jacobian is the statics'
one, so the system keeps its block structure: one 24×24 block per platform (its 6 actuator
forces and 18 ball forces), solved the same way (:func:`~assembler_pin.statics.engine.solve_statics`).
At zero twist and acceleration it is the statics.

Motions are given per plate (world frame, plate k in 0..n):

* twist ``[ṗ_k, ω_k]``: velocity of plate k's origin [m/s] and its angular velocity [rad/s];
* acceleration ``[p̈_k, ω̇_k]``: acceleration of its origin [m/s²] and angular acceleration
  [rad/s²] (classical, not spatial, accelerations);

or by the leg lengths' first two time derivatives (:func:`plate_motion_from_lengths`, base at
rest). Forces: [N], tension positive (the paper's sign), as the statics.

The whole-stack Pinocchio model is used (stacks of up to
:data:`~assembler_pin.model.WHOLE_DATA_MAX_PLATFORMS` platforms). Its ``Data`` is the caller's
(``data=``, as for :func:`~assembler_pin.statics.solve_statics`) or, by default, one kept per
thread and model; the model's own ``am.data`` is never written, so threads may share a model.
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from .common.linalg import cross, inverse_or_nan
from .common.validation import as_float_array
from .config.bounds import BOUNDS
from .exceptions import ArgumentError, SingularConfigurationError
from .kinematics import PlateArrays, leg_vectors, plate_arrays, q_from_arrays
from .model.assembler import WHOLE_DATA_MAX_PLATFORMS, AssemblerModel, checked_model
from .statics.closed_form import CONDITION_LIMIT
from .statics.pinocchio_statics import checked_data, leg_jacobians_t
from .statics.result import StaticsResult

__all__ = [
    "DynamicsResult",
    "inverse_dynamics",
    "inverse_dynamics_from_lengths",
    "path_force_coefficients",
    "plate_motion_from_lengths",
]


@dataclass(frozen=True)
class DynamicsResult(StaticsResult):
    """Actuator forces of a motion (:func:`inverse_dynamics`).

    Attributes:
        forces: (n, 6) axial actuator forces [N], tension positive: static + inertial.
        ball_forces: (n, 6, 3) force the top plate exerts on each shaft tip, world axes [N].
        base_wrench: (6,) wrench ``[f, m]`` the base mount applies to plate 0, world axes,
            moment about plate 0's origin [N, N·m].
        condition: (n,) 1-norm condition number of each platform's block.
        singular: a block's condition number exceeds :data:`~assembler_pin.statics.closed_form.CONDITION_LIMIT`.
    """


@dataclass
class _Pose:
    """What every solve at one pose shares: q, the legs and the factorized blocks."""

    pa: PlateArrays
    data: pin.Data  # the whole-stack Data the Pinocchio calls of this pose write
    q: np.ndarray
    top: np.ndarray  # (n, 6, 3) world ball-joint centres [m]
    bottom: np.ndarray  # (n, 6, 3) world bottom joint centres [m]
    vec: np.ndarray  # (n, 6, 3) leg vectors [m]
    lengths: np.ndarray  # (n, 6) [m]
    axis: np.ndarray  # (n, 6, 3) unit leg axes
    leg_columns: np.ndarray  # (n, 6, 3, 6) world Jacobian columns of the legs' joints
    jac_t: np.ndarray  # (n, 6, 3, 3) leg joints × closure axes
    inverse_t: np.ndarray  # (n, 6, 6) inverse of Wᵀ (the legs' lines in each top plate's frame)
    condition: np.ndarray  # (n,)
    world_lines: np.ndarray  # (n, 6, 6) rows [u_i, t_i × u_i], world axes (velocity map)


def _whole_stack(am: AssemblerModel) -> None:
    if am.n > WHOLE_DATA_MAX_PLATFORMS:
        raise ArgumentError(
            f"inverse dynamics runs on the whole-stack model: at most {WHOLE_DATA_MAX_PLATFORMS} platforms, "
            f"this stack has {am.n}"
        )


#: Per thread: id(model) -> (weak reference to the model, its whole-stack Data).
_local = threading.local()


def _thread_data(am: AssemblerModel) -> pin.Data:
    """A whole-stack ``Data`` of ``am`` that only this thread writes: made on first use
    (:meth:`~assembler_pin.model.AssemblerModel.create_data`, ~0.1 s) and kept while the
    model lives."""
    cache: dict[int, tuple[weakref.ref, pin.Data]] = _local.__dict__.setdefault("data", {})
    ref, data = cache.get(id(am), (None, None))
    if ref is None or ref() is not am or data is None:
        for key in [k for k, (r, _) in cache.items() if r() is None]:
            del cache[key]
        data = am.create_data()
        cache[id(am)] = (weakref.ref(am), data)
    return data


def _pose(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray, data: pin.Data | None) -> _Pose:
    """Configuration, joint Jacobians and the per-platform blocks at a pose, computed on
    ``data`` (default: this thread's, :func:`_thread_data`)."""
    checked_model(am)
    _whole_stack(am)
    data = _thread_data(am) if data is None else checked_data(am, data)
    pa = plate_arrays(am, plates)
    bottom, top, vec, lengths = leg_vectors(am, pa)
    q = q_from_arrays(am, pa, vec, lengths)
    J = pin.computeJointJacobians(am.model, data, q)
    leg_columns = J.T[am.leg_idx_v]  # (n, 6, 3, 6)
    try:
        jac_t = leg_jacobians_t(leg_columns, top)
        np.linalg.inv(jac_t)
    except np.linalg.LinAlgError:
        raise SingularConfigurationError(
            "a universal joint is at gimbal lock (a leg at 90° from its home direction); its forces are not defined",
            float("inf"),
            -1,
        ) from None
    axis = vec / lengths[..., None]
    local = np.matmul(axis[:, :, None], pa.R[1:, None])  # (n, 6, 1, 3): Rᵀ u_i in the top plate's axes
    lines_t = np.matmul(local, am.top_line_map)[:, :, 0]
    inverse_t = inverse_or_nan(lines_t)
    condition = np.abs(lines_t).sum(axis=2).max(axis=1) * np.abs(inverse_t).sum(axis=2).max(axis=1)
    world_lines = np.concatenate([axis, cross(top, axis)], axis=-1)
    return _Pose(pa, data, q, top, bottom, vec, lengths, axis, leg_columns, jac_t, inverse_t, condition, world_lines)


def _spatial(pa: PlateArrays, twists: np.ndarray, accelerations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World spatial velocities and accelerations ``[v at the world origin, ω]`` of the plates
    from their classical twists and accelerations (see the module docstring)."""
    w, alpha = twists[:, 3:], accelerations[:, 3:]
    V = np.concatenate([twists[:, :3] - cross(w, pa.p), w], axis=1)
    A = np.concatenate([accelerations[:, :3] - cross(alpha, pa.p) - cross(w, twists[:, :3]), alpha], axis=1)
    return V, A


def _motion_cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Spatial cross product of motions ``a ×ₘ b`` (…, 6) = ``[ω×v_b + v_a×ω_b, ω_a×ω_b]``."""
    return np.concatenate(
        [cross(a[..., 3:], b[..., :3]) + cross(a[..., :3], b[..., 3:]), cross(a[..., 3:], b[..., 3:])], axis=-1
    )


def _to_local(pa: PlateArrays, k: int | np.ndarray | slice, m: np.ndarray) -> np.ndarray:
    """World spatial motions (…, 6) of plates ``k`` in their own frames (``oMi.actInv``)."""
    R, p = pa.R[k], pa.p[k]
    lin = m[..., :3] + cross(m[..., 3:], p)  # the motion at the plate's origin
    return np.concatenate([np.einsum("...ab,...a->...b", R, lin), np.einsum("...ab,...a->...b", R, m[..., 3:])], -1)


def _point_velocity(V: np.ndarray, x: np.ndarray) -> np.ndarray:
    return V[..., :3] + cross(V[..., 3:], x)


def _joint_motion(am: AssemblerModel, pose: _Pose, V: np.ndarray, A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint velocities and accelerations (nv) of the tree moving the plates by the world
    spatial motions V, A (n+1, 6) with every ball-joint loop closed."""
    pa, top = pose.pa, pose.top
    v, a = np.zeros(am.model.nv), np.zeros(am.model.nv)
    ff = am.plate_idx_v[:, None] + np.arange(6)
    dV, dA = V[1:] - V[:-1], A[1:] - A[:-1]
    v[ff[0]], a[ff[0]] = _to_local(pa, 0, V[0]), _to_local(pa, 0, A[0])
    v[ff[1:]] = _to_local(pa, slice(1, None), dV)
    a[ff[1:]] = _to_local(pa, slice(1, None), dA - _motion_cross(V[1:], dV))
    # legs: the tip moves with the anchor, J_leg q̇ = v_{j+1}(t) - v_j(t)
    rel = _point_velocity(dV[:, None], top)
    v[am.leg_idx_v] = np.linalg.solve(pose.jac_t.swapaxes(2, 3), rel[..., None])[..., 0]
    # accelerations: the shaft's spatial acceleration with the legs' own accelerations zero is
    # Â_j + Σ_c V_parent(c) ×ₘ J_c q̇_c (a world column moves with its joint's parent body)
    J = pose.leg_columns  # (n, 6, 3, 6): (ux, uy, actuator), parent to child
    motion = J * v[am.leg_idx_v][..., None]
    parent = V[:-1, None, None] + np.concatenate(
        [np.zeros_like(motion[:, :, :1]), np.cumsum(motion, axis=2)[:, :, :2]], 2
    )
    Vs = V[:-1, None] + motion.sum(axis=2)
    As = A[:-1, None] + _motion_cross(parent, motion).sum(axis=2)
    tip0 = As[..., :3] + cross(As[..., 3:], top) + cross(Vs[..., 3:], _point_velocity(Vs, top))
    Vt, At = V[1:, None], A[1:, None]
    anchor = At[..., :3] + cross(At[..., 3:], top) + cross(Vt[..., 3:], _point_velocity(Vt, top))
    a[am.leg_idx_v] = np.linalg.solve(pose.jac_t.swapaxes(2, 3), (anchor - tip0)[..., None])[..., 0]
    return v, a


def _block_solve(am: AssemblerModel, pose: _Pose, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Actuator forces (tension positive), ball forces and base wrench balancing the tree's
    generalized forces ``tau`` (nv), block by block (as
    :func:`~assembler_pin.statics.engine.solve_statics`)."""
    own = np.linalg.solve(pose.jac_t, tau[am.leg_idx_v][..., None])[..., 0]
    local = np.matmul(np.stack([pose.axis, own], axis=2), pose.pa.R[1:, None])
    lines = np.matmul(local, am.top_line_map)
    rhs = lines[:, :, 1].sum(axis=1) + tau[am.plate_rows_ff]
    act = np.matmul(rhs[:, None], pose.inverse_t)[:, 0]
    ball = own - act[..., None] * pose.axis
    base = (tau[:6].reshape(2, 3) @ pose.pa.R[0].T).ravel()
    return -act, ball, base


def _check_magnitude(arr: np.ndarray, what: str) -> None:
    """Refuse a motion component beyond the ``dynamics.motion`` bound (its square would
    overflow the inverse dynamics into NaN forces)."""
    high = BOUNDS["dynamics.motion"].high
    if arr.size and not np.abs(arr).max() <= high:
        raise ArgumentError(
            f"{what}: a component of {float(np.abs(arr).max()):.3g} is out of range (every component within "
            f"±{high:g} m/s, rad/s, m/s² or rad/s², the dynamics.motion limit)"
        )


def _checked_motion(am: AssemblerModel, value: npt.ArrayLike, what: str) -> np.ndarray:
    arr = as_float_array(value, what, error=ArgumentError)
    if arr.shape == (am.n, 6):  # the moving plates only: the base at rest
        arr = np.vstack([np.zeros(6), arr])
    if arr.shape != (am.n + 1, 6) or not np.isfinite(arr).all():
        raise ArgumentError(f"{what} must be finite, shape ({am.n + 1}, 6) (plates 0..n) or ({am.n}, 6)")
    _check_magnitude(arr, what)
    return arr


def inverse_dynamics(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    twists: npt.ArrayLike,
    accelerations: npt.ArrayLike,
    raise_on_singular: bool = False,
    data: pin.Data | None = None,
) -> DynamicsResult:
    """Actuator forces producing the plates' motion (see the module docstring).

    Args:
        plates: world poses of plates 0..n.
        twists: (n+1, 6) ``[ṗ_k, ω_k]`` per plate, world axes [m/s, rad/s]; (n, 6): plates
            1..n, the base at rest.
        accelerations: (n+1, 6) or (n, 6) ``[p̈_k, ω̇_k]`` [m/s², rad/s²].
        raise_on_singular: raise :class:`SingularConfigurationError` instead of a result
            flagged ``singular``.
        data: a Pinocchio ``Data`` of the whole-stack model that the caller owns
            (``am.create_data()``), written by the call; default: one kept per thread for
            this model (``am.data`` is never written).

    Raises:
        ArgumentError: arrays of the wrong shape or not finite, a ``data`` of another
            model, or a stack over :data:`~assembler_pin.model.WHOLE_DATA_MAX_PLATFORMS` platforms.
    """
    pose = _pose(am, plates, data)
    V, A = _spatial(pose.pa, _checked_motion(am, twists, "twists"), _checked_motion(am, accelerations, "accelerations"))
    return _result(am, pose, V, A, raise_on_singular)


def _result(am: AssemblerModel, pose: _Pose, V: np.ndarray, A: np.ndarray, raise_on_singular: bool) -> DynamicsResult:
    singular = not pose.condition.max() <= CONDITION_LIMIT
    if singular and raise_on_singular:
        worst = int(np.argmax(np.where(np.isfinite(pose.condition), pose.condition, np.inf)))
        raise SingularConfigurationError(
            f"platform {worst} is near a singular configuration (condition number {pose.condition[worst]:.3g}); "
            "its forces are not defined",
            float(pose.condition[worst]),
            worst,
        )
    v, a = _joint_motion(am, pose, V, A)
    tau = pin.rnea(am.model, pose.data, pose.q, v, a)
    forces, ball, base = _block_solve(am, pose, tau)
    return DynamicsResult(forces, ball, base, pose.condition, singular)


def _spatial_from_lengths(pose: _Pose, rates: np.ndarray, accels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World spatial plate motions (base at rest) from leg-length rates and accelerations."""
    n = rates.shape[0]
    V, A = np.zeros((n + 1, 6)), np.zeros((n + 1, 6))
    W = pose.world_lines
    for j in range(n):  # L̇_i = u_i · (ΔV at t_i): rows [u_i, t_i × u_i]
        V[j + 1] = V[j] + np.linalg.solve(W[j], rates[j])
    t, b, d, L = pose.top, pose.bottom, pose.vec, pose.lengths
    v_top = _point_velocity(V[1:, None], t)
    v_bot = _point_velocity(V[:-1, None], b)
    d_dot = v_top - v_bot
    bias = np.einsum("jia,jia->ji", d, cross(V[1:, None, 3:], v_top) - cross(V[:-1, None, 3:], v_bot))
    rhs = (rates**2 + L * accels - np.einsum("jia,jia->ji", d_dot, d_dot) - bias) / L
    for j in range(n):  # L̈: u_i · (ΔA_lin + Δα × t_i) = rhs_i, the same rows
        A[j + 1] = A[j] + np.linalg.solve(W[j], rhs[j])
    return V, A


def _checked_rates(am: AssemblerModel, value: npt.ArrayLike, what: str) -> np.ndarray:
    arr = as_float_array(value, what, error=ArgumentError)
    if arr.size != 6 * am.n or not np.isfinite(arr).all():
        raise ArgumentError(f"{what} must be {6 * am.n} finite numbers (n x 6 legs)")
    _check_magnitude(arr, what)
    return arr.reshape(am.n, 6)


def plate_motion_from_lengths(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    rates: npt.ArrayLike,
    accels: npt.ArrayLike,
    data: pin.Data | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Plate twists and accelerations (n+1, 6), world, classical (module docstring), of the
    stack at ``plates`` whose legs change at ``rates`` [m/s] and ``accels`` [m/s²] (n, 6),
    the base at rest; ``data`` as for :func:`inverse_dynamics`."""
    pose = _pose(am, plates, data)
    V, A = _spatial_from_lengths(pose, _checked_rates(am, rates, "rates"), _checked_rates(am, accels, "accels"))
    p = pose.pa.p
    pdot = V[:, :3] + cross(V[:, 3:], p)
    pddot = A[:, :3] + cross(A[:, 3:], p) + cross(V[:, 3:], pdot)
    return np.hstack([pdot, V[:, 3:]]), np.hstack([pddot, A[:, 3:]])


def inverse_dynamics_from_lengths(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    rates: npt.ArrayLike,
    accels: npt.ArrayLike,
    raise_on_singular: bool = False,
    data: pin.Data | None = None,
) -> DynamicsResult:
    """:func:`inverse_dynamics` of the motion whose leg lengths change at ``rates`` [m/s] and
    ``accels`` [m/s²] (n, 6) at the pose ``plates`` (the base at rest); ``data`` as for
    :func:`inverse_dynamics`."""
    pose = _pose(am, plates, data)
    V, A = _spatial_from_lengths(pose, _checked_rates(am, rates, "rates"), _checked_rates(am, accels, "accels"))
    return _result(am, pose, V, A, raise_on_singular)


def path_force_coefficients(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    d_lengths: npt.ArrayLike,
    dd_lengths: npt.ArrayLike,
    data: pin.Data | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Leg forces along a path ``L(s)`` at one point, as ``F = a s̈ + b ṡ² + c``.

    Args:
        plates: the pose at the point; d_lengths: (n, 6) ``L'(s)``; dd_lengths: (n, 6)
            ``L''(s)``, or (k, n, 6) for k values of it (e.g. both one-sided values at a
            knot of a C¹ spline).
        data: a Pinocchio ``Data`` of the whole-stack model that the caller owns
            (``am.create_data()``), written by the call; default: one kept per thread for
            this model (``am.data`` is never written).

    Returns:
        (a, b, c) [N]: ``c`` (n, 6) the statics, ``a`` (n, 6) the forces of ``L̈ = L'`` at rest,
        ``b`` (n, 6) or (k, n, 6) those of ``L̇ = L'``, ``L̈ = L''`` (both less ``c``). The
        forces are affine in ``L̈`` and quadratic in ``L̇``, so this is exact.
    """
    pose = _pose(am, plates, data)
    d1 = _checked_rates(am, d_lengths, "d_lengths")
    dd = as_float_array(dd_lengths, "dd_lengths")
    many = dd.ndim == 3
    d2s = [_checked_rates(am, x, "dd_lengths") for x in (dd if many else [dd])]
    zero = np.zeros(am.model.nv)
    c = _block_solve(am, pose, pin.rnea(am.model, pose.data, pose.q, zero, zero))[0]
    out = []
    for rates, accels in [(np.zeros_like(d1), d1)] + [(d1, d2) for d2 in d2s]:
        V, A = _spatial_from_lengths(pose, rates, accels)
        v, a = _joint_motion(am, pose, V, A)
        out.append(_block_solve(am, pose, pin.rnea(am.model, pose.data, pose.q, v, a))[0] - c)
    return out[0], (np.array(out[1:]) if many else out[1]), c
