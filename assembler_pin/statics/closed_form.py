"""The closed-form equilibrium of the stack and the condition number of its 6×6 systems.

The equilibrium (module docstring of :mod:`assembler_pin.statics.derivatives`):

* each leg (motor + shaft, a universal joint at the bottom, a ball at the top) balances
  its own weight: the ball force's component across the leg is
  ``f⊥ = -(c_m m_m + (L - c_s) m_s) / L · g⊥`` (g⊥ = gravity across the leg);
* the top plate of platform j and everything it carries balance the six ball forces:
  ``Σ a_i [u_i; t_i × u_i] = [W_up; M_up] - Σ [f⊥_i; t_i × f⊥_i]``, a 6×6 system for the
  axial ball-force components ``a_i``;
* the actuator force (tension positive) is ``F_i = a_i + m_s g·u_i``.

This module is the one owner of that equilibrium (:func:`equilibrium`, vectorized over
batches of stacks and the platforms) and of the condition number every statics path
reports and judges (:func:`line_conditions`, :data:`CONDITION_LIMIT`,
:func:`is_singular`): :func:`~assembler_pin.statics.pinocchio_statics.solve_statics_pinocchio`, the numpy path of
:mod:`~assembler_pin.statics.kernel` and the elastic truss of :mod:`~assembler_pin.compliance.elastic`
call them. (The compiled kernel of :mod:`~assembler_pin.statics.loops` computes the same
number by its own Gauss–Jordan elimination; the tests hold the two together.)

Frames: world poses of plates 0..n; forces [N], moments [N·m], lengths [m].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.linalg import cross, inverse_or_nan
from ..exceptions import SingularConfigurationError
from ..kinematics import legs
from ..model.assembler import AssemblerModel

__all__ = [
    "CONDITION_LIMIT",
    "Equilibrium",
    "equilibrium",
    "is_singular",
    "line_conditions",
    "raise_singular",
]

CONDITION_LIMIT = 1e8
"""Largest 1-norm condition number of a platform's reduced 6×6 statics system trusted."""


