"""Force-optimal motion along an EE path: every sample a valid, force-optimized internal
pose, each warm-started from the previous one and kept close to it.

For each sample the optimizer (:func:`~assembler_pin.optimize.optimize_internal_poses`)
starts from the previous optimum with the EE's move to the new goal shared evenly by the
platforms (:func:`.guess.spread_start`), then, if that does not converge to a valid sample,
from the previous optimum with only its EE plate moved; with a
:class:`~assembler_pin.optimize.MotionTerm`: no leg moves more than ``max_leg_step`` from
the previous sample (so the plan cannot jump to another assembly mode or local minimum),
and, with ``w3 > 0``, the paper's minimum-movement term ``w3·Σ ΔL²`` in the objective.
When neither run converges, the valid state of lowest max|F| met (a state an optimizer
returned, or a warm start itself) is the sample, listed in ``PlanResult.unconverged``:
valid, checked as every sample, but not a converged optimum.
Between two samples the leg lengths are interpolated and the stack checked there
(``checks_between`` points: stack FK of the lengths, every limit, the EE within
``path_tolerance`` of the path). A step that fails any of this is halved, up to
``max_refinements`` times below its segment's spacing (counted again after each valid
sample); a sample that still cannot be made valid ends the plan with the reason and the
valid prefix — never a gap. The EE step is at most ``STEP_SHARE · n · max_leg_step``, so
that an even share of it fits the motion step of every leg.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..constraints import GoalTolerance
from ..exceptions import OptionsError
from ..kinematics import PlateArrays, plate_arrays, stack_forward_kinematics
from ..messages import binding, describe, one_line
from ..model import AssemblerModel
from ..objective import state_sag
from ..optimize import MotionTerm, OptimizeOptions, optimize_internal_poses
from ..options import checked_options
from ..progress import ProgressCallback
from ..state import StackState, evaluate_state
from ..validation import is_number
from .guess import on_se3, spread_start
from .paths import EEPath

__all__ = ["PlanOptions", "PlanResult", "plan_path"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class PlanOptions:
    """Settings of :func:`plan_path`.

    Attributes:
        position_step, rotation_step: largest EE move between samples [m], [rad] (the
            position step at most ``STEP_SHARE · n · max_leg_step``).
        max_leg_step: largest change of any leg length between samples [m].
        w3: weight of the motion term Σ ΔL² [1/m²] (0: force only); it also keeps the
            legs that do not set max|F| from wandering between samples.
        max_refinements: how many times a failing step may be halved below its segment's
            sample spacing (counted again after each valid sample).
        checks_between: interpolated checks between two samples.
        path_tolerance: how far the EE may leave the path between samples.
        limit_margin: how far inside the stroke [m] and deflection limit [rad] the samples
            stay, so that the interpolated legs between them stay inside too.
        optimize: the optimizer's settings (method slsqp; its ``limit_margin`` is replaced).
    """

    position_step: float = 0.01
    rotation_step: float = math.radians(2.0)
    max_leg_step: float = 0.01
    w3: float = 100.0
    max_refinements: int = 4
    checks_between: int = 3
    path_tolerance: GoalTolerance = field(default_factory=lambda: GoalTolerance(2e-3, math.radians(0.5)))
    limit_margin: float = 2e-3
    optimize: OptimizeOptions = field(default_factory=OptimizeOptions)

    def __post_init__(self) -> None:
        for name in ("position_step", "rotation_step", "max_leg_step", "limit_margin"):
            value = getattr(self, name)
            if not (is_number(value) and 0 < value < math.inf):
                raise OptionsError(f"{name} must be a finite number > 0, got {value!r}")
        if not (is_number(self.w3) and 0 <= self.w3 < math.inf):
            raise OptionsError(f"w3 must be a finite number >= 0 [1/m^2], got {self.w3!r}")
        for name in ("max_refinements", "checks_between"):
            value = getattr(self, name)
            if not (isinstance(value, int) and 0 <= value <= 20):
                raise OptionsError(f"{name} must be an integer in [0, 20], got {value!r}")
        if self.optimize.method != "slsqp":
            raise OptionsError("motion planning needs the optimizer method 'slsqp'")
        object.__setattr__(self, "optimize", dataclasses.replace(self.optimize, limit_margin=self.limit_margin))


@dataclass
class PlanResult:
    """A planned motion: valid samples along the path (the whole path when successful).

    Attributes:
        success: every sample to the end of the path is valid and continuous.
        reason: why the plan stopped, or "reached the end of the path".
        path: the EE path.
        parameters: (m,) path parameter of each sample (0 … path.segments).
        states: the m valid, force-optimized states (the valid prefix when it failed).
        solve_times_s: (m,) optimization time of each sample [s] (0 for the start).
        refinements: number of halved steps over the whole plan.
        max_between_deviation: largest EE distance from the path at the checks between
            samples [m] and angle [rad].
        time_s: wall time of the plan [s].
        path_tolerance: how far the EE may leave the path between samples.
        unconverged: indices of the samples where the optimizer did not converge and a
            valid state it met (or its warm start) is the sample instead: valid (every
            constraint, the motion step, the checks between samples) but not force-optimal.
    """

    success: bool
    reason: str
    path: EEPath
    parameters: np.ndarray
    states: list[StackState]
    solve_times_s: np.ndarray
    refinements: int
    max_between_deviation: tuple[float, float]
    time_s: float
    path_tolerance: GoalTolerance = field(default_factory=lambda: GoalTolerance(2e-3, math.radians(0.5)))
    unconverged: tuple[int, ...] = ()

    @property
    def not_optimal(self) -> list[int]:
        """Indices of the held samples that are valid but not a converged optimum."""
        return [i for i in self.unconverged if i < len(self.states)]

    @property
    def lengths(self) -> np.ndarray:
        """(m, n, 6) leg lengths of the samples [m]."""
        return np.array([s.leg_lengths for s in self.states])

    @property
    def max_abs_forces(self) -> np.ndarray:
        """(m,) max|F| of each sample [N]."""
        return np.array([s.max_abs_force for s in self.states])

    def __repr__(self) -> str:
        peak = f"{self.max_abs_forces.max():.2f} N" if self.states else "-"
        return (
            f"PlanResult(success={self.success}, {len(self.states)} samples to u = "
            f"{self.parameters[-1] if len(self.parameters) else 0:.3f}/{self.path.segments}, peak max|F| {peak}, "
            f"{self.refinements} refinements, {len(self.not_optimal)} not optimal, {self.time_s:.2f} s, "
            f"reason={self.reason!r})"
        )


def _with_ee(plates: PlateArrays, goal: pin.SE3) -> PlateArrays:
    R, p = plates.R.copy(), plates.p.copy()
    R[-1], p[-1] = goal.rotation, goal.translation
    return PlateArrays(R, p)


def _between_problems(
    am: AssemblerModel, path: EEPath, u0: float, u1: float, a: StackState, b: StackState, opts: PlanOptions
) -> tuple[str, float, float]:
    """Checks at the interpolated leg lengths strictly between two samples: the first
    problem found ("" when none), and the largest EE deviation from the path [m], [rad]."""
    dev_p = dev_r = 0.0
    guess = a.plates
    for t in np.arange(1, opts.checks_between + 1) / (opts.checks_between + 1):
        lengths = (1 - t) * a.leg_lengths + t * b.leg_lengths
        fk = stack_forward_kinematics(am, lengths, base=a.plates.se3(0), guess=on_se3(guess))
        if not fk.success:
            return f"{fk.message}, between samples", dev_p, dev_r
        guess = fk.plates
        target = path.at((1 - t) * u0 + t * u1)
        state = evaluate_state(am, fk.plates, goal=target, tolerance=opts.path_tolerance)
        ee = fk.plates.se3(am.n)
        dev_p = max(dev_p, float(np.linalg.norm(ee.translation - target.translation)))
        dev_r = max(dev_r, float(np.linalg.norm(pin.log3(target.rotation.T @ ee.rotation))))
        if not state.feasible:
            return f"{describe(binding(state.violations))}, between samples", dev_p, dev_r
    return "", dev_p, dev_r


def _motion_problem(prev: StackState, state: StackState, opts: PlanOptions) -> str:
    """Why ``state`` breaks the motion step from ``prev`` ("" when every leg moved at most
    ``max_leg_step``)."""
    jump = float(np.abs(state.leg_lengths - prev.leg_lengths).max())
    if jump > opts.max_leg_step * (1 + 1e-9):
        return f"motion step: a leg would move {1e3 * jump:.2f} mm, at most {1e3 * opts.max_leg_step:.3g} mm"
    return ""


def _valid_step(
    am: AssemblerModel, path: EEPath, u0: float, u1: float, prev: StackState, state: StackState, opts: PlanOptions
) -> tuple[str, tuple[float, float]]:
    """Every check of a candidate sample ``state`` at ``u1`` after ``prev`` at ``u0``: feasible
    at the path's pose, within the motion step, valid between the two: ("" or why not, EE
    deviation between them [m], [rad])."""
    if not state.feasible:
        return describe(binding(state.violations)), (0.0, 0.0)
    problem = _motion_problem(prev, state, opts)
    if problem:
        return problem, (0.0, 0.0)
    problem, dev_p, dev_r = _between_problems(am, path, u0, u1, prev, state, opts)
    return problem, (dev_p, dev_r)


def _warm_starts(prev: StackState, goal: pin.SE3) -> list[PlateArrays]:
    """Starts of the sample at ``goal`` after ``prev``, in the order tried: the previous
    plates with the EE's move shared by every platform (:func:`.guess.spread_start`), and
    with only the EE moved."""
    return [spread_start(prev.plates, goal), _with_ee(prev.plates, goal)]


def _step(
    am: AssemblerModel, path: EEPath, u0: float, u1: float, prev: StackState, opts: PlanOptions
) -> tuple[StackState | None, str, float, tuple[float, float], bool]:
    """One sample at ``u1`` from the valid sample ``prev`` at ``u0``: (state or None, why
    not, solve time [s], EE deviation between them, whether the optimizer converged there).

    The optimizer runs from each warm start in turn until one converges to a valid sample.
    When none does, the best valid state met (an optimizer's returned state or a warm start
    itself, re-checked in full) is the sample, marked not converged."""
    goal = path.at(u1)
    motion = MotionTerm(prev.leg_lengths, opts.max_leg_step, opts.w3)
    tolerance = opts.optimize.ee_tolerance or opts.optimize.goal_tolerance
    first_why, spent, fallback = "", 0.0, []
    for start in _warm_starts(prev, goal):
        result = optimize_internal_poses(am, start, goal, opts.optimize, motion=motion)
        spent += result.time_s
        why, dev = _valid_step(am, path, u0, u1, prev, result.optimized, opts)
        if result.success and not why:
            return result.optimized, "", spent, dev, True
        first_why = first_why or (why if result.success else result.message)
        fallback += [result.optimized, evaluate_state(am, start, goal=goal, tolerance=tolerance)]
    best = _best_valid(am, path, u0, u1, prev, fallback, opts)
    if best is not None:
        logger.info("plan: at u = %.4f the optimizer did not converge; a valid state met is the sample", u1)
        return best[0], "", spent, best[1], False
    return None, first_why, spent, (0.0, 0.0), False


def _best_valid(
    am: AssemblerModel,
    path: EEPath,
    u0: float,
    u1: float,
    prev: StackState,
    candidates: list[StackState],
    opts: PlanOptions,
) -> tuple[StackState, tuple[float, float]] | None:
    """The candidate of lowest max|F| that passes every check of :func:`_valid_step` and
    the optimizer's sag limit (``max_sag``, when set), with its EE deviation between the
    samples, or None."""
    limit = opts.optimize.max_sag
    for state in sorted(candidates, key=lambda s: s.max_abs_force if s.feasible else math.inf):
        if not state.feasible:
            break
        if limit is not None and not state_sag(am, state) <= limit:
            continue
        why, dev = _valid_step(am, path, u0, u1, prev, state, opts)
        if not why:
            return state, dev
    return None


def _start_state(
    am: AssemblerModel, path: EEPath, start: StackState | PlateArrays | list | None, opts: PlanOptions
) -> tuple[StackState | None, str]:
    """The valid state the plan starts from, or (None, why not)."""
    first = path.at(0.0)
    if start is None:
        from ..solver import solve

        solved = solve(am, first, options=opts.optimize)
        if not solved.success:
            return None, one_line(f"{solved.message}, at the path's start")
        return solved.optimized, ""
    pa = start.plates if isinstance(start, StackState) else plate_arrays(am, start)
    state = evaluate_state(am, pa, goal=first, tolerance=GoalTolerance(1e-6, 1e-6))
    if not state.feasible:
        why = describe(binding(state.violations))
        return None, one_line(f"the start state is not valid at the path's start: {why}")
    return state, ""


#: The EE step is at most this share of ``n · max_leg_step``: the EE's move shared evenly by
#: the n platforms then moves each leg by at most about half the motion step.
STEP_SHARE = 0.5


def _targets(am: AssemblerModel, path: EEPath, opts: PlanOptions) -> list[tuple[float, float]]:
    """(path parameter, smallest step to it [path parameter]) of every sample after the
    start: the path split at ``position_step`` (at most ``STEP_SHARE · n · max_leg_step``)
    and ``rotation_step``; a step may be halved ``max_refinements`` times below its
    segment's spacing, counted from the last valid sample."""
    position_step = min(opts.position_step, STEP_SHARE * am.n * opts.max_leg_step)
    grid = path.parameters(position_step, opts.rotation_step)
    spacing = np.diff(grid) / 2**opts.max_refinements
    return [(float(u), float(f)) for u, f in zip(grid[1:], spacing, strict=True)]


