"""The stack as an elastic truss: its total potential, gradient and Hessian over the plate poses,
and the Newton solve of its loaded equilibrium (used by :mod:`assembler_pin.compliance.ee_stiffness` and
:mod:`assembler_pin.compliance.loaded`).

Model. Each leg is a linear spring along its pin-to-pin axis, stiffness ``k = leg.stiffness``
[N/m], unloaded (commanded) length ``L0``: its tension is ``T = k (L - L0)`` (positive when
stretched, the package's sign). The motor and shaft centres of mass lie on the leg axis, so
with the plates placed every body is placed and the total potential is a function of the
plate poses alone::

    V = Σ_legs ½ k (L - L0)²  +  Σ_bodies m g z  -  f·p_n - m·θ_n

(plates at their centres, motors ``motor_com`` above the bottom joint and shafts ``shaft_com``
below the top joint on the axis, the payload ``payload.offset`` along the EE's z; an optional
wrench ``[f, m]`` on the EE, world axes, the moment about the EE origin).

Coordinates. Plates 1..n each move by ``(δp, δθ)``, world axes at the plate's origin:
``p ← p + δp``, ``R ← exp3(δθ) R`` (plate 0 is fixed). A point ``x = p + r`` of the plate then
moves by ``δp + δθ × r + ½ δθ × (δθ × r)``; its second-order term makes the Hessian exact in
these coordinates (``sym(f rᵀ) - (f·r) I`` in the rotation block, ``f`` the point's gradient).

Per leg, with ``d = t - b``, ``u = d / L``, ``a = (0, 0, -g)`` and the leg's lever
``λ = m_m c_m - m_s c_s`` (the leg's weight reduced to its axis):

* gradient in d: ``G = T u - λ (a - (a·u) u) / L``; in b: ``-G - m_m a``; in t: ``G - m_s a``;
* Hessian in d: ``k u uᵀ`` (the elastic part) ``+ (T / L)(I - u uᵀ)`` (the preload)
  ``+ λ (a uᵀ + u aᵀ + (a·u)(I - 3 u uᵀ)) / L²`` (the leg's own weight).

The Hessian is block-tridiagonal over the plates (a leg joins plates j and j+1). Up to
:data:`DENSE_MAX_PLATFORMS` platforms it is solved as one dense matrix (one LAPACK call, which
also gives the EE's condensed compliance, the EE block of its inverse); above, by one sweep of
its blocks from the base up (linear in n); :mod:`assembler_pin.compliance.tangent` holds those solves.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..common.linalg import cross, skew
from ..model.assembler import AssemblerModel
from ..statics import closed_form
from .tangent import held_solve, tangent_solve

__all__ = [
    "DENSE_MAX_PLATFORMS",
    "MAX_STEP",
    "ElasticTerms",
    "Equilibrium",
    "elastic_terms",
    "exp3_batch",
    "line_conditions",
    "solve_equilibrium",
]

_I3 = np.eye(3)

#: Largest Newton step [m, or rad × node radius] taken at once; longer steps are scaled down.
MAX_STEP = 0.02

#: Up to this many platforms the tangent stiffness is one dense (6n, 6n) matrix solved by one
#: LAPACK call; above, its blocks are swept (linear in n).
DENSE_MAX_PLATFORMS = 16


def exp3_batch(w: np.ndarray) -> np.ndarray:
    """Rotation matrices (m, 3, 3) of rotation vectors (m, 3) [rad] (Rodrigues, series near 0)."""
    if w.shape[0] <= 32:  # a few: Pinocchio's own is faster than the vectorized formula
        return np.array([pin.exp3(x) for x in w]).reshape(-1, 3, 3)
    th2 = (w * w).sum(axis=1)
    small = th2 < 1e-8
    th = np.sqrt(th2)
    safe = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - th2 / 24.0, (1.0 - np.cos(safe)) / np.where(small, 1.0, th2))
    K = skew(w)
    return _I3 + a[:, None, None] * K + b[:, None, None] * np.matmul(K, K)


@dataclass(frozen=True)
class ElasticTerms:
    """The potential's first and second derivatives at one pose (plates 1..n, see module doc).

    Attributes:
        gradient: (n, 6) ``∂V/∂(δp, δθ)`` of plates 1..n [N, N·m] (zero at an equilibrium).
        hessian: (6n, 6n) the Hessian (up to :data:`DENSE_MAX_PLATFORMS` platforms), else None.
        diag, off: above that, its blocks: (n, 6, 6) of plates 1..n and (n-1, 6, 6) of
            (plate m, plate m+1), m = 1..n-1 (None when ``hessian`` is given).
        symmetric: False when an EE moment makes the tangent unsymmetric.
        tension: (n, 6) spring tensions ``k (L - L0)`` [N]; lengths: (n, 6) [m].
        lines: (n, 6, 6) each leg's line ``[u, r × u]`` at its top plate's origin (world axes,
            ``r`` the top joint from that origin): the rows of ``dL/d(δp, δθ)`` of the top plate.
        base_gradient: (6,) ``∂V/∂(δp, δθ)`` of plate 0 [N, N·m]: the wrench a support holding
            it supplies at equilibrium (world axes, moment about its origin).
    """

    gradient: np.ndarray
    hessian: np.ndarray | None
    diag: np.ndarray | None
    off: np.ndarray | None
    symmetric: bool
    tension: np.ndarray
    lengths: np.ndarray
    lines: np.ndarray
    base_gradient: np.ndarray


_SKEW_INDEX = np.array([0, 2, 1, 2, 0, 0, 1, 0, 0])  # skew(v).ravel() = v[_SKEW_INDEX] * _SKEW_SIGN
_SKEW_SIGN = np.array([0.0, -1.0, 1.0, 1.0, 0.0, -1.0, -1.0, 1.0, 0.0])


@dataclass(frozen=True)
class _Design:
    """What :func:`elastic_terms` needs of one model, computed once per geometry.

    template: (n, 6, 3, 12) ``∂d/∂(bottom, top plate)`` with its translation blocks ``-I, I``
    filled; weights: (2, 1, 1) the motor's and the shaft's weight [N] at the bottom and top
    joints; lever: ``λ = m_m c_m - m_s c_s`` [kg·m].
    """

    template: np.ndarray
    weights: np.ndarray
    lever: float


_DESIGNS: dict[int, tuple[weakref.ref, _Design]] = {}


def _design(am: AssemblerModel) -> _Design:
    geo = am.geometry
    hit = _DESIGNS.get(id(geo))
    if hit is not None and hit[0]() is geo:
        return hit[1]
    leg, g, n = am.config.leg, am.config.gravity, am.n
    template = np.zeros((n, 6, 3, 12))
    template[..., 0:3] = -_I3
    template[..., 6:9] = _I3
    design = _Design(
        template,
        np.array([leg.motor_mass * g, leg.shaft_mass * g]).reshape(2, 1, 1),
        leg.motor_mass * leg.motor_com - leg.shaft_mass * leg.shaft_com,
    )
    if len(_DESIGNS) > 64:
        _DESIGNS.clear()
    _DESIGNS[id(geo)] = (weakref.ref(geo), design)
    return design


def _platform_hessians(u, inv_L, T, D, stiffness: float, lever: float, g: float) -> np.ndarray:
    """(n, 12, 12) ``Σ Dᵀ H_d D`` over each platform's legs, ``H_d = c1 u uᵀ + c2 I + c3 (a uᵀ
    + u aᵀ)`` (a = -g e_z) and ``D`` (n, 6, 3, 12) each leg's ``∂d/∂(bottom, top plate)``.

    With the leg's line ``l = Dᵀ u`` and ``m = Dᵀ e_z`` (both 12-vectors) it is ``Σ (c1 l -
    g c3 m) lᵀ - g c3 l mᵀ + c2 DᵀD``: one product of stacked (30 × 12) factors per platform.
    """
    n = u.shape[0]
    c3 = lever * inv_L * inv_L
    au = -g * u[..., 2]
    c2 = T * inv_L + c3 * au
    c1 = stiffness - T * inv_L - 3.0 * c3 * au
    line = np.matmul(u[..., None, :], D)[..., 0, :]  # (n, 6, 12)
    m = D[..., 2, :]
    gc3 = (-g * c3)[..., None]
    left = np.concatenate([c1[..., None] * line + gc3 * m, gc3 * line, (c2[..., None, None] * D).reshape(n, 18, 12)], 1)
    right = np.concatenate([line, m, D.reshape(n, 18, 12)], axis=1)
    return np.matmul(np.swapaxes(left, 1, 2), right)


def _joint_gradient(am: AssemblerModel, u, r, r_u, along, across) -> tuple[np.ndarray, np.ndarray]:
    """The gradient at the joints, ``f`` (2, n, 6, 3): bottom ``-G - m_m a``, top ``G - m_s a``
    with ``G = along u - across a`` (a = -g e_z), and the plates' gradient (n+1, 6) from them,
    their moments ``r × f`` (``r_u`` = r × u) and the plates' weight, plate 0's included (the
    payload's is the caller's)."""
    leg, g, n = am.config.leg, am.config.gravity, am.n
    f = np.empty((2, n, 6, 3))
    f[1] = along[..., None] * u
    f[1, ..., 2] += g * (across + leg.shaft_mass)
    f[0] = -f[1]
    f[0, ..., 2] += g * (leg.motor_mass + leg.shaft_mass)
    r_z = np.stack([r[..., 1], -r[..., 0], np.zeros_like(r[..., 0])], axis=-1)  # r × e_z
    m_top = along[..., None] * r_u[1] + (g * (across + leg.shaft_mass))[..., None] * r_z[1]
    m_bottom = -along[..., None] * r_u[0] + (g * (leg.motor_mass - across))[..., None] * r_z[0]
    grad = np.zeros((n + 1, 6))
    grad[1:, :3] = f[1].sum(axis=1)
    grad[:, 2] += am.config.plate.mass * g  # plate 0 too: its row is what its support supplies
    grad[1:, 3:] = m_top.sum(axis=1)
    grad[:-1, :3] += f[0].sum(axis=1)
    grad[:-1, 3:] += m_bottom.sum(axis=1)
    return f, grad


def elastic_terms(
    am: AssemblerModel,
    R: np.ndarray,
    p: np.ndarray,
    rest: np.ndarray | None,
    stiffness: float,
    wrench: np.ndarray | None = None,
    hessian: bool = True,
) -> ElasticTerms:
    """Gradient and Hessian of the total potential (module doc) at plates ``R`` (n+1, 3, 3),
    ``p`` (n+1, 3) [m] for unloaded leg lengths ``rest`` (n, 6) [m] (None: the lengths here).

    Every leg at once: with ``D`` (3 × 12) the map of the two plates' motions to the leg's ``d``,
    a platform's Hessian is ``Σ Dᵀ H_d D`` (:func:`_platform_hessians`) plus the charts' terms.

    Args:
        stiffness: each leg's axial stiffness [N/m].
        wrench: (6,) ``[f, m]`` on the EE [N, N·m], world axes, moment about the EE origin.
        hessian: False skips the Hessian.
    """
    cfg, n, des = am.config, am.n, _design(am)
    g = cfg.gravity
    rb = np.matmul(am.geometry.bottom_in_plate, np.swapaxes(R[:-1], 1, 2))  # bottom joints from plate j's origin
    rt = np.matmul(am.geometry.top_in_plate, np.swapaxes(R[1:], 1, 2))  # top joints from plate j+1's origin
    r = np.stack((rb, rt))
    d = rt - rb + (p[1:] - p[:-1])[:, None, :]
    L = np.sqrt((d * d).sum(axis=2))
    inv_L = 1.0 / L
    u = d * inv_L[..., None]
    T = np.zeros_like(L) if rest is None else stiffness * (L - rest)
    lever = des.lever
    r_u = cross(r, u)  # r × u of the bottom and top joints
    F, grad = _joint_gradient(am, u, r, r_u, T + lever * (-g * u[..., 2]) * inv_L, lever * inv_L)
    r_pay = R[n, :, 2] * cfg.payload.offset
    w_pay = cfg.payload.mass * g  # the payload's weight, along -z
    grad[n, 2] += w_pay
    grad[n, 3:5] += (w_pay * r_pay[1], -w_pay * r_pay[0])  # r × (0, 0, w)
    if wrench is not None:
        grad[n] -= wrench
    lines = np.concatenate([u, r_u[1]], axis=2)
    symmetric = wrench is None or not np.any(wrench[3:])
    if not hessian:
        return ElasticTerms(grad[1:], None, None, None, symmetric, T, L, lines, grad[0])
    S = (r[..., _SKEW_INDEX] * _SKEW_SIGN).reshape(2, n, 6, 3, 3)  # r× of every joint
    D = des.template.copy()
    D[..., 3:6] = S[0]
    D[..., 9:12] = -S[1]
    H12 = _platform_hessians(u, inv_L, T, D, stiffness, lever, g)
    M = np.matmul(np.swapaxes(F, -1, -2), r)  # Σ f ⊗ r over each plate's joints
    charts = M + np.swapaxes(M, -1, -2)
    charts.reshape(2, n, 9)[..., ::4] -= 2.0 * (M[..., 0, 0] + M[..., 1, 1] + M[..., 2, 2])[..., None]
    H12[:, 3:6, 3:6] += 0.5 * charts[0]  # plate 0's own (platform 0) is dropped with its rows
    H12[:, 9:, 9:] += 0.5 * charts[1]
    ee = np.zeros((3, 3))  # the payload's ½ (f rᵀ + r fᵀ) - (f·r) I, f = (0, 0, w)
    ee[2] += 0.5 * w_pay * r_pay
    ee[:, 2] += 0.5 * w_pay * r_pay
    ee.flat[::4] -= w_pay * r_pay[2]
    if wrench is not None and not symmetric:  # a constant world moment on a rotating plate: -½ [m]×
        ee = ee - 0.5 * skew(wrench[3:])
    return _assembled(grad, H12, ee, symmetric, T, L, lines)


def _assembled(grad, H12, ee, symmetric: bool, T, L, lines) -> ElasticTerms:
    """The terms with the platforms' (n, 12, 12) Hessians and the EE's rotation-block term
    ``ee`` (3, 3) put together: dense up to :data:`DENSE_MAX_PLATFORMS`, else as blocks;
    ``grad`` (n+1, 6) holds plate 0's row too."""
    n = H12.shape[0]
    base, grad = grad[0], grad[1:]
    if n <= DENSE_MAX_PLATFORMS:
        full = np.zeros((6 * n, 6 * n))
        full[:6, :6] = H12[0, 6:, 6:]  # plate 0 is fixed: platform 0 adds only to plate 1
        for j in range(1, n):
            full[6 * j - 6 : 6 * j + 6, 6 * j - 6 : 6 * j + 6] += H12[j]
        full[-3:, -3:] += ee
        return ElasticTerms(grad, full, None, None, symmetric, T, L, lines, base)
    diag = H12[:, 6:, 6:].copy()
    diag[:-1] += H12[1:, :6, :6]
    diag[-1, 3:, 3:] += ee
    return ElasticTerms(grad, None, diag, H12[1:, :6, 6:].copy(), symmetric, T, L, lines, base)


