"""Whether a returned state is the optimum: the first-order (KKT) conditions, checked at the
state itself.

A solver's status code says how its run ended, not whether the point it returns is an
optimum: the same goal can end in SLSQP's "Inequality constraints incompatible" on one
OpenBLAS kernel and in "Optimization terminated successfully" on another, at optima 0.1 N
apart, and a restart from a true optimum can end in "Positive directional derivative for
linesearch". The verdict here reads the point only: in the smooth epigraph form centred on
the state (x = 0, ``s`` = its max|F|), the rows within :data:`ACTIVE_DISTANCE` of their
bound (a distance in chart units, each row divided by its gradient's norm) are active, and
the multipliers ``λ >= 0`` that best explain the objective's gradient by theirs come from a
non-negative least squares. The state is an optimum when the part left unexplained is at most
:data:`KKT_TOLERANCE` of the gradient. Measured on the default stack: optima 1e-8 to 3e-4,
stalled runs 0.2 to 1; the tolerance sits between them with two decades on either side.

That unexplained part ``ρ = ∇f - J_Aᵀ λ`` is also a direction to improve along: ``-ρ`` keeps
every active row to first order (``J_A ρ <= 0``) and lowers the objective (``∇fᵀρ = |ρ|²``),
which is how :mod:`.internal_poses` restarts a run that stalled away from an optimum.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..collision.scene import Scene
from ..config.options import OptimizeOptions
from ..exceptions import SingularIterateError
from ..model.assembler import AssemblerModel
from ..state import StackState
from .objective import deviation_term, deviation_term_gradient
from .options import MotionTerm
from .problem import Problem
from .smooth import SmoothForm

__all__ = ["ACTIVE_DISTANCE", "KKT_TOLERANCE", "Optimality", "optimality"]

#: A row this close to its bound [chart units: m and rad] counts as active.
ACTIVE_DISTANCE = 1e-5

#: The deviation term counts as at its kink (:func:`_kink_part`) while its share of the
#: objective is at most this.
KINK_SHARE = 1e-5

#: The largest share of the objective's gradient the active rows may leave unexplained at an
#: optimum (relative 2-norm).
KKT_TOLERANCE = 1e-2


@dataclass(frozen=True)
class Optimality:
    """The first-order optimality of a state.

    Attributes:
        optimal: the KKT conditions hold within :data:`KKT_TOLERANCE`.
        residual: the unexplained share of the objective's gradient (0 at an exact optimum,
            1 where no active row opposes it; inf where no derivative exists).
        active: how many rows were active.
        descent: the direction ``-ρ`` in the problem's chart (pose part; empty when
            optimal or undefined), along which the objective decreases and the active rows
            hold to first order.
        problem: the problem the check was made in (its chart is centred on the state).
        reason: why not optimal, one phrase ("" when optimal).
    """

    optimal: bool
    residual: float
    active: int
    descent: np.ndarray
    problem: Problem | None
    reason: str = ""

    def to_dict(self) -> dict[str, object]:
        """JSON: ``{"optimal", "kkt_residual", "active_rows", "reason"}``."""
        residual = self.residual if np.isfinite(self.residual) else None
        return {"optimal": self.optimal, "kkt_residual": residual, "active_rows": self.active, "reason": self.reason}


def optimality(
    am: AssemblerModel,
    state: StackState,
    goal: pin.SE3,
    options: OptimizeOptions,
    motion: MotionTerm | None = None,
    scene: Scene | None = None,
) -> Optimality:
    """The KKT check of ``state`` for the problem of ``options`` (its objective, EE tolerance,
    sag limit, motion term and, with a scene, clearance rows; the force limits of the legs,
    not a start's cap).

    A state that does not meet every constraint is not checked (``optimal`` False)."""
    if not state.feasible:
        return Optimality(False, np.inf, 0, np.zeros(0), None, "the state does not meet every constraint")
    # the smooth form, whatever method ran
    opts = options if options.method == "slsqp" else dataclasses.replace(options, method="slsqp")
    problem = Problem(am, state.plates, goal, opts, start_feasible=False, motion=motion, scene=scene)
    if problem.nx_pose == 0:
        return Optimality(True, 0.0, 0, np.zeros(0), problem)
    form = SmoothForm(problem)
    x = form.x0(state)
    try:
        gradient, rows, jacobian = form.grad(x), form.cons(x), form.cons_jac(x)
        gradient[:-1] -= _kink_part(problem, x[:-1], form.fun(x))
    except SingularIterateError as exc:
        return Optimality(False, np.inf, 0, np.zeros(0), problem, f"no derivative at the state: {exc}")
    return _kkt(problem, gradient, rows, jacobian)


def _kink_part(problem: Problem, x_pose: np.ndarray, objective: float) -> np.ndarray:
    """The deviation term's part of the objective's gradient where the term is at most
    :data:`KINK_SHARE` of the objective, else zeros.

    ``w2·sqrt(Σ λ_k²)`` is not differentiable at λ = 0 (every plate parallel to the one below):
    near it its gradient keeps a norm of w2 however small the term, and an optimizer nears
    the kink without reaching it (IPOPT stops 2e-4 rad from it on a 32-platform stack). Without
    the term the first-order conditions are asked of the rest of the objective; a point meeting
    them is within the term's value, at most this share, of the optimum."""
    p = problem.point(x_pose)
    weight = problem.objective.omega_weight * problem.opts.w2
    if weight * deviation_term(p.plate_angles) > KINK_SHARE * max(abs(objective), 1.0):
        return np.zeros(x_pose.size)
    return weight * deviation_term_gradient(p.plate_angles, problem.derivatives(x_pose).plate_angles_sq)


def _kkt(problem: Problem, gradient: np.ndarray, rows: np.ndarray, jacobian: np.ndarray) -> Optimality:
    """The check from the objective's gradient and the rows with their Jacobian."""
    from scipy.optimize import nnls  # on first use: fast start-up

    norms = np.linalg.norm(jacobian, axis=1)
    reach = ACTIVE_DISTANCE * np.where(norms > 0, norms, 1.0)
    if np.any(rows < -reach):  # valid by the limits, but not within the optimizer's own margins
        why = "the state is outside the optimizer's rows (within a limit but not its margin)"
        return Optimality(False, np.inf, 0, np.zeros(0), problem, why)
    active = rows <= reach
    scale = float(np.linalg.norm(gradient))
    if scale == 0.0:
        return Optimality(True, 0.0, int(active.sum()), np.zeros(0), problem)
    if active.any():
        multipliers, _ = nnls(jacobian[active].T, gradient, maxiter=50 * int(active.sum()) + 100)
        unexplained = gradient - jacobian[active].T @ multipliers
    else:
        unexplained = gradient
    residual = float(np.linalg.norm(unexplained)) / scale
    if residual <= KKT_TOLERANCE:
        return Optimality(True, residual, int(active.sum()), np.zeros(0), problem)
    why = f"the first-order conditions fail: {100 * residual:.3g} % of the objective's gradient is unopposed"
    return Optimality(False, residual, int(active.sum()), -unexplained, problem, why)