def plan_path(
    am: AssemblerModel,
    path: EEPath,
    start: StackState | PlateArrays | list | None = None,
    options: PlanOptions | None = None,
    progress: ProgressCallback | None = None,
) -> PlanResult:
    """Force-optimized internal poses along an EE path (see module docstring).

    Args:
        path: the EE path (:class:`~assembler_pin.motion.paths.EEPath`).
        start: the stack's state at the path's start (e.g. its current pose, or
            ``am.home`` for a motion from the home pose). Default: the force-optimized
            solution of the path's first pose (:func:`~assembler_pin.solver.solve`).
        options: see :class:`PlanOptions`.
        progress: called as ``(permille of the path done, 1000, note)`` after each sample.
    """
    opts = checked_options(options, PlanOptions, "options")
    t_start = time.perf_counter()
    targets = _targets(am, path, opts)  # bounded before planning
    start_state, why = _start_state(am, path, start, opts)
    if start_state is None:
        empty = np.zeros(0)
        return PlanResult(
            False, why, path, empty, [], empty, 0, (0.0, 0.0), time.perf_counter() - t_start, opts.path_tolerance
        )
    march = _march(am, path, opts, targets, start_state, progress)
    params, states, times, refinements, dev, unconverged, reason, success = march
    result = PlanResult(
        success,
        reason,
        path,
        np.array(params),
        states,
        np.array(times),
        refinements,
        dev,
        time.perf_counter() - t_start,
        opts.path_tolerance,
        tuple(unconverged),
    )
    logger.info("plan: %s", result)
    return result


