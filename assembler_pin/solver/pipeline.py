"""Goal pose → internal poses: the helper-arm initial condition, then force optimization.

:func:`solve` is the whole pipeline behind ``assembler-pin solve``: a fast valid initial
pose from the helper arm (paper §III), then, unless told not to, the force-optimized
internal poses (paper §IV). An unreachable goal is an answer (``success=False`` with the
reason), not an exception.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from ..collision.scene import Scene, read_scene
from ..common.messages import binding, describe, one_line
from ..common.threads import one_blas_thread
from ..config.options import checked_options
from ..exceptions import ArgumentError, OptionsError
from ..helper_arm import HelperArmOptions, initial_condition
from ..kinematics import se3_to_taa, to_se3
from ..model.assembler import AssemblerModel, checked_model
from ..optimize import OptimizeOptions, OptimizeResult
from ..state import StackState, evaluate_state
from .sag import SagReport, sag_report
from .starts import START_MODES, agreeing, best_run, run_starts

if TYPE_CHECKING:
    from ..helper_arm import InitialConditionResult

__all__ = ["SolveResult", "solve"]


@dataclass
class SolveResult:
    """Outcome of :func:`solve`.

    Attributes:
        goal: the EE goal pose.
        success: a valid pose is returned: it meets every constraint, re-checked with the
            Pinocchio statics (the optimized pose when optimizing, else the helper arm's).
            Whether it is also a local optimum is :attr:`optimal`.
        message: what happened, or why not: one line naming the binding cause
            (:mod:`~assembler_pin.common.messages`); the long form in ``details``.
        initial_result: the helper-arm result (arm configuration, d used, attempts).
        optimization: the optimizer's result from the winning start (None with
            ``optimize=False`` or when no start gave a feasible state).
        timing_s: wall times ``initial`` and ``optimize`` (all starts) [s].
        start: name of the start the returned optimum came from (see
            :data:`~assembler_pin.solver.starts.STARTS`; ``perturbed_k`` for a fallback start,
            ``lean_k`` for a lean start), None without one.
        runs: every start tried, in the order tried → its optimization result.
    """

    goal: pin.SE3
    success: bool
    message: str
    initial_result: InitialConditionResult
    optimization: OptimizeResult | None = None
    timing_s: dict[str, float] = field(default_factory=dict)
    start: str | None = None
    runs: dict[str, OptimizeResult] = field(default_factory=dict)
    details: str = ""
    """What every step met: the helper arm's scan, each start's result (may be long)."""
    model: AssemblerModel | None = field(default=None, repr=False, compare=False)
    """The stack solved (for :attr:`sag`)."""
    options: OptimizeOptions | None = field(default=None, repr=False, compare=False)
    """The optimizer's options (None without optimization)."""

    @functools.cached_property
    def sag(self) -> SagReport | None:
        """The EE's linear sag under its own load of the helper arm's pose and of the returned
        pose (:func:`~assembler_pin.solver.sag.sag_report`), computed on first access (a few
        ms); None without :attr:`model`."""
        if self.model is None:
            return None
        return sag_report(self.model, self.initial, self.best, self.options)

    @property
    def optimal(self) -> bool:
        """The returned pose is a local optimum: it is valid and the first-order (KKT)
        conditions hold at it, the objective's gradient opposed by the active constraints'
        within :data:`~assembler_pin.optimize.certificate.KKT_TOLERANCE` (the residual is
        ``optimization.optimality.residual``; :func:`~assembler_pin.optimize.certificate.optimality`).
        A certificate of the pose itself, not a global claim: another start may reach a lower
        optimum (:attr:`starts_tried`, :attr:`starts_agreeing`). False without optimization."""
        return self.success and self.optimization is not None and self.optimization.optimal

    @property
    def starts_tried(self) -> tuple[str, ...]:
        """The starts the optimizer ran from, in the order tried (empty without optimization)."""
        return tuple(self.runs)

    @property
    def starts_agreeing(self) -> int:
        """How many of :attr:`starts_tried` reached the returned optimum (a proven optimum
        whose Ω is the answer's within :data:`~assembler_pin.solver.starts.SAME_OPTIMUM`);
        0 when the answer is not a proven optimum."""
        return agreeing(self.runs, self.optimization) if self.success else 0

    @property
    def initial(self) -> StackState | None:
        """The valid initial state (None when the helper arm found none)."""
        return self.initial_result.state if self.initial_result.success else None

    @property
    def optimized(self) -> StackState | None:
        """The best feasible optimized state (None without optimization)."""
        return self.optimization.optimized if self.optimization is not None else None

    @property
    def best(self) -> StackState | None:
        """The optimized state when there is one, else the initial one."""
        return self.optimized or self.initial

    def __repr__(self) -> str:
        init = f"{self.initial.max_abs_force:.3f} N" if self.initial is not None else "-"
        opt = f"{self.optimized.max_abs_force:.3f} N" if self.optimized is not None else "-"
        times = ", ".join(f"{k} {1e3 * v:.0f} ms" for k, v in self.timing_s.items())
        return (
            f"SolveResult(success={self.success}, optimal={self.optimal}, "
            f"goal {np.round(self.goal.translation, 4).tolist()} m, max|F| "
            f"initial {init} → optimized {opt} (start {self.start}), {times}, "
            f"message={self.message!r})"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON of ``assembler-pin solve --json``."""
        out: dict[str, Any] = {
            "goal": se3_to_taa(self.goal).tolist(),
            "success": self.success,
            "message": self.message,
            # the helper arm's state: the home pose, flagged by success false, when it failed
            "initial": self.initial_result.state.to_dict(),
        }
        if self.optimization is not None or "optimize" in self.timing_s:
            opt = self.optimization
            helper_run = self.runs.get("helper_arm")
            out["optimized"] = self.optimized.to_dict() if self.optimized is not None else None
            out["objective"] = {
                # Ω of the helper arm's initial condition (None when it found none)
                "initial": helper_run.objective_initial if helper_run else None,
                "optimized": opt.objective_optimized if opt else None,
            }
            out["timing_s"] = dict(self.timing_s)
            if opt is not None:
                out["optimizer"] = {
                    "method": opt.method,
                    "status": opt.status,
                    "message": opt.solver_message,
                    "iterations": opt.iterations,
                    "evaluations": opt.evaluations,
                }
                out["optimality"] = opt.optimality.to_dict() if opt.optimality is not None else None
            out["start"] = self.start
            out["starts_tried"] = list(self.starts_tried)
            out["starts_agreeing"] = self.starts_agreeing
            out["starts"] = {
                name: {
                    "success": r.success,
                    "optimal": r.optimal,
                    "max_abs_force": r.optimized.max_abs_force,
                    "message": r.message,
                }
                for name, r in self.runs.items()
            }
        else:
            out["timing_s"] = dict(self.timing_s)
        # the returned pose is a local optimum: valid, and the KKT conditions hold at it within
        # the tolerance of optimality.kkt_residual; not a global claim (docs/contract.md)
        out["optimal"] = self.optimal
        out["details"] = self.details  # the long form of message: every step met (may be long)
        if self.sag is not None:
            out["sag"] = self.sag.to_dict()  # the EE's sag of the helper arm's pose and of the answer
        return out


@one_blas_thread
def solve(
    am: AssemblerModel,
    goal: pin.SE3 | np.ndarray,
    optimize: bool = True,
    options: OptimizeOptions | None = None,
    helper_options: HelperArmOptions | None = None,
    starts: str = "first",
    scene: Scene | str | None = None,
) -> SolveResult:
    """Internal poses of the stack for an EE goal pose.

    The helper arm gives a valid initial condition; the optimizer then runs from the starts of
    :data:`~assembler_pin.solver.starts.STARTS` in order (the helper arm's, the even screw
    pose, the home pose; then fallback and lean starts when none reached an optimum or a valid
    pose), all of them with ``starts="all"``, the first ones until the answer is settled
    (:func:`~assembler_pin.solver.starts.settled`) by default. The best optimum is returned
    with the name of its start (:func:`~assembler_pin.solver.starts.best_run`), the starts
    tried and how many agreed on it. A goal the helper arm cannot reach may still be solved
    from another start.

    Args:
        goal: EE pose in the base (world) frame, ``pin.SE3`` or 4×4.
        optimize: run the force optimization after the initial condition.
        options: optimizer settings; helper_options: helper-arm settings.
        starts: ``"first"`` (default): the starts in order until the answer is settled;
            ``"all"``: every start.
        scene: obstacles and floor (:class:`~assembler_pin.collision.scene.Scene`, a scene
            file or None): every run keeps every checked pair of bodies at least the
            configuration's ``clearance`` apart (the optimizer's clearance rows), and a goal
            no start reaches without a collision is answered ``success=False`` with the cause
            ``collision``. The helper arm does not see the scene: its pose is only a start.

    Returns:
        A :class:`SolveResult`: ``success`` (a valid pose was found, every constraint
        re-checked) and ``message`` (why not, when not); ``optimized`` the force-optimized
        :class:`~assembler_pin.state.StackState` (``.plates``, ``.forces`` [N],
        ``.max_abs_force``), ``initial`` the helper arm's, ``best`` the first of the two that
        exists; ``optimal`` whether the pose is proven an optimum. An unreachable goal is an
        answer (``success=False``), not an exception.

    Raises:
        PoseError: the goal is not a valid SE(3) pose.
        OptionsError: ``starts`` is not one of :data:`~assembler_pin.solver.starts.START_MODES`.
    """
    goal, options, helper_options = _checked_inputs(am, goal, optimize, options, helper_options, starts)
    result = _solved(am, goal, optimize, options, helper_options, starts, read_scene(scene))
    result.model, result.options = am, options if optimize else None
    return result


def _solved(
    am: AssemblerModel,
    goal: pin.SE3,
    optimize: bool,
    options: OptimizeOptions,
    helper_options: HelperArmOptions,
    starts: str,
    scene: Scene | None,
) -> SolveResult:
    """:func:`solve` on checked inputs (the result without its model and options)."""
    t0 = time.perf_counter()
    init = initial_condition(am, goal, helper_options)
    timing = {"initial": time.perf_counter() - t0}
    helper = f"helper arm: {init.details or init.message}"
    if not optimize:
        if scene is not None and init.success:  # the helper arm's pose, checked in the scene
            state = evaluate_state(am, init.state.plates, goal=goal, tolerance=helper_options.tolerance, scene=scene)
            if not state.feasible:
                why = one_line(f"{describe(binding(state.violations))} (the helper arm's pose, in the scene)")
                return SolveResult(goal, False, why, init, None, timing, details=helper)
        return SolveResult(goal, init.success, init.message, init, None, timing, details=helper)
    if init.attempts == 0 and not init.success:  # out of reach: nothing to start from
        timing["optimize"] = 0.0
        return SolveResult(goal, False, init.message, init, None, timing, details=helper)
    t1 = time.perf_counter()
    runs = run_starts(am, goal, init, options, starts, scene)
    timing["optimize"] = time.perf_counter() - t1
    return _answer(goal, init, runs, timing)


def _checked_inputs(
    am: AssemblerModel,
    goal: pin.SE3 | np.ndarray,
    optimize: bool,
    options: OptimizeOptions | None,
    helper_options: HelperArmOptions | None,
    starts: str,
) -> tuple[pin.SE3, OptimizeOptions, HelperArmOptions]:
    """(goal, options, helper options) of :func:`solve`, or the error naming what is wrong."""
    checked_model(am)
    if starts not in START_MODES:
        raise OptionsError(f"starts must be one of {', '.join(START_MODES)}, got {starts!r}")
    goal = to_se3(goal, "goal")
    options = checked_options(options, OptimizeOptions, "options")
    helper_options = checked_options(helper_options, HelperArmOptions, "helper_options")
    if not isinstance(optimize, bool):
        raise ArgumentError(f"optimize must be True or False, got {type(optimize).__name__}")
    return goal, options, helper_options


def _answer(
    goal: pin.SE3, init: InitialConditionResult, runs: dict[str, OptimizeResult], timing: dict[str, float]
) -> SolveResult:
    """The :class:`SolveResult` of the optimizer's runs: the best run
    (:func:`~assembler_pin.solver.starts.best_run`) or why none reached a feasible pose."""
    name, best = best_run(runs)
    helper = f"helper arm: {init.details or init.message}"
    details = "; ".join([helper, *(f"{k} start: {r.message}" for k, r in runs.items())])
    if best is None:
        return SolveResult(goal, False, _no_start_message(init, runs), init, None, timing, None, runs, details=details)
    message = f"{best.message} (from the {name} start)"
    if not init.success:
        message += "; the helper arm found no valid initial condition"
    return SolveResult(goal, best.success, one_line(message), init, best, timing, name, runs, details=details)


def _no_start_message(init: InitialConditionResult, runs: dict[str, OptimizeResult]) -> str:
    """One line when no start reached a feasible pose: the helper arm's cause when it
    failed, else the binding violation of the closest start (smallest Ω)."""
    if not init.success:
        return one_line(f"{init.message}; no optimizer start reached a feasible pose")
    feasible = [r for r in runs.values() if r.optimized.feasible]
    closest = min(feasible or runs.values(), key=lambda r: r.objective_optimized, default=None)
    if closest is not None and closest.optimized.feasible:  # kept out by the sag limit or a motion step
        return one_line(f"{closest.message} (closest of {len(runs)} optimizer starts)")
    worst = None if closest is None else binding(closest.optimized.violations)
    why = describe(worst) if worst is not None else "no feasible pose"
    return one_line(f"{why} (closest of {len(runs)} optimizer starts)")
