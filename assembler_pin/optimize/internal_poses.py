"""``optimize_internal_poses``: run a method from a start and return a checked answer.

The iterates are evaluated in closed form (:mod:`.problem`); every state the user gets back
is evaluated again with the Pinocchio statics (:func:`~assembler_pin.state.evaluate_state`),
and only such a re-checked state can be called feasible.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..collision.scene import Scene, read_scene
from ..common.messages import one_line
from ..common.threads import one_blas_thread
from ..config.options import SMOOTH_METHODS, GoalTolerance, OptimizeOptions, checked_options, resolved_method
from ..exceptions import OptionsError, SingularIterateError
from ..kinematics import PlateArrays, checked_goal, plate_arrays
from ..model.assembler import AssemblerModel, checked_model
from ..state import StackState, evaluate_state
from .certificate import Optimality, optimality
from .ipopt import run_ipopt
from .objective import SagObjective, state_sag, state_score
from .options import MotionTerm
from .paper import PaperForm
from .problem import Problem
from .result import OptimizeResult, SolverResult, StoppedEarly, nothing_to_optimize, verdict
from .smooth import SmoothForm

__all__ = ["optimize_internal_poses"]

logger = logging.getLogger(__name__)


@one_blas_thread
def optimize_internal_poses(
    am: AssemblerModel,
    initial: StackState | PlateArrays | list,
    goal: pin.SE3 | None = None,
    options: OptimizeOptions | None = None,
    motion: MotionTerm | None = None,
    scene: Scene | str | None = None,
) -> OptimizeResult:
    """Minimize Ω over the intermediate plate poses, from a starting pose.

    The start need not be valid (the solver may reach a feasible point from outside); the
    result is a success only when the solver converged to a point that meets every
    constraint. A converged point just outside a limit is pulled back inside along the
    segment to the best feasible point met; when that fails the result says so.

    Args:
        initial: the starting pose (a state or plate poses), e.g. the helper-arm initial
            condition; plate n is taken as the goal unless ``goal`` is given.
        goal: the EE goal pose (default: the initial state's plate n).
        options: see :class:`OptimizeOptions`.
        motion: continuity with a previous sample (:class:`MotionTerm`, slsqp only); the
            chosen state then also keeps every leg within ``max_step`` of it.
        scene: obstacles and floor (:class:`~assembler_pin.collision.scene.Scene`, a scene
            file or None): the clearance rows (:class:`~.rows.ClearanceRows`) keep every pair
            of bodies :func:`~assembler_pin.collision.check.clearance` checks at least the
            configuration's ``clearance`` apart, and the states are checked against the scene
            (an empty ``Scene()`` holds the stack's own pairs alone). Without a scene the
            first run has no clearance rows (most optima are clear, and the rows cost time);
            when its state collides, the run is made again with the stack's own pairs as
            rows (an empty scene). IPOPT's moment-variable form has no clearance rows: with a
            scene, ``ipopt`` (and ``auto`` on long stacks) runs SLSQP.
    """
    opts, start, goal = _checked_inputs(am, initial, goal, options, motion)
    scene = read_scene(scene)
    if scene is not None and opts.method == "ipopt":
        opts = dataclasses.replace(opts, method="slsqp")
    result = _optimized(am, start, goal, opts, motion, scene)
    if scene is None and opts.method != "ipopt" and _collides(result):
        scene = Scene()  # the stack's own pairs as rows, from the same start
        result = _optimized(am, start, goal, opts, motion, scene)
    if _asked_for_auto(options) and result.method == "ipopt" and not result.optimal:
        result = _polished(am, result, goal, opts, motion)
    # the restarts are SLSQP runs, for SLSQP's stalls (IPOPT's run is finished by _polished);
    # a motion's sample has the planner's own fallbacks (another start, a shorter step)
    if result.optimal or not result.success or opts.method != "slsqp" or motion is not None:
        return result
    return _restarted(am, result, goal, opts, motion, scene)


def _collides(result: OptimizeResult) -> bool:
    """True when the run's state (or, having none valid, its reason) is a collision."""
    state = result.optimized
    return any(v.kind == "collision" for v in state.violations) or "collision" in result.message


#: The extra margins [m, cos] of the restarts from a valid state that is not an optimum
#: (:func:`_restarted`): each runs SLSQP from it with its rows kept this much further inside,
#: then again with the asked margin from where that run ended.
RESTART_MARGINS = (1e-6, 1e-5)


def _restarted(
    am: AssemblerModel,
    result: OptimizeResult,
    goal: pin.SE3,
    opts: OptimizeOptions,
    motion: MotionTerm | None,
    scene: Scene | None = None,
) -> OptimizeResult:
    """A run that returned a valid state which is not an optimum
    (:func:`~.certificate.optimality`), restarted from that state until one is.

    A run stalls where the start sits on many limits at once (the repaired starts are put
    exactly on them) and SLSQP's linearized rows turn incompatible, or where its line
    search fails; where it stalls depends on the rounding of the machine's BLAS kernel. A
    restart from the same point stalls again; one with the rows kept a little further inside
    (:data:`RESTART_MARGINS`) leaves the corner, and a second with the asked margin ends on
    the optimum. Each restart is kept only when it is valid and no worse."""
    for extra in RESTART_MARGINS:
        inside = _optimized(am, result.optimized.plates, goal, replace_margin(opts, extra), motion, scene)
        start = inside.optimized if inside.success else result.optimized
        again = _optimized(am, start.plates, goal, opts, motion, scene)
        if again.success and again.objective_optimized <= result.objective_optimized + 1e-9:
            result = _continued(result, again, inside)
        if result.optimal:
            break
    return result


def replace_margin(opts: OptimizeOptions, extra: float) -> OptimizeOptions:
    """``opts`` with its limit margin ``extra`` larger (than 0, for a margin that is not positive)."""
    return dataclasses.replace(opts, limit_margin=max(opts.limit_margin, 0.0) + extra)


def _continued(first: OptimizeResult, *later: OptimizeResult, how: str = "") -> OptimizeResult:
    """The last of ``later`` as the outcome of ``first`` continued: the start, counters and
    times of them all; ``how`` says how it went on (default: restarted where it stopped)."""
    last = later[-1]
    runs = (first, *later)
    methods = list(dict.fromkeys(r.method for r in runs))
    how = how or f"restarted from where {first.method} stopped"
    return dataclasses.replace(
        last,
        message=one_line(f"{last.message} ({how})"),
        iterations=sum(r.iterations for r in runs),
        evaluations=sum(r.evaluations for r in runs),
        gradient_evaluations=sum(r.gradient_evaluations for r in runs),
        time_s=sum(r.time_s for r in runs),
        initial=first.initial,
        objective_initial=first.objective_initial,
        sag_initial=first.sag_initial,
        method="+".join(methods),
    )


def _asked_for_auto(options: OptimizeOptions | None) -> bool:
    return (options.method if options is not None else OptimizeOptions().method) == "auto"


def _polished(
    am: AssemblerModel, ipopt: OptimizeResult, goal: pin.SE3, opts: OptimizeOptions, motion: MotionTerm | None
) -> OptimizeResult:
    """``method="auto"``'s IPOPT run that did not converge, finished by SLSQP from the best
    state it met (method ``"ipopt+slsqp"``; the counters and times of both runs).

    On long stacks IPOPT's limited-memory Hessian nears the optimum slowly (its objective
    still moves by 1e-6 relative per iteration at the iteration cap) and SLSQP's active set
    finishes it in 10-30 iterations (measured at n = 16 and 32, 4 displaced goals each).
    From a feasible state SLSQP's force rows are capped at its max|F|, so the result is never
    worse than IPOPT's; when SLSQP fails too, IPOPT's result stands."""
    polish = _optimized(am, ipopt.optimized.plates, goal, dataclasses.replace(opts, method="slsqp"), motion)
    if not polish.success or polish.objective_optimized > ipopt.objective_optimized + 1e-9:
        return ipopt
    return _continued(ipopt, polish, how=f"SLSQP from the best state met by {ipopt.solver_message}")


def _optimized(
    am: AssemblerModel,
    start: PlateArrays,
    goal: pin.SE3,
    opts: OptimizeOptions,
    motion: MotionTerm | None,
    scene: Scene | None = None,
) -> OptimizeResult:
    """One run of the method of ``opts`` (resolved, not ``auto``) from ``start``."""
    tolerance = opts.ee_tolerance or opts.goal_tolerance
    initial_state = evaluate_state(am, start, goal=goal, tolerance=tolerance, scene=scene)
    problem = Problem(am, start, goal, opts, initial_state.feasible, motion, scene, initial_state.clearance)
    check = _Check(am, goal, tolerance, opts, motion, problem.objective, scene)
    omega0 = check.score(initial_state)
    if problem.nx_pose == 0:
        return _sag_checked(check, nothing_to_optimize(initial_state, omega0, opts.method), initial_state)
    t0 = time.perf_counter()
    res, x_final, singular = _run_solver(problem, initial_state)
    elapsed = time.perf_counter() - t0
    chosen, omega_chosen, success, message = _outcome(check, problem, res, x_final, singular, initial_state)
    certificate = optimality(am, chosen, goal, opts, motion, scene) if success else None
    optimal = certificate is not None and certificate.optimal
    message = _optimality_message(success, optimal, message, certificate, f"{res.message} (status {res.status})")
    logger.info(
        "optimize[%s, %s]: %s, objective %.4g -> %.4g in %.3f s, %d iterations",
        *(opts.method, opts.objective, message, omega0, omega_chosen, elapsed, res.nit),
    )
    return OptimizeResult(
        success=success,
        message=message,
        status=int(res.status),
        solver_message=str(res.message),
        iterations=int(res.nit),
        evaluations=problem.evaluations,
        gradient_evaluations=problem.gradient_evaluations,
        time_s=elapsed,
        initial=initial_state,
        optimized=chosen,
        objective_initial=omega0,
        objective_optimized=omega_chosen,
        method=opts.method,
        objective=opts.objective,
        sag_initial=state_sag(am, initial_state),
        sag_optimized=state_sag(am, chosen),
        optimal=optimal,
        optimality=certificate,
    )


def _optimality_message(
    success: bool, optimal: bool, message: str, certificate: Optimality | None, solver_said: str
) -> str:
    """The message of a run whose returned state is valid (``success``): "converged" at an
    optimum (with what the solver said when its status says otherwise), else why it is not
    proven one."""
    if not success or certificate is None:
        return message
    if optimal:
        return "converged" if message == "converged" else one_line(f"converged: the solver ended with {solver_said}")
    why = certificate.reason if message == "converged" else message
    return one_line(f"not proven optimal: {why}")


def _outcome(
    check: _Check, problem: Problem, res: SolverResult, x_final: np.ndarray, singular: str, initial_state: StackState
) -> tuple[StackState, float, bool, str]:
    """(state returned, its Ω, success, message): the solver's point re-checked with the
    Pinocchio statics, pulled back inside when just outside a limit, then the best of it,
    the best feasible point met and the start (:func:`_chosen`)."""
    final_state = check.state_at(problem, x_final)
    converged = bool(res.success) and not singular
    if converged and not check.acceptable(final_state):
        final_state = _pulled_inside(check, problem, x_final, final_state)
    chosen, omega_chosen = _chosen(check, problem, final_state, initial_state)
    if check.motion is not None and converged and final_state.feasible and not check.acceptable(final_state):
        converged, singular = (
            False,
            f"motion step: the converged point moves a leg more than {1e3 * check.motion.max_step:.3g} mm",
        )
    converged_here, message = verdict(res, singular, converged, final_state, chosen, initial_state)
    converged_here, message = _sag_verdict(check, converged_here, message, converged, final_state, chosen)
    valid = check.acceptable(chosen)
    return chosen, omega_chosen, valid, "converged" if converged_here and valid else message


def _sag_verdict(
    check: _Check, success: bool, message: str, converged: bool, final: StackState, chosen: StackState
) -> tuple[bool, str]:
    """(success, message) with the sag limit: a returned state above ``max_sag`` (or a
    converged point above it while another state is returned) is no success, and its
    message starts ``sag limit:``."""
    limit = check.opts.max_sag
    if limit is None:
        return success, message
    mm = f"{1e3 * limit:.4g} mm"
    sag = state_sag(check.am, chosen)
    if sag > limit:
        why = message if not success else "no state within it met"
        return False, one_line(f"sag limit: EE sag {1e3 * sag:.4g} mm, limit {mm}; {why}")
    if converged and final is not chosen and final.feasible and state_sag(check.am, final) > limit:
        return False, one_line(
            f"sag limit: the converged point sags {1e3 * state_sag(check.am, final):.4g} mm, limit {mm}; "
            "the best state within it is returned"
        )
    return success, message


def _sag_checked(check: _Check, result: OptimizeResult, state: StackState) -> OptimizeResult:
    """A result without a solve (nothing to optimize) with the sag limit and the sags."""
    success, message = _sag_verdict(check, result.success, result.message, False, state, state)
    sag = state_sag(check.am, state)
    return dataclasses.replace(
        result,
        success=success,
        optimal=success and result.optimal,
        message=message,
        objective=check.opts.objective,
        sag_initial=sag,
        sag_optimized=sag,
    )


def _checked_inputs(
    am: AssemblerModel,
    initial: StackState | PlateArrays | list,
    goal: pin.SE3 | None,
    options: OptimizeOptions | None,
    motion: MotionTerm | None,
) -> tuple[OptimizeOptions, PlateArrays, pin.SE3]:
    """(options, start plates, goal), or an :class:`OptionsError` / :class:`PoseError`."""
    checked_model(am)
    opts = checked_options(options, OptimizeOptions, "options")
    if motion is not None and not isinstance(motion, MotionTerm):
        raise OptionsError(f"motion must be a MotionTerm or None, got {type(motion).__name__}")
    if goal is not None:
        goal = checked_goal(goal, "goal")
    if motion is not None:
        if opts.method not in SMOOTH_METHODS:
            raise OptionsError("a motion term needs method 'slsqp' (or 'ipopt', 'auto')")
        if motion.previous_lengths.shape != (am.n, 6):
            raise OptionsError(f"previous_lengths must have shape ({am.n}, 6), got {motion.previous_lengths.shape}")
    start = initial.plates if isinstance(initial, StackState) else plate_arrays(am, initial)
    if opts.method == "auto":
        opts = dataclasses.replace(opts, method=resolved_method(opts.method, am.n))
    return opts, start, start.se3(am.n) if goal is None else goal


@dataclass(frozen=True)
class _Check:
    """The Pinocchio re-check of candidate points: their states, whether they may be
    returned, and their objective (with the motion term)."""

    am: AssemblerModel
    goal: pin.SE3
    tolerance: GoalTolerance
    opts: OptimizeOptions
    motion: MotionTerm | None
    objective: SagObjective
    scene: Scene | None = None

    states: dict[bytes, StackState] = dataclasses.field(default_factory=dict)
    """The states re-checked so far, by chart point (the best point met is often the final one)."""

    def state_at(self, problem: Problem, x_pose: np.ndarray) -> StackState:
        """The Pinocchio-checked state at the chart point (each point checked once)."""
        key = np.asarray(x_pose, dtype=float).tobytes()
        if key not in self.states:
            plates = problem.chart.plates(x_pose)
            self.states[key] = evaluate_state(
                self.am, plates, goal=self.goal, tolerance=self.tolerance, scene=self.scene
            )
        return self.states[key]

    def acceptable(self, state: StackState) -> bool:
        """Feasible, within the motion step of the previous sample and within the sag limit."""
        if not state.feasible:
            return False
        if self.motion is not None and not bool(np.all(self.motion.margins(state.leg_lengths) >= 0)):
            return False
        return self.opts.max_sag is None or state_sag(self.am, state) <= self.opts.max_sag

    def score(self, state: StackState) -> float:
        """The objective of the state (:func:`~assembler_pin.optimize.objective.state_score`)."""
        return state_score(self.am, state, self.objective, self.opts.w1, self.opts.w2, self.motion)


def _run_solver(problem: Problem, initial_state: StackState) -> tuple[SolverResult, np.ndarray, str]:
    """Run the method (SLSQP in its chart, or IPOPT on the epigraph form); returns (solver
    result, final pose point, the reason when it stopped at a singular iterate else "")."""
    from scipy.optimize import minimize  # on first use: fast start-up

    opts = problem.opts
    if opts.method == "ipopt":
        ipopt_result, singular = run_ipopt(problem, SmoothForm(problem).x0(initial_state))
        return ipopt_result, ipopt_result.x[:-1], singular
    form = SmoothForm(problem) if opts.method == "slsqp" else PaperForm(problem)
    x0 = form.x0(initial_state)
    cons: dict = {"type": "ineq", "fun": form.cons}
    if isinstance(form, SmoothForm):
        cons["jac"] = form.cons_jac
    jac = form.grad if isinstance(form, SmoothForm) else None
    try:
        res = minimize(
            form.fun,
            x0,
            jac=jac,
            method="SLSQP",
            constraints=[cons],
            options={"maxiter": opts.max_iterations, "ftol": opts.ftol},
        )
        singular = ""
    except SingularIterateError as exc:
        singular = f"stopped at a singular iterate: {exc}"
        res = StoppedEarly(x0, singular)
    x_final = res.x[:-1] if isinstance(form, SmoothForm) else res.x
    return res, x_final, singular


def _pulled_inside(check: _Check, problem: Problem, x_final: np.ndarray, final_state: StackState) -> StackState:
    """SLSQP honours its rows to ~1e-8: step back towards the best feasible point met; the
    first acceptable state on the way, else ``final_state``."""
    x_inside = problem.best[1] if problem.best is not None else np.zeros_like(x_final)
    for t in (1e-4, 1e-3, 1e-2, 1e-1):
        trial = check.state_at(problem, x_final + t * (x_inside - x_final))
        if check.acceptable(trial):
            return trial
    return final_state


def _chosen(
    check: _Check, problem: Problem, final_state: StackState, initial_state: StackState
) -> tuple[StackState, float]:
    """The state returned and its objective: the acceptable one of (final, best met, start)
    with the lowest objective (for the force objective: whose max|F| is no worse than a
    feasible start's)."""
    candidates = [final_state] + ([check.state_at(problem, problem.best[1])] if problem.best is not None else [])
    chosen, omega_chosen = initial_state, check.score(initial_state)
    for state in candidates:
        value = check.score(state)
        no_worse = (
            check.opts.objective != "force"
            or not initial_state.feasible
            or state.max_abs_force <= initial_state.max_abs_force + 1e-9
        )
        if check.acceptable(state) and (not check.acceptable(chosen) or (value < omega_chosen and no_worse)):
            chosen, omega_chosen = state, value
    return chosen, omega_chosen