@dataclass(frozen=True)
class Equilibrium:
    """Outcome of :func:`solve_equilibrium`.

    Attributes:
        R, p: plate rotations (n+1, 3, 3) and positions (n+1, 3) at the end.
        terms: the derivatives at the last evaluated pose (at most one tiny step before ``R, p``).
        compliance: (6, 6) the EE's condensed compliance there (the EE block of ``H⁻¹``).
        stable: the tangent stiffness there is positive definite.
        iterations: Newton steps taken.
        step: size of the last Newton step [m] (rotations times the node radius): the
            distance left to the equilibrium.
        message: None when converged, else why not.
    """

    R: np.ndarray
    p: np.ndarray
    terms: ElasticTerms
    compliance: np.ndarray
    stable: bool
    iterations: int
    step: float
    message: str | None


def line_conditions(lines: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverses (n, 6, 6) and 1-norm condition numbers (n,) of the platforms' leg-line matrices
    (rows ``[u, r × u]`` per leg, world axes at the top plate's origin: ``dL/d(δp, δθ)``), by
    :func:`~assembler_pin.statics.closed_form.line_conditions` (the statics' condition number, with
    the lines in world axes). A singular matrix gives NaN inverses and an infinite condition
    number."""
    inverse, cond = closed_form.line_conditions(lines)
    return inverse, np.where(np.isfinite(cond), cond, np.inf)


def _singular(terms: ElasticTerms, limit: float) -> str | None:
    cond = line_conditions(terms.lines)[1]
    if cond.max() <= limit:
        return None
    j = int(np.argmax(cond))
    return (
        f"platform {j} is at a singular configuration (condition number {cond[j]:.3g} > {limit:.0g}): "
        "its stiffness is not defined"
    )


def _step_size(x: np.ndarray, scale: float) -> float:
    return max(float(np.abs(x[:, :3]).max()), scale * float(np.abs(x[:, 3:]).max()))


def solve_equilibrium(
    am: AssemblerModel,
    R: np.ndarray,
    p: np.ndarray,
    rest: np.ndarray | None,
    stiffness: float,
    wrench: np.ndarray | None = None,
    tol: float = 1e-12,
    max_iterations: int = 30,
    condition_limit: float | None = None,
    hold_ee: bool = False,
) -> Equilibrium:
    """Newton's method on the plate poses for ``∇V = 0`` from the start ``R, p`` (plate 0 stays;
    with ``hold_ee`` the EE plate n stays too and plates 1..n-1 move: both ends held).

    Converged when the Newton step is at most ``tol`` [m] (rotations scaled by the node
    radius); that last step is taken and the terms (forces, gradient) are those of the pose it
    lands on, never of the start, whatever ``tol``; steps longer than :data:`MAX_STEP` are
    shortened. Whether the answer is stable is
    reported (``stable``), not required. With ``condition_limit``, a start whose leg lines are
    worse conditioned (:func:`line_conditions`) is refused before any step (a singular pose).
    ``rest`` None commands the lengths of the start.
    """
    R, p = R.copy(), p.copy()
    scale = am.config.plate.node_radius
    message = None
    size = math.inf
    C, stable = np.full((6, 6), np.nan), False
    for it in range(max_iterations + 1):
        terms = elastic_terms(am, R, p, rest, stiffness, wrench)
        if rest is None:
            rest = terms.lengths
        if it == 0 and condition_limit is not None:
            message = _singular(terms, condition_limit)
            if message is not None:
                break
        try:
            x, C, stable = held_solve(terms) if hold_ee else tangent_solve(terms, -terms.gradient)
        except np.linalg.LinAlgError:
            message = "the tangent stiffness is singular (a mechanism: the legs do not hold the plates)"
            break
        size = _step_size(x, scale)
        if not math.isfinite(size):
            message = "the elastic equilibrium diverged (non-finite step)"
            break
        if size <= tol or it == max_iterations:
            if size > tol:
                message = (
                    f"the elastic equilibrium did not converge in {max_iterations} Newton steps "
                    f"(last step {size:.3g} m > {tol:.1g} m)"
                )
            else:  # the last step taken, and the forces, energy and gradient of where it lands
                p[1:] += x[:, :3]
                R[1:] = np.matmul(exp3_batch(x[:, 3:]), R[1:])
                terms = elastic_terms(am, R, p, rest, stiffness, wrench)
            return Equilibrium(R, p, terms, C, stable, it, size, message)
        if size > MAX_STEP:
            x = x * (MAX_STEP / size)
        p[1:] += x[:, :3]
        R[1:] = np.matmul(exp3_batch(x[:, 3:]), R[1:])
    return Equilibrium(R, p, terms, C, stable, it, size, message)
