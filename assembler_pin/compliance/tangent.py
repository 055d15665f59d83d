"""Solving with the tangent stiffness of the elastic truss (:mod:`assembler_pin.compliance.elastic`).

The Hessian of the stack's potential is block-tridiagonal over the plates. Given dense (up to
:data:`~assembler_pin.compliance.elastic.DENSE_MAX_PLATFORMS` platforms) it is solved by one LAPACK call,
which also gives the EE's condensed compliance (the EE block of its inverse); given as blocks,
by one sweep from the base up (:func:`block_sweep`, linear in n). Units: the gradient rows are
``[N, N·m]`` of plates 1..n (world axes at each plate's origin), the steps ``[m, rad]``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg.lapack import dgesv, dposv, dpotrf

if TYPE_CHECKING:
    from .elastic import ElasticTerms

__all__ = ["block_sweep", "held_solve", "tangent_solve"]

_I6 = np.eye(6)


def tangent_solve(terms: ElasticTerms, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """Solve ``H x = rhs`` (rhs (n, 6)) with the tangent stiffness of ``terms``.

    Returns:
        x (n, 6); the EE's condensed compliance (6, 6) (the EE block of ``H⁻¹``); and whether
        the (symmetric part of the) tangent is positive definite: a stable equilibrium.

    Raises:
        numpy.linalg.LinAlgError: the tangent is singular.
    """
    n = rhs.shape[0]
    if terms.hessian is None:
        assert terms.diag is not None and terms.off is not None, "terms computed without a Hessian"
        x, S = block_sweep(terms.diag, terms.off, rhs)
        sym = 0.5 * (S + np.swapaxes(S, 1, 2))
        return x, np.linalg.inv(S[-1]), bool(np.linalg.eigvalsh(sym).min() > 0)
    H = terms.hessian
    b = np.zeros((6 * n, 7))
    b[:, 0] = rhs.ravel()
    b[-6:, 1:] = _I6
    info = 1
    if terms.symmetric:
        _, sol, info = dposv(H, b)  # Cholesky: succeeds exactly when H is positive definite
        stable = info == 0
    else:
        stable = dpotrf(0.5 * (H + H.T))[1] == 0
    if info != 0:
        _, _, sol, info = dgesv(H, b)
        if info != 0 or not np.all(np.isfinite(sol)):
            raise np.linalg.LinAlgError("singular tangent stiffness")
    return sol[:, 0].reshape(n, 6), sol[-6:, 1:], bool(stable)


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


def held_solve(terms: ElasticTerms) -> tuple[np.ndarray, np.ndarray, bool]:
    """The Newton step of plates 1..n-1 with the EE held (its row of the step zero); the
    compliance returned is plate n-1's."""
    n = terms.gradient.shape[0]
    if n == 1:
        return np.zeros((1, 6)), np.zeros((6, 6)), True
    H, diag, off = terms.hessian, terms.diag, terms.off
    free = replace(
        terms,
        gradient=terms.gradient[:-1],
        hessian=None if H is None else H[:-6, :-6],
        diag=None if diag is None else diag[:-1],
        off=None if off is None else off[:-1],
    )
    x, C, stable = tangent_solve(free, -free.gradient)
    return np.vstack([x, np.zeros((1, 6))]), C, stable
