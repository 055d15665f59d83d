"""The hexapod as one elastic structure: every stack's legs as springs, every plate and the
body rigid, solved by Newton's method on the whole structure's potential.

Unknowns. The body's motion ``(δp, δθ)`` [m, rad] (world axes, at the body's centre of mass
``c``), and each stack's plates 1..n-1 in the charts of
:mod:`assembler_pin.compliance.elastic` (``p ← p + δp``, ``R ← exp3(δθ) R``, world axes at the
plate's origin); a foot that is free (lifted) adds its plate 0. Each stack's EE plate is fixed
to the body: it moves as the body's own point, its origin ``p_n`` by
``δp + (exp3(δθ) − I)(p_n − c)``.

Potential and derivatives. Each stack's potential, gradient and Hessian over its plates 1..n
are :func:`~assembler_pin.compliance.elastic.elastic_terms` (legs ``½ k (L − L0)²``, the
plates', motors' and shafts' weights, the tool payload); the body adds ``m g z_c``. With
``r = p_n − c`` and ``J = [[I, −r×], [0, I]]`` the EE plate's rows reach the body as
``Jᵀ g`` (its force, and its moment carried to ``c``: ``m + r × f``) and ``Jᵀ H J`` plus the
chart's second-order term ``sym(f rᵀ) − (f·r) I`` in the rotation block (``f`` the EE plate's
force row): the Hessian is exact, so Newton converges quadratically to the exact
large-deflection equilibrium. A free foot's rows of the Hessian (its own block and its
coupling with plate 1) are central differences of the exact gradient, symmetrized.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from ..common.linalg import skew
from ..compliance.elastic import MAX_STEP, ElasticTerms, elastic_terms, exp3_batch
from ..kinematics.legs import leg_points
from ..model.assembler import AssemblerModel

__all__ = ["StructureEquilibrium", "StructureState", "leg_jacobian", "solve_structure", "structure_terms"]

#: Step of the central differences of a free foot's rows [m, rad].
_FD_STEP = 1e-6


@dataclass
class StructureState:
    """Plate poses of every stack, ``R`` (k, n+1, 3, 3) and ``p`` (k, n+1, 3) [m], and the
    body's centre of mass ``com`` (3,) [m] (world)."""

    R: np.ndarray
    p: np.ndarray
    com: np.ndarray

    def copy(self) -> StructureState:
        return StructureState(self.R.copy(), self.p.copy(), self.com.copy())


@dataclass(frozen=True)
class StructureTerms:
    """Gradient (m,) and Hessian (m, m) over the unknowns (module doc), and every stack's terms."""

    gradient: np.ndarray
    hessian: np.ndarray
    stacks: list[ElasticTerms]


def _layout(k: int, n: int, free: np.ndarray) -> list[np.ndarray]:
    """Per stack the indices of its unknowns: plate 0 (if free) then plates 1..n-1."""
    out, at = [], 6
    for i in range(k):
        size = 6 * (n - 1 + int(free[i]))
        out.append(np.arange(at, at + size))
        at += size
    return out


def _foot_rows(am: AssemblerModel, R: np.ndarray, p: np.ndarray, rest: np.ndarray, stiffness: float):
    """(6, 6) Hessian block of plate 0 and (6, 6) coupling of plate 1 with plate 0 (rows plate 1),
    by central differences of the exact gradient (module doc)."""
    cols0, cols1 = np.zeros((6, 6)), np.zeros((6, 6))
    for j in range(6):
        grads = []
        for sign in (1.0, -1.0):
            Rj, pj = R.copy(), p.copy()
            if j < 3:
                pj[0, j] += sign * _FD_STEP
            else:
                Rj[0] = exp3_batch(sign * _FD_STEP * np.eye(3)[j - 3][None])[0] @ R[0]
            t = elastic_terms(am, Rj, pj, rest, stiffness, hessian=False)
            grads.append((t.base_gradient, t.gradient[0]))
        cols0[:, j] = (grads[0][0] - grads[1][0]) / (2 * _FD_STEP)
        cols1[:, j] = (grads[0][1] - grads[1][1]) / (2 * _FD_STEP)
    return 0.5 * (cols0 + cols0.T), cols1