def _march(
    am: AssemblerModel,
    path: EEPath,
    opts: PlanOptions,
    targets: list,
    start_state: StackState,
    progress: ProgressCallback | None,
) -> tuple[list[float], list[StackState], list[float], int, tuple[float, float], list[int], str, bool]:
    """The samples of :func:`plan_path` from its start: each target tried, a failing step
    halved down to its segment's floor (the count restarting after each valid sample).
    Returns (parameters, states, solve times, halvings, path deviation, unconverged samples,
    reason, success)."""
    params, states, times = [0.0], [start_state], [0.0]
    refinements, dev, unconverged = 0, (0.0, 0.0), []
    reason, success = "reached the end of the path", True
    halved = 0  # halvings of the step since the last valid sample
    while targets:
        (u0, (u1, floor)) = params[-1], targets[0]
        state, why, dt, d, converged = _step(am, path, u0, u1, states[-1], opts)
        if state is None:
            if (u1 - u0) <= floor * (1 + 1e-9) or opts.max_refinements == 0:
                success = False
                where = f"no valid sample after u = {u0:.4f} of {path.segments}, step halved {halved} times"
                reason = one_line(f"{why} ({where})")
                break
            targets.insert(0, (0.5 * (u0 + u1), floor))
            refinements, halved = refinements + 1, halved + 1
            continue
        targets.pop(0)
        params.append(u1)
        states.append(state)
        times.append(dt)
        halved = 0
        if not converged:
            unconverged.append(len(states) - 1)
        dev = (max(dev[0], d[0]), max(dev[1], d[1]))
        if progress is not None:
            progress(round(1000 * u1 / path.segments), 1000, f"planning: {len(states)} samples")
    return params, states, times, refinements, dev, unconverged, reason, success
