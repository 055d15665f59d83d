"""Differentiable statics and kinematics of a stack pose, for the optimizer.

The optimizer needs the actuator forces, leg lengths, joint deflections, rise and
plate angular deviations *and their exact derivatives* with respect to the plate poses.
Differentiating the Pinocchio system ``g(q) = Sᵀτ + J_cᵀλ`` needs second-order kinematics
and a correction for the world-fixed closure forces; the same equilibrium written per
platform in closed form (:mod:`assembler_pin.statics.closed_form`) differentiates in a few
vectorized lines, so this module uses it:

* each leg (motor + shaft, a universal joint at the bottom, a ball at the top) balances
  its own weight: the ball force's component across the leg is
  ``f⊥ = -(c_m m_m + (L - c_s) m_s) / L · g⊥`` (g⊥ = gravity across the leg), and the
  universal joint carries no moment (the leg's weights act on its axis);
* the top plate of platform j and everything it carries balance the six ball forces:
  ``Σ a_i [u_i; t_i × u_i] = [W_up; M_up] - Σ [f⊥_i; t_i × f⊥_i]`` — a 6×6 system for the
  axial ball-force components ``a_i`` (``W_up``/``M_up``: weight of everything above and
  its moment about the world origin);
* the actuator force (tension positive) is ``F_i = a_i + m_s g·u_i``.

The values come from the closed form and from the one set of leg measures
(:mod:`assembler_pin.kinematics.legs`); only their derivatives are written here. The tests
hold these forces to :func:`~assembler_pin.statics.pinocchio_statics.solve_statics_pinocchio` (Pinocchio) and every
derivative to finite differences of the Pinocchio statics.

Derivatives are taken with respect to a **world twist** ``η_k = (v, ω)`` of each plate
k = 1..n (``T_k ← exp6(η_k) · T_k``), columns ``6(k-1) .. 6k-1``; plate 0 is fixed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..common.linalg import cross, skew
from ..kinematics import PlateArrays, PlateDeviation, legs, plate_deviation
from ..model.assembler import AssemblerModel
from .closed_form import Equilibrium, equilibrium

__all__ = [
    "LegDerivatives",
    "PoseDerivatives",
    "PoseValues",
    "leg_derivatives",
    "pose_derivatives",
    "pose_values",
]

_I3 = np.eye(3)


@dataclass(frozen=True)
class LegDerivatives:
    """Leg lengths, deflection cosines and rise of a stack pose with their derivatives
    (last axis: the 6n world-twist columns of plates 1..n).

    Attributes:
        lengths, d_lengths: (n, 6) [m] and (n, 6, 6n).
        cos_deflection, d_cos_deflection: (n, 6, 2) cosines of the bottom / top joint
            deflections and (n, 6, 2, 6n).
        rise, d_rise: (n, 6) height of each top joint above its bottom joint in the
            bottom plate's frame [m] and (n, 6, 6n).
    """

    lengths: np.ndarray
    d_lengths: np.ndarray
    cos_deflection: np.ndarray
    d_cos_deflection: np.ndarray
    rise: np.ndarray
    d_rise: np.ndarray


@dataclass(frozen=True)
class PoseDerivatives(LegDerivatives):
    """The :class:`LegDerivatives` with the statics and the plate angles (last axis: 6n
    world-twist columns of plates 1..n).

    Attributes:
        forces, d_forces: (n, 6) actuator forces [N, tension positive] and (n, 6, 6n).
        plate_angles, d_plate_angles_sq: (n,) angle λ_k between ``p_k - p_{k-1}`` and the
            rest direction of plate k on plate k-1 [rad] (paper eq. 9), and the
            derivative of λ_k² (n, 6n) — smooth where λ_k itself is not.
    """

    forces: np.ndarray
    d_forces: np.ndarray
    plate_angles: np.ndarray
    d_plate_angles_sq: np.ndarray


def _point_jacobian(points: np.ndarray, first_plate: int, n: int) -> np.ndarray:
    """d(point)/d(world twists of plates 1..n) for points (m, ..., 3) with points[r] on
    plate ``first_plate + r``; returns (m, ..., 3, 6n).

    Plate 0 is fixed (zero columns); plate k ≥ 1 owns columns 6(k-1)..6k-1:
    ``[I, -[x]×]`` (a world twist (v, ω) moves x by v + ω × x).
    """
    m = points.shape[0]
    inner = points.shape[1:-1]
    out = np.zeros((m, *inner, 3, n, 6))
    rows = np.arange(m)
    cols = rows + first_plate - 1
    rows, cols = rows[cols >= 0], cols[cols >= 0]
    sel: tuple[Any, ...] = (rows, *([slice(None)] * len(inner)), slice(None), cols)
    out[(*sel, slice(0, 3))] = _I3
    out[(*sel, slice(3, 6))] = -skew(points[rows])
    return out.reshape(*out.shape[:-2], 6 * n)


def _leg_jacobians(
    b: np.ndarray, t: np.ndarray, L: np.ndarray, u: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """d(bottom joint), d(top joint), d(leg vector), d(length), d(unit direction) of the legs
    (n, 6, ...) w.r.t. the world twists of plates 1..n: (n, 6, 3, 6n) and (n, 6, 6n)."""
    n = b.shape[0]
    db = _point_jacobian(b, 0, n)  # bottom joints of SP j lie on plate j
    dt = _point_jacobian(t, 1, n)  # top joints on plate j+1
    dd = dt - db
    dL = np.einsum("jik,jikc->jic", u, dd)
    du = (dd - u[..., None] * dL[:, :, None, :]) / L[..., None, None]
    return db, dt, dd, dL, du


def rest_directions(home: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each leg's rest direction ``home`` (6, 3) in the world as seen by its bottom and its
    top plate: (n, 6, 3) each."""
    return np.matmul(home, R[:-1].transpose(0, 2, 1)), np.matmul(home, R[1:].transpose(0, 2, 1))