def structure_terms(
    am: AssemblerModel, state: StructureState, rest: np.ndarray, body_mass: float, free: np.ndarray
) -> StructureTerms:
    """The whole structure's gradient and Hessian at ``state`` (module doc) for unloaded leg
    lengths ``rest`` (k, n, 6) [m] and free (lifted) feet ``free`` (k,) bool."""
    k, n = rest.shape[0], am.n
    stiffness = float(am.config.leg.stiffness)
    idx = _layout(k, n, free)
    size = 6 + sum(len(i) for i in idx)
    g, H = np.zeros(size), np.zeros((size, size))
    g[2] += body_mass * am.config.gravity
    body = np.arange(6)
    terms = []
    for i in range(k):
        t = elastic_terms(am, state.R[i], state.p[i], rest[i], stiffness)
        terms.append(t)
        assert t.hessian is not None, "dense Hessians up to DENSE_MAX_PLATFORMS platforms"
        r = state.p[i, -1] - state.com
        J = np.eye(6)
        J[:3, 3:] = -skew(r)
        f = t.gradient[-1, :3]
        inner = idx[i][6:] if free[i] else idx[i]  # plates 1..n-1
        Hs = t.hessian
        g[body] += J.T @ t.gradient[-1]
        H[np.ix_(body, body)] += J.T @ Hs[-6:, -6:] @ J
        H[3:6, 3:6] += 0.5 * (np.outer(f, r) + np.outer(r, f)) - float(f @ r) * np.eye(3)
        if n > 1:
            g[inner] += t.gradient[:-1].ravel()
            H[np.ix_(inner, inner)] += Hs[:-6, :-6]
            H[np.ix_(inner, body)] += Hs[:-6, -6:] @ J
            H[np.ix_(body, inner)] += J.T @ Hs[-6:, :-6]
        if free[i]:
            foot = idx[i][:6]
            H00, H10 = _foot_rows(am, state.R[i], state.p[i], rest[i], stiffness)
            g[foot] += t.base_gradient
            H[np.ix_(foot, foot)] += H00
            plate1 = inner[:6] if n > 1 else body
            M = H10 if n > 1 else J.T @ H10
            H[np.ix_(plate1, foot)] += M
            H[np.ix_(foot, plate1)] += M.T
    return StructureTerms(g, H, terms)


def leg_jacobian(am: AssemblerModel, state: StructureState, free: np.ndarray) -> np.ndarray:
    """(6nk, m) the derivative of every leg's length (stack by stack, platform by platform)
    over the unknowns (module doc): a leg's row is ``[u, r_t × u]`` on its top plate and
    ``−[u, r_b × u]`` on its bottom plate (``r`` its joint from the plate's origin, world
    axes), the EE plate's reaching the body through ``J``."""
    k, n = state.R.shape[0], am.n
    idx = _layout(k, n, free)
    size = 6 + sum(len(i) for i in idx)
    bottom, top = leg_points(am.geometry, state.R, state.p)  # (k, n, 6, 3)
    u = top - bottom
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    out = np.zeros((k, n, 6, size))
    for i in range(k):
        cols = {m: idx[i][6 * (m - 1 + int(free[i])) : 6 * (m + int(free[i]))] for m in range(1, n)}
        if free[i]:
            cols[0] = idx[i][:6]
        for j in range(n):
            for plate, joint, sign in ((j, bottom[i, j], -1.0), (j + 1, top[i, j], 1.0)):
                rows = sign * np.concatenate([u[i, j], np.cross(joint - state.p[i, plate], u[i, j])], axis=1)
                if plate == n:
                    r = state.p[i, n] - state.com
                    J = np.eye(6)
                    J[:3, 3:] = -skew(r)
                    out[i, j, :, :6] += rows @ J
                elif plate in cols:
                    out[i, j][:, cols[plate]] += rows
    return out.reshape(k * n * 6, size)


