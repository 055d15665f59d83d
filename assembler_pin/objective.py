"""The objective Ω of the paper (eq. 10) and the motion term: the one place they are written.

``Ω = w1·max|F| + w2·sqrt(Σ λ_k²)``: F the actuator forces [N], λ_k the plate-deviation
angles of paper eq. 9 [rad] (:func:`~assembler_pin.kinematics.plate_deviation`), w1 [1/N]
and w2 [1/rad] the weights (both 1 in the paper).

Along a motion the paper's "minimum required movement" adds ``w3·Σ (L_i - L_i^prev)²``
(L the leg lengths [m], w3 [1/m²]).

The optimizer (its smooth form carries max|F| in an epigraph variable ``s``, so it calls
:func:`omega` with ``s`` in place of max|F|), the carrier's Ω_c, the payload capacity's
optimizations and the ranking of the solver's runs all read Ω from here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    from .model import AssemblerModel
    from .state import StackState

__all__ = [
    "deviation_term",
    "deviation_term_gradient",
    "motion_cost",
    "motion_cost_gradient",
    "objective_value",
    "omega",
]


class _Motion(Protocol):
    """What the motion term reads of a :class:`~assembler_pin.optimize.MotionTerm`."""

    @property
    def previous_lengths(self) -> np.ndarray: ...

    @property
    def w3(self) -> float: ...


def deviation_term(plate_angles: np.ndarray) -> float:
    """``sqrt(Σ λ_k²)`` [rad] of the plate-deviation angles λ (n,) [rad]."""
    return float(np.sqrt(np.sum(np.square(plate_angles))))


def omega(max_abs_force: float, plate_angles: np.ndarray, w1: float = 1.0, w2: float = 1.0) -> float:
    """Ω = w1·max|F| + w2·sqrt(Σ λ_k²) (paper eq. 10).

    Args:
        max_abs_force: the largest actuator force magnitude [N] (or the smooth form's bound on it).
        plate_angles: λ_k, k = 1..n [rad] (paper eq. 9).
        w1, w2: weights [1/N], [1/rad].
    """
    return float(w1 * max_abs_force + w2 * deviation_term(plate_angles))


def motion_cost(lengths: np.ndarray, motion: _Motion | None) -> float:
    """``w3·Σ (L_i - L_i^prev)²`` of leg lengths (n, 6) [m]; 0 without a motion term."""
    if motion is None or motion.w3 == 0.0:
        return 0.0
    return float(motion.w3 * np.sum((lengths - motion.previous_lengths) ** 2))


def objective_value(
    am: AssemblerModel, state: StackState, w1: float = 1.0, w2: float = 1.0, motion: _Motion | None = None
) -> float:
    """Ω of a state (paper eq. 10), plus the motion term when ``motion`` is given."""
    from .kinematics import plate_deviation

    lam = plate_deviation(am, state.plates).angles
    return omega(state.max_abs_force, lam, w1, w2) + motion_cost(state.leg_lengths, motion)


def deviation_term_gradient(plate_angles: np.ndarray, d_plate_angles_sq: np.ndarray) -> np.ndarray:
    """Gradient of ``sqrt(Σ λ_k²)`` from the derivatives of λ_k² (n, m) → (m,); zero where
    every λ_k is 0 (its subgradient there)."""
    s = deviation_term(plate_angles)
    if s <= 1e-12:
        return np.zeros(d_plate_angles_sq.shape[-1])
    return (0.5 / s) * d_plate_angles_sq.sum(axis=0)


def motion_cost_gradient(lengths: np.ndarray, d_lengths: np.ndarray, motion: _Motion | None) -> np.ndarray:
    """Gradient of :func:`motion_cost` from the leg lengths (n, 6) and their derivatives
    (6n, m) → (m,)."""
    if motion is None or motion.w3 == 0.0:
        return np.zeros(d_lengths.shape[-1])
    step = (lengths - motion.previous_lengths).ravel()
    return 2.0 * motion.w3 * step @ d_lengths