def _deflection_and_rise(
    am: AssemblerModel, R: np.ndarray, u: np.ndarray, L: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Cosines of the bottom / top joint deflections (n, 6, 2) and the rise (n, 6) [m] of legs
    of world directions ``u`` and lengths ``L`` (:mod:`~assembler_pin.kinematics.legs`)."""
    in_bottom, in_top = legs.directions_in_plates(u, R[:-1], R[1:])
    return legs.deflection_cosines(in_bottom, in_top, am.geometry.home_direction), legs.leg_rise(in_bottom, L)


def _deflection_and_rise_derivatives(
    R: np.ndarray,
    d: np.ndarray,
    u: np.ndarray,
    h_bottom: np.ndarray,
    h_top: np.ndarray,
    dd: np.ndarray,
    du: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """d(cos deflection) (n, 6, 2, 6n) and d(rise) (n, 6, 6n), from the legs' vectors ``d``,
    directions ``u``, rest directions in the world and the derivatives ``dd``, ``du``."""
    n = d.shape[0]
    d_cos_b = np.einsum("jik,jikc->jic", h_bottom, du)
    d_cos_t = np.einsum("jik,jikc->jic", h_top, du)
    # rotating plate k by ω turns h into h + ω × h: d(u·h) += u·(ω × h) = (h × u)·ω
    hb_x_u = cross(h_bottom, u)
    ht_x_u = cross(h_top, u)
    z_bottom = R[:-1, :, 2]  # (n, 3)
    d_rise = np.einsum("jk,jikc->jic", z_bottom, dd)
    z_x_d = cross(z_bottom[:, None, :], d)
    for j in range(n):
        if j >= 1:
            d_cos_b[j, :, 6 * (j - 1) + 3 : 6 * j] += hb_x_u[j]
            d_rise[j, :, 6 * (j - 1) + 3 : 6 * j] += z_x_d[j]
        d_cos_t[j, :, 6 * j + 3 : 6 * j + 6] += ht_x_u[j]
    return np.stack([d_cos_b, d_cos_t], axis=2), d_rise


def leg_derivatives(am: AssemblerModel, pa: PlateArrays) -> LegDerivatives:
    """The kinematic part of :func:`pose_derivatives` alone (no statics): lengths [m],
    deflection cosines (n, 6, 2), rise [m] and their derivatives w.r.t. the world twists
    of plates 1..n."""
    geo = am.geometry
    R, p = pa.R, pa.p
    b, t = legs.leg_points(geo, R, p)
    d = t - b
    L = legs.leg_lengths(d)
    u = d / L[..., None]
    _, _, dd, dL, du = _leg_jacobians(b, t, L, u)
    h_bottom, h_top = rest_directions(geo.home_direction, R)
    cos, rise = _deflection_and_rise(am, R, u, L)
    d_cos, d_rise = _deflection_and_rise_derivatives(R, d, u, h_bottom, h_top, dd, du)
    return LegDerivatives(L, dL, cos, d_cos, rise, d_rise)


@dataclass(frozen=True)
class PoseValues:
    """Everything the optimizer reads at one stack pose, from the closed form alone.

    The intermediates are kept so that :func:`pose_derivatives` extends the same pass
    instead of computing the pose again.

    Attributes:
        plates: the world poses of plates 0..n.
        eq: the closed-form :class:`Equilibrium` (forces [N], leg vectors, directions, ...).
        cos_deflection: (n, 6, 2) cosines of the bottom / top joint deflections.
        rise: (n, 6) height of each top joint above its bottom joint, bottom plate's frame [m].
        deviation: the plate-deviation angles λ_k and their vectors (paper eq. 9).
    """

    plates: PlateArrays
    eq: Equilibrium
    cos_deflection: np.ndarray
    rise: np.ndarray
    deviation: PlateDeviation

    @property
    def forces(self) -> np.ndarray:
        """(n, 6) actuator forces [N, tension positive]; NaN where the statics are singular."""
        return self.eq.forces

    @property
    def lengths(self) -> np.ndarray:
        """(n, 6) leg lengths [m]."""
        return self.eq.L

    @property
    def plate_angles(self) -> np.ndarray:
        """(n,) λ_k [rad]."""
        return self.deviation.angles


def pose_values(am: AssemblerModel, pa: PlateArrays) -> PoseValues:
    """Forces, lengths, deflection cosines, rise and plate angles of a stack pose in one
    closed-form pass (no Pinocchio); a singular platform gives NaN forces.

    Args:
        pa: world poses of plates 0..n (validated, e.g. by
            :func:`~assembler_pin.kinematics.plate_arrays`).
    """
    eq, _ = equilibrium(am, pa.R, pa.p)
    cos, rise = _deflection_and_rise(am, pa.R, eq.u, eq.L)
    return PoseValues(pa, eq, cos, rise, plate_deviation(am, pa))


def transverse_force_derivatives(
    am: AssemblerModel, eq: Equilibrium, dL: np.ndarray, du: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """d(gravity along each leg) (n, 6, C) [m/s²] and d(transverse ball force) (n, 6, 3, C) [N],
    over the C derivative columns of ``dL`` and ``du``."""
    leg = am.config.leg
    g = np.array([0.0, 0.0, -am.config.gravity])
    dgu = np.einsum("k,jikc->jic", g, du)
    dg_perp = -(dgu[:, :, None, :] * eq.u[..., None] + eq.gu[..., None, None] * du)
    lever = leg.motor_com * leg.motor_mass - leg.shaft_com * leg.shaft_mass
    ds = (-lever / eq.L**2)[..., None] * dL
    df_perp = -(ds[:, :, None, :] * eq.g_perp[..., None] + eq.s[..., None, None] * dg_perp)
    return dgu, df_perp


def _up_moment_derivatives(
    am: AssemblerModel, eq: Equilibrium, p: np.ndarray, db: np.ndarray, dt: np.ndarray, du: np.ndarray
) -> np.ndarray:
    """d(moment about the world origin of the weight above each top plate) (n, 3, 6n) [N·m]."""
    cfg, n = am.config, am.n
    leg = cfg.leg
    skew_g = skew(np.array([0.0, 0.0, -cfg.gravity]))
    d_motor_c = db + leg.motor_com * du
    d_shaft_c = dt - leg.shaft_com * du
    level_dmoment = np.zeros((n + 1, 3, 6 * n))
    level_dmoment[1:] = -cfg.plate.mass * np.matmul(skew_g, _point_jacobian(p[1:], 1, n))
    level_dmoment[:n] += (-np.matmul(skew_g, leg.motor_mass * d_motor_c + leg.shaft_mass * d_shaft_c)).sum(axis=1)
    d_payload = _point_jacobian(eq.payload_point[None], n, n)[0]
    level_dmoment[n] += -cfg.payload.mass * skew_g @ d_payload
    return np.cumsum(level_dmoment[::-1], axis=0)[::-1][1:]


def axial_force_derivatives(
    eq: Equilibrium,
    dt: np.ndarray,
    du: np.ndarray,
    df_perp: np.ndarray,
    up_dmoment: np.ndarray,
    a: np.ndarray | None = None,
) -> np.ndarray:
    """d(axial ball-force components) (n, 6, C) [N] over any C derivative columns: the 6×6
    system of each platform differentiated, ``K da = d(rhs) - dK a`` (``a``: the axial
    components the system is differentiated at, the equilibrium's by default)."""
    skew_t = skew(eq.t)
    # d(t × f) = -[f]× dt + [t]× df ;  d(t × u) = -[u]× dt + [t]× du
    d_t_cross_f = -np.matmul(skew(eq.f_perp), dt) + np.matmul(skew_t, df_perp)
    d_t_cross_u = -np.matmul(skew(eq.u), dt) + np.matmul(skew_t, du)
    d_rhs = np.concatenate([-df_perp.sum(axis=1), up_dmoment - d_t_cross_f.sum(axis=1)], axis=1)
    a = eq.a if a is None else a
    dK_a = np.concatenate([np.einsum("ji,jikc->jkc", a, du), np.einsum("ji,jikc->jkc", a, d_t_cross_u)], axis=1)
    return np.linalg.solve(eq.K, d_rhs - dK_a)


def plate_angle_sq_derivatives(dev: PlateDeviation, p: np.ndarray) -> np.ndarray:
    """d(λ_k²) (n, 6n): ``dλ = -(c - cosλ â)·dâ / sinλ - (â - cosλ c)·dc / sinλ``, with
    â the unit step ``p_k - p_{k-1}`` and c the rest direction (λ/sinλ → 1 at λ = 0)."""
    n = p.shape[0] - 1
    C = 6 * n
    lam, step_dir, step_len, rest_dir, sin_l, cos_l = (
        dev.angles,
        dev.step_dir,
        dev.step_length,
        dev.rest_dir,
        dev.sin,
        dev.cos,
    )
    ratio = np.where(sin_l > 1e-12, lam / np.maximum(sin_l, 1e-300), 1.0)
    dp_all = _point_jacobian(p[1:], 1, n)
    d_step = dp_all.copy()
    d_step[1:] -= dp_all[:-1]
    d_rest_dir = np.zeros((n, 3, C))
    for k in range(1, n):
        d_rest_dir[k, :, 6 * (k - 1) + 3 : 6 * k] = -skew(rest_dir[k])
    d_step_dir = np.matmul((_I3 - step_dir[:, :, None] * step_dir[:, None, :]) / step_len[:, None, None], d_step)
    g_a = -(rest_dir - cos_l[:, None] * step_dir)
    g_c = -(step_dir - cos_l[:, None] * rest_dir)
    inner = np.einsum("jk,jkc->jc", g_a, d_step_dir) + np.einsum("jk,jkc->jc", g_c, d_rest_dir)
    return 2.0 * ratio[:, None] * inner


def pose_derivatives(am: AssemblerModel, pa: PlateArrays, values: PoseValues | None = None) -> PoseDerivatives:
    """Forces, lengths, deflections, rise and plate angles with their derivatives.

    Args:
        pa: world poses of plates 0..n (validated, e.g. by
            :func:`~assembler_pin.kinematics.plate_arrays`).
        values: :func:`pose_values` of ``pa`` when the caller has it: the derivatives then
            extend that pass instead of computing the pose again.

    Raises:
        numpy.linalg.LinAlgError: a platform's 6×6 system is singular.
    """
    v = pose_values(am, pa) if values is None else values
    eq = v.eq
    db, dt, dd, dL, du = _leg_jacobians(eq.b, eq.t, eq.L, eq.u)
    dgu, df_perp = transverse_force_derivatives(am, eq, dL, du)
    up_dmoment = _up_moment_derivatives(am, eq, pa.p, db, dt, du)
    da = axial_force_derivatives(eq, dt, du, df_perp, up_dmoment)
    h_bottom, h_top = rest_directions(am.geometry.home_direction, pa.R)
    d_cos, d_rise = _deflection_and_rise_derivatives(pa.R, eq.d, eq.u, h_bottom, h_top, dd, du)
    return PoseDerivatives(
        forces=eq.forces,
        d_forces=da + am.config.leg.shaft_mass * dgu,
        lengths=eq.L,
        d_lengths=dL,
        cos_deflection=v.cos_deflection,
        d_cos_deflection=d_cos,
        rise=v.rise,
        d_rise=d_rise,
        plate_angles=v.plate_angles,
        d_plate_angles_sq=plate_angle_sq_derivatives(v.deviation, pa.p),
    )