def _moved(am: AssemblerModel, state: StructureState, x: np.ndarray, free: np.ndarray) -> StructureState:
    """``state`` moved by the step ``x`` over the unknowns (module doc)."""
    out = state.copy()
    k, n = state.R.shape[0], am.n
    dp, dth = x[:3], x[3:6]
    turn = exp3_batch(dth[None])[0]
    r = state.p[:, -1] - state.com
    out.com = state.com + dp
    out.p[:, -1] = out.com + r @ turn.T
    out.R[:, -1] = np.matmul(turn, state.R[:, -1])
    for i, rows in enumerate(_layout(k, n, free)):
        steps = x[rows].reshape(-1, 6)
        plates = np.arange(0 if free[i] else 1, n)
        out.p[i, plates] += steps[:, :3]
        out.R[i, plates] = np.matmul(exp3_batch(steps[:, 3:]), state.R[i, plates])
    return out


@dataclass(frozen=True)
class StructureEquilibrium:
    """Outcome of :func:`solve_structure`: the end state, its terms, whether the tangent there
    is positive definite (``stable``), Newton steps taken, the last step's size [m] (rotations
    times the node radius) and None when converged, else why not."""

    state: StructureState
    terms: StructureTerms
    stable: bool
    iterations: int
    step: float
    message: str | None


def _step_size(x: np.ndarray, scale: float) -> float:
    blocks = x.reshape(-1, 6)
    return max(float(np.abs(blocks[:, :3]).max()), scale * float(np.abs(blocks[:, 3:]).max()))


def _newton_step(H: np.ndarray, g: np.ndarray) -> tuple[np.ndarray, bool]:
    """``−H⁻¹ g`` and whether ``H`` is positive definite (Cholesky, else LU)."""
    try:
        return -cho_solve(cho_factor(H), g), True
    except np.linalg.LinAlgError:
        return -np.linalg.solve(H, g), False


def solve_structure(
    am: AssemblerModel,
    start: StructureState,
    rest: np.ndarray,
    body_mass: float,
    free: np.ndarray,
    tol: float = 1e-11,
    max_iterations: int = 40,
) -> StructureEquilibrium:
    """Newton's method for the whole structure's ``∇V = 0`` from ``start`` (the feet not in
    ``free`` stay). Converged when the step is at most ``tol`` [m]; that step is taken and the
    terms are those of where it lands. Steps longer than
    :data:`~assembler_pin.compliance.elastic.MAX_STEP` are shortened."""
    state, scale = start.copy(), am.config.plate.node_radius
    size, stable, message = math.inf, False, None
    terms = structure_terms(am, state, rest, body_mass, free)
    for it in range(max_iterations + 1):
        try:
            x, stable = _newton_step(terms.hessian, terms.gradient)
        except np.linalg.LinAlgError:
            message = "the tangent stiffness is singular (a mechanism: the legs do not hold the structure)"
            return StructureEquilibrium(state, terms, False, it, math.inf, message)
        size = _step_size(x, scale)
        if not math.isfinite(size):
            return StructureEquilibrium(state, terms, False, it, size, "the equilibrium diverged (non-finite step)")
        if size <= tol:
            state = _moved(am, state, x, free)
            terms = structure_terms(am, state, rest, body_mass, free)
            return StructureEquilibrium(state, terms, stable, it, size, None)
        if it == max_iterations:
            break
        state = _moved(am, state, x * min(1.0, MAX_STEP / size), free)
        terms = structure_terms(am, state, rest, body_mass, free)
    message = f"the equilibrium did not converge in {max_iterations} Newton steps (last step {size:.3g} m)"
    return StructureEquilibrium(state, terms, stable, max_iterations, size, message)
