"""The stack as an elastic truss: its total potential, gradient and Hessian over the plate poses,
and the Newton solve of its loaded equilibrium (used by :mod:`assembler_pin.ee_stiffness` and
:mod:`assembler_pin.compliance`).

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

The Hessian is block-tridiagonal over the plates (a leg joins plates j and j+1); it is solved
and condensed onto the EE plate by one sweep from the base up (linear in n).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .linalg import cross, skew
from .model import AssemblerModel

__all__ = ["ElasticTerms", "Equilibrium", "block_sweep", "elastic_terms", "exp3_batch", "solve_equilibrium"]

_I3 = np.eye(3)

#: Largest Newton step [m, or rad × node radius] taken at once; longer steps are scaled down.
MAX_STEP = 0.02


def exp3_batch(w: np.ndarray) -> np.ndarray:
    """Rotation matrices (m, 3, 3) of rotation vectors (m, 3) [rad] (Rodrigues, series near 0)."""
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
        diag: (n, 6, 6) Hessian blocks of plates 1..n; off: (n-1, 6, 6) the blocks
            (plate m, plate m+1), m = 1..n-1.
        tension: (n, 6) spring tensions ``k (L - L0)`` [N]; lengths: (n, 6) [m].
        lines: (n, 6, 6) each leg's line ``[u, r × u]`` at its top plate's origin (world axes,
            ``r`` the top joint from that origin): the rows of ``dL/d(δp, δθ)`` of the top plate.
    """

    gradient: np.ndarray
    diag: np.ndarray
    off: np.ndarray
    tension: np.ndarray
    lengths: np.ndarray
    lines: np.ndarray


def _sandwich(H: np.ndarray, Sa: np.ndarray, Sb: np.ndarray) -> np.ndarray:
    """Σ_legs Jaᵀ H Jb with ``J = [I, -S]`` (S = [r]×): (n, 6, 6) from (n, 6, 3, 3) arrays."""
    HSb = np.matmul(H, Sb)
    SaH = -np.swapaxes(np.matmul(H, Sa), -1, -2) if Sa is not Sb else -np.swapaxes(HSb, -1, -2)
    out = np.empty((H.shape[0], 6, 6))
    out[:, :3, :3] = H.sum(axis=1)
    out[:, :3, 3:] = -HSb.sum(axis=1)
    out[:, 3:, :3] = SaH.sum(axis=1)
    out[:, 3:, 3:] = -np.matmul(Sa, HSb).sum(axis=1)
    return out


