"""The outcome of an optimization: :class:`OptimizeResult`, the verdict on it, and the
result of a stack with nothing to optimize."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ..common.messages import binding, describe, one_line
from ..state import StackState

if TYPE_CHECKING:
    from .certificate import Optimality

__all__ = ["OptimizeResult"]


@dataclass
class OptimizeResult:
    """Outcome of an internal-pose optimization.

    Attributes:
        success: the returned state is valid: it meets every constraint, re-checked with the
            Pinocchio statics (and the motion step and sag limit where they apply).
        optimal: it is also an optimum: the first-order (KKT) conditions hold at it
            (:func:`~.certificate.optimality`, decided at the state, not by the solver's status).
        optimality: that check (residual, active rows, why not), None when the state is not valid.
        message: what happened, and why not when it failed or is not proven optimal.
        status, solver_message: scipy's own status code and message.
        iterations, evaluations, gradient_evaluations: solver counters.
        time_s: wall time of the optimization [s].
        initial, optimized: the starting state and the best feasible state found (the
            initial one when nothing better was found).
        objective_initial, objective_optimized: the objective of both states (Ω for the
            force objective, :mod:`assembler_pin.optimize.objective`).
        method: the method used (``slsqp``, ``paper``, ``ipopt``, or ``ipopt+slsqp`` for
            ``auto``'s IPOPT run finished by SLSQP); objective: the objective minimized
            (``OptimizeOptions.objective``).
        sag_initial, sag_optimized: the EE's linear sag of both states [m]
            (:func:`~assembler_pin.compliance.loaded.sag_and_gradient`; inf where a platform is singular).
    """

    success: bool
    message: str
    status: int
    solver_message: str
    iterations: int
    evaluations: int
    gradient_evaluations: int
    time_s: float
    initial: StackState
    optimized: StackState
    objective_initial: float
    objective_optimized: float
    method: str
    objective: str = "force"
    sag_initial: float | None = None
    sag_optimized: float | None = None
    optimal: bool = False
    optimality: Optimality | None = None

    def __repr__(self) -> str:
        return (
            f"OptimizeResult(success={self.success}, optimal={self.optimal}, method={self.method!r}, max|F| "
            f"{self.initial.max_abs_force:.3f} → {self.optimized.max_abs_force:.3f} N, "
            f"Ω {self.objective_initial:.3f} → {self.objective_optimized:.3f}, {self.iterations} iterations, "
            f"{1e3 * self.time_s:.1f} ms, "
            f"message={self.message!r})"
        )


class SolverResult(Protocol):
    """What is read of a solver result: scipy's ``OptimizeResult`` or :class:`StoppedEarly`."""

    x: np.ndarray
    message: str
    success: bool
    status: int
    nit: int


@dataclass
class StoppedEarly:
    """Stands in for scipy's result when the solve stopped early (no converged point)."""

    x: np.ndarray
    message: str
    success: bool = False
    status: int = -1
    nit: int = 0


def verdict(
    res: SolverResult, singular: str, converged: bool, final: StackState, chosen: StackState, initial: StackState
) -> tuple[bool, str]:
    """(success, message) of an optimization: success only when the solver converged to a
    point that meets every constraint (or was pulled back inside) and that point was kept."""
    stopped = singular or f"the optimizer stopped after {res.nit} iterations (status {res.status})"
    if not converged:
        if not chosen.feasible:
            return False, one_line(f"no feasible state found: {describe(binding(chosen.violations))}")
        if chosen is initial:
            return False, one_line(f"did not converge: {stopped}; the start is returned")
        return False, one_line(f"did not converge: {stopped}; the best feasible state met is returned")
    if not final.feasible:
        kept = "the best feasible state met is returned" if chosen.feasible else "no feasible state found"
        return False, one_line(f"{describe(binding(final.violations))} at the converged point; {kept}")
    return True, "converged"


def nothing_to_optimize(initial_state: StackState, omega0: float, method: str) -> OptimizeResult:
    """A stack without movable plates (one platform, EE fixed): the start is the optimum."""
    if initial_state.feasible:
        message = "nothing to optimize (no internal plates): the start is the optimum"
    else:
        message = one_line(f"{describe(binding(initial_state.violations))} (nothing to optimize: no internal plates)")
    return OptimizeResult(
        success=initial_state.feasible,
        message=message,
        status=0,
        solver_message="",
        iterations=0,
        evaluations=0,
        gradient_evaluations=0,
        time_s=0.0,
        initial=initial_state,
        optimized=initial_state,
        objective_initial=omega0,
        objective_optimized=omega0,
        method=method,
        optimal=initial_state.feasible,
    )
