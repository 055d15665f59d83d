"""The objective Ω of the paper (eq. 10) and the motion term: the one place they are written.

``Ω = w1·max|F| + w2·sqrt(Σ λ_k²)``: F the actuator forces [N], λ_k the plate-deviation
angles of paper eq. 9 [rad] (:func:`~assembler_pin.kinematics.plate_deviation`), w1 [1/N]
and w2 [1/rad] the weights (both 1 in the paper).

Along a motion the paper's "minimum required movement" adds ``w3·Σ (L_i - L_i^prev)²``
(L the leg lengths [m], w3 [1/m²]).

The optimizer's objectives (``OptimizeOptions.objective``, :data:`~assembler_pin.config.choices.OBJECTIVES`):

* ``"force"`` — Ω (the default, the paper's);
* ``"sag"`` — ``sag / sag_ref``: the EE's linear sag under the pose's own load
  (:func:`~assembler_pin.compliance.loaded.sag_and_gradient`) over the reference sag;
* ``"weighted"`` — ``Ω + w·sag / sag_ref``, ``w = sag_weight``.

``sag_ref`` is the sag of the model's home pose (:func:`sag_reference`): it depends on the
stack (platforms, stiffness, masses, payload) and on nothing a solve chooses, so every start
and every goal of one model is scored on the same scale, and the sag term is dimensionless
(``w`` is in Ω's units: with w1 = 1/N, ``w = 1`` weighs one home-pose sag like one newton
of max|F|). On the default stack the scenario optima sag 10–40 home sags and their max|F|
is 45–125 N, so ``w = 1`` gives the two terms the same order. The motion term adds to each.

The optimizer (its smooth form carries max|F| in an epigraph variable ``s``, so it calls
:func:`omega` with ``s`` in place of max|F|), the carrier's Ω_c, the payload capacity's
optimizations and the ranking of the solver's runs all read Ω from here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

import numpy as np

from ..exceptions import OptionsError
from ..kinematics import plate_arrays, plate_deviation
from ..statics.closed_form import equilibrium
from ..statics.derivatives import pose_values
from .sag import equilibrium_sag, linear_sag

if TYPE_CHECKING:
    from ..model.assembler import AssemblerModel
    from ..state import StackState

__all__ = [
    "SagObjective",
    "deviation_term",
    "deviation_term_gradient",
    "motion_cost",
    "motion_cost_gradient",
    "objective_value",
    "omega",
    "sag_reference",
    "state_sag",
    "state_score",
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


def sag_reference(am: AssemblerModel) -> float:
    """The reference sag [m] of the sag objectives: the EE's linear sag at the model's home pose.

    Raises:
        OptionsError: the home pose does not sag (no load on the legs): no sag objective.
    """
    sag = linear_sag(pose_values(am, plate_arrays(am, am.home)), float(am.config.leg.stiffness))[0]
    if not (np.isfinite(sag) and sag > 0):
        raise OptionsError(f"the home pose has no sag ({sag!r} m): the stack carries no load, no sag objective")
    return sag


class SagObjective:
    """The objective of ``OptimizeOptions.objective`` from its terms: Ω (or the smooth form's
    ``w1·s + w2·sqrt(Σλ²)``) and the EE sag [m].

    Args:
        kind: ``"force"``, ``"sag"`` or ``"weighted"``; sag_weight: w (no unit);
        sag_ref: the reference sag [m] (:func:`sag_reference`; unused for ``"force"``).
    """

    def __init__(self, kind: str, sag_weight: float = 1.0, sag_ref: float = 1.0) -> None:
        self.kind, self.sag_weight, self.sag_ref = kind, float(sag_weight), float(sag_ref)

    @property
    def needs_sag(self) -> bool:
        """The objective reads the sag."""
        return self.kind != "force"

    @property
    def omega_weight(self) -> float:
        """The factor on Ω: 1, or 0 for ``"sag"``."""
        return 0.0 if self.kind == "sag" else 1.0

    @property
    def sag_factor(self) -> float:
        """The factor on the sag [1/m]: ``0``, ``1/sag_ref`` or ``w/sag_ref``."""
        return {"force": 0.0, "sag": 1.0, "weighted": self.sag_weight}[self.kind] / self.sag_ref

    def value(self, omega_value: float, sag: float) -> float:
        """The objective from Ω and the sag [m] (the sag is not read for ``"force"``)."""
        value = self.omega_weight * omega_value
        return value + self.sag_factor * sag if self.needs_sag else value

    def gradient(self, d_omega: np.ndarray, d_sag: np.ndarray | None) -> np.ndarray:
        """Its gradient from those of Ω and of the sag (same shape; ``d_sag`` None for ``"force"``)."""
        grad = self.omega_weight * d_omega
        return grad + self.sag_factor * d_sag if self.needs_sag and d_sag is not None else grad


def state_score(
    am: AssemblerModel,
    state: StackState,
    objective: SagObjective,
    w1: float = 1.0,
    w2: float = 1.0,
    motion: _Motion | None = None,
) -> float:
    """The objective of a state (with the motion term): Ω for ``"force"``
    (:func:`objective_value`), else with its linear EE sag (inf where none is defined)."""
    omega_value = objective_value(am, state, w1, w2)
    sag = state_sag(am, state) if objective.needs_sag else 0.0
    return objective.value(omega_value, sag) + motion_cost(state.leg_lengths, motion)


def state_sag(am: AssemblerModel, state: StackState) -> float:
    """The EE's linear sag [m] of a state's plates (inf when a platform is singular), from the
    closed-form equilibrium of its plates (the pass of :func:`~assembler_pin.statics.derivatives.pose_values`
    without the angles the sag does not read)."""
    plates = state.plates
    eq, _ = equilibrium(am, plates.R, plates.p)
    sag = equilibrium_sag(eq, plates.p[-1], float(am.config.leg.stiffness))[0]
    return sag if np.isfinite(sag) else float("inf")
