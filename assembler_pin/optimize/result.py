"""The outcome of an optimization: :class:`OptimizeResult`, the verdict on it, and the
result of a stack with nothing to optimize."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ..state import StackState

__all__ = ["OptimizeResult"]


@dataclass
class OptimizeResult:
    """Outcome of an internal-pose optimization.

    Attributes:
        success: the solver converged and the returned state satisfies every constraint.
        message: what happened, and why not when it failed.
        status, solver_message: scipy's own status code and message.
        iterations, evaluations, gradient_evaluations: solver counters.
        time_s: wall time of the optimization [s].
        initial, optimized: the starting state and the best feasible state found (the
            initial one when nothing better was found).
        objective_initial, objective_optimized: Ω of both states.
        method: the method used.
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

    def __repr__(self) -> str:
        return (
            f"OptimizeResult(success={self.success}, method={self.method!r}, max|F| "
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
    solver = f" (solver: {singular or res.message})"
    if not converged:
        if not chosen.feasible:
            worst = "; ".join(str(v) for v in chosen.violations[:3])
            return False, f"no feasible state found{solver}: {worst}"
        if chosen is initial:
            return False, f"the solver did not converge{solver}; no better feasible state than the start"
        return False, f"the solver did not converge{solver}; best feasible state met returned"
    if not final.feasible:
        worst = "; ".join(str(v) for v in final.violations[:2])
        kept = "best feasible state met returned" if chosen.feasible else "no feasible state found"
        return False, f"the solver's converged point breaks a limit ({worst}); {kept}"
    return True, "converged"


def nothing_to_optimize(initial_state: StackState, omega0: float, method: str) -> OptimizeResult:
    """A stack without movable plates (one platform, EE fixed): the start is the optimum."""
    if initial_state.feasible:
        message = "nothing to optimize (no internal plates): the start is the optimum"
    else:
        message = "nothing to optimize (no internal plates) and the start is not feasible: " + "; ".join(
            str(v) for v in initial_state.violations[:3]
        )
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
    )