def line_conditions(lines_t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverses and 1-norm condition numbers of the platforms' leg-line matrices.

    Args:
        lines_t: (..., 6, 6) the transposes ``Wᵀ`` of the matrices ``W`` whose columns are
            the legs' lines ``[u_i; r_i × u_i]`` (so one row per leg), in any frame.

    Returns:
        The inverses of ``lines_t`` (..., 6, 6) and ``‖W‖₁ ‖W⁻¹‖₁`` (...), from the rows
        of the transposes; an exactly singular matrix gives NaN for both.
    """
    inverse_t = inverse_or_nan(lines_t)
    condition = np.abs(lines_t).sum(axis=-1).max(axis=-1) * np.abs(inverse_t).sum(axis=-1).max(axis=-1)
    return inverse_t, condition


def is_singular(condition: np.ndarray, raise_on_singular: bool = False) -> bool:
    """Whether a platform's condition number (``condition`` (n,)) exceeds
    :data:`CONDITION_LIMIT` (NaN counts as singular).

    Raises:
        SingularConfigurationError: with ``raise_on_singular``, when it does
            (:func:`raise_singular`).
    """
    singular = not condition.max() <= CONDITION_LIMIT
    if singular and raise_on_singular:
        raise_singular(condition)
    return singular


def raise_singular(condition: np.ndarray) -> None:
    """Raise :class:`SingularConfigurationError` naming the worst platform of ``condition`` (n,)
    (a NaN condition counts as the worst)."""
    worst = int(np.argmax(np.where(np.isfinite(condition), condition, np.inf)))
    raise SingularConfigurationError(
        f"platform {worst} is near a singular configuration (condition number "
        f"{condition[worst]:.3g} > {CONDITION_LIMIT:.0g}); its forces are not defined",
        float(condition[worst]),
        worst,
    )


@dataclass(frozen=True)
class Equilibrium:
    """The closed-form equilibrium of stacks (module docstring), leading batch axes ``...``.

    Attributes:
        b, t: (..., n, 6, 3) bottom and top joint centres, world [m].
        d, L, u: leg vectors [m], lengths [m] and unit directions.
        gu: (..., n, 6) gravity along each leg [m/s²].
        g_perp, s, f_perp: gravity across the leg, the leg's mass factor [kg] and the
            transverse ball force [N].
        motor_c, shaft_c: (..., n, 6, 3) motor and shaft centres of mass, world [m].
        payload_point: (..., 3) the payload's centre of mass, world [m].
        up_force, up_moment: (..., n, 3) weight above each top plate [N] and its moment
            about the world origin [N·m].
        K: (..., n, 6, 6) the lines of the legs (rows [u; t × u], a column per leg).
        a: (..., n, 6) axial ball-force components [N]; forces: actuator forces [N, tension +].
    """

    b: np.ndarray
    t: np.ndarray
    d: np.ndarray
    L: np.ndarray
    u: np.ndarray
    gu: np.ndarray
    g_perp: np.ndarray
    s: np.ndarray
    f_perp: np.ndarray
    motor_c: np.ndarray
    shaft_c: np.ndarray
    payload_point: np.ndarray
    up_force: np.ndarray
    up_moment: np.ndarray
    K: np.ndarray
    a: np.ndarray
    forces: np.ndarray


def _weight_above(
    am: AssemblerModel, R: np.ndarray, p: np.ndarray, motor_c: np.ndarray, shaft_c: np.ndarray, g: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The payload's centre (..., 3) [m], and the weight above each top plate (..., n, 3) [N]
    with its moment about the world origin (..., n, 3) [N·m]."""
    cfg, n, leg = am.config, am.n, am.config.leg
    mg_plate = cfg.plate.mass * g
    payload_point = np.einsum("...ab,b->...a", R[..., n, :, :], np.array([0.0, 0.0, cfg.payload.offset])) + p[..., n, :]
    batch = R.shape[:-3]
    level_moment = np.zeros((*batch, n + 1, 3))  # level k: plate k, legs of SP k, payload (k = n)
    level_force = np.zeros((*batch, n + 1, 3))
    level_moment[..., 1:, :] = cross(p[..., 1:, :], mg_plate)
    level_force[..., 1:, :] = mg_plate
    level_moment[..., :n, :] += cross((leg.motor_mass * motor_c + leg.shaft_mass * shaft_c).sum(axis=-2), g)
    level_force[..., :n, :] += 6 * (leg.motor_mass + leg.shaft_mass) * g
    level_moment[..., n, :] += cfg.payload.mass * cross(payload_point, g)
    level_force[..., n, :] += cfg.payload.mass * g
    # everything above plate j+1 = levels j+1 .. n  (reverse cumulative sums)
    up_force = np.flip(np.cumsum(np.flip(level_force, -2), axis=-2), -2)[..., 1:, :]
    up_moment = np.flip(np.cumsum(np.flip(level_moment, -2), axis=-2), -2)[..., 1:, :]
    return payload_point, up_force, up_moment


def _axial(K: np.ndarray, rhs: np.ndarray, inverse: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """``K a = rhs`` per platform: ``a`` (..., n, 6) and, with ``inverse`` (or when a block is
    singular), the inverses of ``K`` (NaN where exactly singular)."""
    if not inverse:
        try:
            return np.linalg.solve(K, rhs[..., None])[..., 0], None
        except np.linalg.LinAlgError:
            pass
    K_inv = inverse_or_nan(K)
    return np.einsum("...ab,...b->...a", K_inv, rhs), K_inv


def equilibrium(
    am: AssemblerModel, R: np.ndarray, p: np.ndarray, inverse: bool = False
) -> tuple[Equilibrium, np.ndarray | None]:
    """The closed-form statics of one stack (R (n+1, 3, 3), p (n+1, 3)) or of a batch
    (R (B, n+1, 3, 3), p (B, n+1, 3)), vectorized over the batch and the platforms.

    Returns:
        The :class:`Equilibrium`, and with ``inverse`` the inverses of ``K`` (world frame,
        moments about the world origin); a singular ``K`` gives NaN forces (and NaN inverses).
    """
    leg = am.config.leg
    g = np.array([0.0, 0.0, -am.config.gravity])
    b, t = legs.leg_points(am.geometry, R, p)
    d = t - b
    L = legs.leg_lengths(d)
    u = d / L[..., None]
    gu = u @ g
    g_perp = g - gu[..., None] * u
    lever = leg.motor_com * leg.motor_mass - leg.shaft_com * leg.shaft_mass
    s = leg.shaft_mass + lever / L
    f_perp = -s[..., None] * g_perp
    motor_c = b + leg.motor_com * u
    shaft_c = t - leg.shaft_com * u
    payload_point, up_force, up_moment = _weight_above(am, R, p, motor_c, shaft_c, g)
    K = np.swapaxes(np.concatenate([u, cross(t, u)], axis=-1), -1, -2)  # (..., n, 6 rows, 6 legs)
    rhs = np.concatenate([up_force - f_perp.sum(axis=-2), up_moment - cross(t, f_perp).sum(axis=-2)], axis=-1)
    a, K_inv = _axial(K, rhs, inverse)
    forces = a + leg.shaft_mass * gu
    eq = Equilibrium(
        b, t, d, L, u, gu, g_perp, s, f_perp, motor_c, shaft_c, payload_point, up_force, up_moment, K, a, forces
    )
    return eq, K_inv