def _chart(f: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Σ over the points' last-but-one axis of ``sym(f rᵀ) - (f·r) I`` (the rotation block's
    second-order term), (n, m, 3) arrays → (n, 3, 3)."""
    M = np.matmul(np.swapaxes(f, -1, -2), r)  # Σ f ⊗ r
    tr = M[:, 0, 0] + M[:, 1, 1] + M[:, 2, 2]
    return 0.5 * (M + np.swapaxes(M, -1, -2)) - tr[:, None, None] * _I3


def elastic_terms(
    am: AssemblerModel,
    R: np.ndarray,
    p: np.ndarray,
    rest: np.ndarray,
    stiffness: float,
    wrench: np.ndarray | None = None,
    hessian: bool = True,
) -> ElasticTerms:
    """Gradient and Hessian of the total potential (module doc) at plates ``R`` (n+1, 3, 3),
    ``p`` (n+1, 3) [m] for unloaded leg lengths ``rest`` (n, 6) [m].

    Args:
        stiffness: each leg's axial stiffness [N/m].
        wrench: (6,) ``[f, m]`` on the EE [N, N·m], world axes, moment about the EE origin.
        hessian: False skips the Hessian (``diag``/``off`` are then empty).
    """
    cfg, geo, n = am.config, am.geometry, am.n
    leg = cfg.leg
    a = np.array([0.0, 0.0, -cfg.gravity])
    rb = np.matmul(geo.bottom_in_plate, np.swapaxes(R[:-1], 1, 2))  # bottom joints from plate j's origin
    rt = np.matmul(geo.top_in_plate, np.swapaxes(R[1:], 1, 2))  # top joints from plate j+1's origin
    d = rt - rb + (p[1:] - p[:-1])[:, None, :]
    L = np.sqrt((d * d).sum(axis=2))
    u = d / L[..., None]
    T = stiffness * (L - rest)
    lam = leg.motor_mass * leg.motor_com - leg.shaft_mass * leg.shaft_com
    au = u @ a
    G = T[..., None] * u - (lam / L)[..., None] * (a - au[..., None] * u)
    f_top = G - leg.shaft_mass * a
    f_bottom = -G - leg.motor_mass * a
    grad = np.zeros((n + 1, 6))
    grad[1:, :3] = f_top.sum(axis=1) - cfg.plate.mass * a
    grad[1:, 3:] = cross(rt, f_top).sum(axis=1)
    grad[:-1, :3] += f_bottom.sum(axis=1)
    grad[:-1, 3:] += cross(rb, f_bottom).sum(axis=1)
    r_pay = R[n, :, 2] * cfg.payload.offset
    f_pay = -cfg.payload.mass * a
    grad[n, :3] += f_pay
    grad[n, 3:] += cross(r_pay, f_pay)
    if wrench is not None:
        grad[n] -= wrench
    lines = np.concatenate([u, cross(rt, u)], axis=2)
    if not hessian:
        return ElasticTerms(grad[1:], np.empty((0, 6, 6)), np.empty((0, 6, 6)), T, L, lines)
    uu = u[..., :, None] * u[..., None, :]
    au_t = a[:, None] * u[..., None, :]  # a uᵀ
    c2 = T / L + lam * au / L**2
    c1 = stiffness - T / L - 3.0 * lam * au / L**2
    H = (
        c1[..., None, None] * uu
        + c2[..., None, None] * _I3
        + (lam / L**2)[..., None, None] * (au_t + np.swapaxes(au_t, -1, -2))
    )
    St, Sb = skew(rt), skew(rb)
    diag = _sandwich(H, St, St)  # top plates (1..n)
    diag[:, 3:, 3:] += _chart(f_top, rt)
    diag[:-1] += _sandwich(H[1:], Sb[1:], Sb[1:])  # bottom plates of SP 1..n-1
    diag[:-1, 3:, 3:] += _chart(f_bottom[1:], rb[1:])
    diag[-1, 3:, 3:] += _chart(f_pay[None, None, :], r_pay[None, None, :])[0]
    if wrench is not None:  # a constant world moment on a rotating plate: -½ [m]× (not symmetric)
        diag[-1, 3:, 3:] -= 0.5 * skew(wrench[3:])
    off = -_sandwich(H[1:], Sb[1:], St[1:])  # rows: plate j (bottom of SP j), columns: plate j+1
    return ElasticTerms(grad[1:], diag, off, T, L, lines)


def block_sweep(diag: np.ndarray, off: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Solve the block-tridiagonal ``H x = rhs`` (blocks ``diag`` (n, 6, 6), upper ``off``
    (n-1, 6, 6), lower ``offᵀ``) by one sweep from plate 1 up, then back.

    Returns:
        x (n, 6), and the Schur complements S (n, 6, 6): ``S[m]`` is the stiffness of plate m+1
        with plates 1..m condensed out, so ``S[-1]`` is the EE's condensed stiffness.

    Raises:
        numpy.linalg.LinAlgError: a Schur complement is exactly singular.
    """
    n = diag.shape[0]
    S = np.empty_like(diag)
    S[0] = diag[0]
    y = rhs.copy()
    factors = []
    for m in range(1, n):
        X = np.linalg.solve(S[m - 1], np.concatenate([off[m - 1], y[m - 1, :, None]], axis=1))
        factors.append(X)
        lower = off[m - 1].T
        S[m] = diag[m] - lower @ X[:, :6]
        y[m] -= lower @ X[:, 6]
    x = np.empty_like(rhs)
    x[-1] = np.linalg.solve(S[-1], y[-1])
    for m in range(n - 2, -1, -1):
        X = factors[m]
        x[m] = X[:, 6] - X[:, :6] @ x[m + 1]
    return x, S


@dataclass(frozen=True)
class Equilibrium:
    """Outcome of :func:`solve_equilibrium`.

    Attributes:
        R, p: plate rotations (n+1, 3, 3) and positions (n+1, 3) at the end.
        terms: the derivatives at the last evaluated pose (at most one tiny step before ``R, p``).
        schur: (n, 6, 6) the Schur complements there (``schur[-1]``: the EE's stiffness).
        iterations: Newton steps taken.
        step: size of the last Newton step [m] (rotations times the node radius): the
            distance left to the equilibrium.
        message: None when converged, else why not.
    """

    R: np.ndarray
    p: np.ndarray
    terms: ElasticTerms
    schur: np.ndarray
    iterations: int
    step: float
    message: str | None


def _step_size(x: np.ndarray, scale: float) -> float:
    return max(float(np.abs(x[:, :3]).max()), scale * float(np.abs(x[:, 3:]).max()))


def solve_equilibrium(
    am: AssemblerModel,
    R: np.ndarray,
    p: np.ndarray,
    rest: np.ndarray,
    stiffness: float,
    wrench: np.ndarray | None = None,
    tol: float = 1e-12,
    max_iterations: int = 30,
) -> Equilibrium:
    """Newton's method on the plate poses for ``∇V = 0`` from the start ``R, p`` (plate 0 stays).

    Converged when the Newton step is at most ``tol`` [m] (rotations scaled by the node
    radius); steps longer than :data:`MAX_STEP` are shortened. The stability of the answer
    (a positive definite Hessian) is the caller's to check on ``schur``.
    """
    R, p = R.copy(), p.copy()
    scale = am.config.plate.node_radius
    message = None
    size = math.inf
    S = np.full((am.n, 6, 6), np.nan)
    for it in range(max_iterations + 1):
        terms = elastic_terms(am, R, p, rest, stiffness, wrench)
        try:
            x, S = block_sweep(terms.diag, terms.off, -terms.gradient)
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
            else:
                p[1:] += x[:, :3]
                R[1:] = np.matmul(exp3_batch(x[:, 3:]), R[1:])
            return Equilibrium(R, p, terms, S, it, size, message)
        if size > MAX_STEP:
            x = x * (MAX_STEP / size)
        p[1:] += x[:, :3]
        R[1:] = np.matmul(exp3_batch(x[:, 3:]), R[1:])
    return Equilibrium(R, p, terms, S, it, size, message)
