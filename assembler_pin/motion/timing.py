"""Time law of a planned motion: leg-length trajectories within the legs' speed and
acceleration limits, resampled at a user rate.

The planned samples are joined by a monotone cubic (PCHIP) in the path parameter ``s``
(sample index): C¹ with bounded second derivative, and it never overshoots two
neighbouring samples, so a leg does not leave its stroke between them.

The time law is the simple one, documented rather than time-optimal: the motion follows
``s(t) = s₀ + (s₁ − s₀)·σ(t/T)`` with the quintic ``σ(τ) = 10τ³ − 15τ⁴ + 6τ⁵`` (rest to
rest, zero acceleration at both ends) and the shortest duration ``T`` that keeps every leg's
speed ``|L'(s) ṡ|`` and acceleration ``|L''(s) ṡ² + L'(s) s̈|`` within ``safety`` × the
configured limits (default 0.95) on a dense grid. Speeds and accelerations scale as 1/T and
1/T², so ``T`` is exact up to the grid. Without waypoint times the whole path is one such
piece; with them (``EEPath.times``), each segment between waypoints is one, of exactly the
given duration: the EE arrives at each waypoint at its time, at rest, and a segment whose
time is shorter than its shortest duration is refused. :func:`verify_trajectory` checks the
resampled result against the full limits by finite differences.

Files: :mod:`.trajfile` (format, atomic writer, strict reader); rows against the model:
:mod:`.rows`.
"""

from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

from ..collision.scene import Scene
from ..common.messages import one_line
from ..common.progress import ProgressCallback, checked_progress
from ..common.threads import one_blas_thread
from ..config.bounds import BOUNDS, check_bound
from ..config.options import checked_options
from ..dynamics import path_force_coefficients
from ..exceptions import PathError, TrajectoryError
from ..model.assembler import AssemblerModel
from .laws import TIME_LAWS, QuinticLaw, TimeLaw, TimingProblem
from .paths import EEPath
from .planner import PlanOptions, PlanResult, plan_path
from .result import MotionResult, first_bad_row, plan_prefix, rows_prefix, verify_trajectory
from .rows import evaluate_rows, trajectory_states
from .toppra_law import OptimalLaw
from .trajfile import Trajectory, read_trajectory

logger = logging.getLogger(__name__)

__all__ = [
    "law_by_name",
    "plan_trajectory",
    "read_trajectory",
    "time_parametrize",
    "trajectory_states",
]


def _pieces(plan: PlanResult) -> list[tuple[int, int, float | None]]:
    """(first sample, last sample, given duration [s] or None) of each rest-to-rest piece:
    the whole plan, or one piece per waypoint segment when the path has times."""
    last = len(plan.states) - 1
    times = plan.path.times
    if times is None:
        return [(0, last, None)]
    u = plan.parameters
    out = []
    for k in range(plan.path.segments):
        if u[-1] <= k + 1e-12:
            break
        i0 = int(np.argmin(np.abs(u - k)))
        full = u[-1] >= k + 1 - 1e-12
        i1 = int(np.argmin(np.abs(u - (k + 1)))) if full else last
        if i1 > i0:
            out.append((i0, i1, float(times[k + 1] - times[k]) if full else None))
    return out


#: How far inside the force limits the optimal law plans [N] (its force constraints hold on
#: its grid; every output row is then checked against the limits themselves).
FORCE_MARGIN = 1.0


def _force_terms(am: AssemblerModel, plan: PlanResult, spline):
    """``forces(grid)`` of :class:`~.laws.TimingProblem`: the coefficients ``a, b, c`` of
    every leg's force at the planned samples (their poses known), linear in between; at a
    sample the two one-sided ``L''`` of the PCHIP give two rows of ``b`` (a and c repeated)."""
    m = len(plan.states)
    knots = np.arange(m, dtype=float)
    d1 = spline(knots, 1)
    left, right = spline(np.clip(knots - 1e-9, 0, m - 1), 2), spline(np.clip(knots + 1e-9, 0, m - 1), 2)
    A, BL, BR, C = (np.empty((m, d1.shape[1])) for _ in range(4))
    for k, state in enumerate(plan.states):
        a, b, c = path_force_coefficients(am, state.plates, d1[k], np.stack([left[k], right[k]]).reshape(2, am.n, 6))
        A[k], BL[k], BR[k], C[k] = a.ravel(), b[0].ravel(), b[1].ravel(), c.ravel()

    def forces(grid: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        k0 = np.clip(np.floor(grid).astype(int), 0, m - 2)
        f = (grid - k0)[:, None]
        a, c = (1 - f) * A[k0] + f * A[k0 + 1], (1 - f) * C[k0] + f * C[k0 + 1]
        inner = (1 - f) * BR[k0] + f * BL[k0 + 1]
        at = np.isclose(grid, np.round(grid), rtol=0, atol=1e-12)
        kr = np.clip(np.round(grid).astype(int), 0, m - 1)
        b1 = np.where(at[:, None], BL[kr], inner)
        b2 = np.where(at[:, None], BR[kr], inner)
        return np.hstack([a, a]), np.hstack([b1, b2]), np.hstack([c, c])

    return forces


def timing_problem(
    am: AssemblerModel, plan: PlanResult, spline, v_max: float, a_max: float, grid_per_sample: int, law: str
) -> TimingProblem:
    leg = am.config.leg
    return TimingProblem(
        spline,
        len(plan.states),
        _pieces(plan),
        v_max,
        a_max,
        -leg.max_compression + FORCE_MARGIN,
        leg.max_tension - FORCE_MARGIN,
        _force_terms(am, plan, spline) if law == "optimal" else None,
        grid_per_sample,
    )


def time_parametrize(
    am: AssemblerModel,
    plan: PlanResult,
    rate: float = 50.0,
    max_speed: float | None = None,
    max_acceleration: float | None = None,
    safety: float = 0.95,
    grid_per_sample: int = 16,
    strict: bool = True,
    progress: ProgressCallback | None = None,
    time_law: str = "quintic",
) -> Trajectory:
    """The trajectory of a plan: time law within the leg limits, resampled at ``rate``.

    Args:
        plan: a plan with at least 2 samples (its valid prefix when it failed).
        rate: output samples per second [Hz] (bounds key ``plan.rate``).
        max_speed, max_acceleration: leg limits [m/s], [m/s²] (default: the config's).
        safety: fraction of the limits the time law uses (0 < safety <= 1).
        grid_per_sample: grid points of the duration check per planned step.
        strict: raise when stack FK fails at an output sample; otherwise mark that sample
            infeasible (its pose and margins NaN) — for comparing plans that may be invalid.
        progress: called as ``(rows done, rows, note)`` while the rows are checked.
        time_law: ``quintic`` or ``optimal`` (:mod:`.laws`).

    Raises:
        TrajectoryError: fewer than 2 samples, settings out of their bounds, a motion that
            would last over ``plan.duration`` or hold over ``plan.samples`` rows, waypoint
            times too short for the limits, limits that allow no motion (optimal law), or
            (strict) a failed FK.
    """
    progress = checked_progress(progress)
    return _timed(am, plan, rate, max_speed, max_acceleration, safety, grid_per_sample, strict, progress, time_law)[0]


def check_row_work(rows: int, platforms: int, rate: float, duration: float) -> None:
    """Refuse a trajectory whose rows would take too long to check (``plan.row_checks``):
    every row is checked by stack FK, statics and the inverse dynamics, about 1 ms per
    platform, before the answer is given.

    Raises:
        TrajectoryError: naming the rows, the rate, the duration and the limit.
    """
    limit = BOUNDS["plan.row_checks"].high
    if rows * platforms > limit:
        raise TrajectoryError(
            f"the trajectory would hold {rows:,} rows ({rate:g} Hz x {duration:.4g} s) of {platforms} platforms, "
            f"{rows * platforms:,} row checks, over the {limit:,.0f} of one plan (plan.row_checks): "
            "lower the rate or raise leg.max_speed / leg.max_acceleration"
        )


def _timed(
    am: AssemblerModel,
    plan: PlanResult,
    rate: float,
    max_speed: float | None = None,
    max_acceleration: float | None = None,
    safety: float = 0.95,
    grid_per_sample: int = 16,
    strict: bool = True,
    progress: ProgressCallback | None = None,
    law: str = "quintic",
) -> tuple[Trajectory, np.ndarray]:
    """:func:`time_parametrize`, and the path sample index ``s`` of each row."""
    from scipy.interpolate import PchipInterpolator

    leg = am.config.leg
    v_max = leg.max_speed if max_speed is None else max_speed
    a_max = leg.max_acceleration if max_acceleration is None else max_acceleration
    check_bound("plan.rate", rate, "rate", TrajectoryError)
    check_bound("leg.max_speed", v_max, "max_speed", TrajectoryError)
    check_bound("leg.max_acceleration", a_max, "max_acceleration", TrajectoryError)
    if not (isinstance(safety, (int, float)) and 0 < safety <= 1):
        raise TrajectoryError(f"safety must be in (0, 1], got {safety!r}")
    if len(plan.states) < 2:
        raise TrajectoryError("a trajectory needs a plan with at least 2 samples")
    L = plan.lengths.reshape(len(plan.states), -1)
    spline = PchipInterpolator(np.arange(len(L), dtype=float), L, axis=0)
    problem = timing_problem(am, plan, spline, safety * v_max, safety * a_max, grid_per_sample, law)
    schedule = law_by_name(law).schedule(problem, rate)
    check_row_work(len(schedule.times), am.n, rate, schedule.duration)
    times, s, sd, sdd = schedule.times, schedule.s, schedule.s_dot[:, None], schedule.s_ddot[:, None]
    lengths = spline(s).reshape(len(times), am.n, 6)
    d1 = spline(s, 1)
    rates = (d1 * sd).reshape(lengths.shape)
    accels = (spline(s, 2) * sd**2 + d1 * sdd).reshape(lengths.shape)
    u_of_s = np.interp(s, np.arange(len(L), dtype=float), plan.parameters)
    meta = {
        "complete": plan.success,
        "reason": plan.reason,
        "rate_hz": float(rate),
        "max_speed": float(v_max),
        "max_acceleration": float(a_max),
        "path_kind": plan.path.kind,
        "base": plan.states[0].plates.se3(0).homogeneous.tolist(),
        "waypoint_times": None if plan.path.times is None else [float(t) for t in plan.path.times],
        "time_law": law,
    }
    return evaluate_rows(am, plan, times, lengths, u_of_s, meta, strict, progress, rates, accels), s


def _valid_prefix(
    am: AssemblerModel,
    plan: PlanResult,
    traj: Trajectory,
    s: np.ndarray,
    rate: float,
    progress: ProgressCallback | None,
) -> tuple[Trajectory | None, str]:
    """The longest checked prefix of a trajectory with a bad row: the plan cut before the
    first bad row and timed again (rest to rest), up to 4 times; then the rows before it."""
    for _ in range(4):
        bad = first_bad_row(am, traj)
        if bad is None:
            return traj, f"the trajectory ends at rest at u = {plan.parameters[-1]:.4f}"
        m = min(int(np.floor(s[bad])) + 1, len(plan.states) - 1)
        if m < 2:
            return None, "no valid trajectory prefix"
        plan = plan_prefix(plan, m, plan.reason)
        traj, s = _timed(am, plan, rate, progress=progress, law=traj.meta.get("time_law", "quintic"))
    bad = first_bad_row(am, traj)
    if bad is None:
        return traj, f"the trajectory ends at rest at u = {plan.parameters[-1]:.4f}"
    if bad < 2:
        return None, "no valid trajectory prefix"
    return rows_prefix(traj, bad), f"the trajectory stops, in motion, at t = {traj.times[bad - 1]:.3f} s"


@one_blas_thread
def plan_trajectory(
    am: AssemblerModel,
    path,
    start=None,
    options=None,
    rate: float = 50.0,
    refinements: int = 2,
    progress: ProgressCallback | None = None,
    time_law: str = "auto",
    scene: Scene | str | None = None,
) -> MotionResult:
    """Plan a path, time it, and check every output sample; when a check fails between the
    samples of a successful plan, plan again with steps half as long (up to ``refinements``
    times). A failed plan is not planned again: its trajectory is its valid prefix.

    Args:
        path: the EE path (:class:`~assembler_pin.motion.paths.EEPath`).
        start: the stack's state at the path's start (e.g. ``am.home``); default the
            force-optimized pose of the path's first pose.
        options: :class:`~assembler_pin.motion.planner.PlanOptions`.
        rate: output samples per second [Hz] (bounds key ``plan.rate``).
        refinements: how many times the whole path may be planned again with half steps.
        progress: called as ``(done, total, note)`` while planning and checking.
        time_law: ``quintic``, ``optimal`` (:mod:`.laws`) or ``auto`` (default): the
            shorter of the two whose every row holds (the optimal law tries
            :data:`OPTIMAL_SAFETIES` of the limits in turn; with waypoint times only the
            quintic law applies).
        scene: obstacles and floor (a :class:`~assembler_pin.collision.scene.Scene`, a scene
            file or None): the plan keeps the clearance at and between its samples
            (:func:`~assembler_pin.motion.planner.plan_path`); the timed output rows follow
            the plan's leg lengths between its samples.

    Returns:
        A :class:`MotionResult`. Its trajectory holds valid rows only: the whole path when
        ``success``, else the valid prefix (``trajectory.meta["complete"]`` false, the
        reason in ``meta["reason"]``), or None when no prefix of 2 rows is valid.

    Raises:
        TrajectoryError: ``rate`` out of its bounds (checked before planning).
    """
    t0 = time.perf_counter()
    opts = _checked_plan_inputs(path, options, rate, refinements, time_law)
    progress = checked_progress(progress)
    attempt, noted = 0, progress
    for attempt in range(refinements + 1):
        plan = plan_path(am, path, start, opts, progress=noted, scene=scene)
        if len(plan.states) < 2:
            return MotionResult(False, plan.reason, plan, None, [plan.reason], time.perf_counter() - t0)
        try:
            traj, s, problems, durations = _best_timed(am, plan, rate, time_law, progress)
        except TrajectoryError as exc:  # a duration or row count over the bounds, waypoint times too short
            return MotionResult(False, str(exc), plan, None, [str(exc)], time.perf_counter() - t0)
        if not problems or not plan.success or attempt == refinements:
            break
        why = one_line(problems[0])[:80]
        logger.info("re-planning the whole path with half steps (%d of %d): %s", attempt + 1, refinements, why)
        noted = _replan_progress(progress, attempt + 1, refinements)
        opts = dataclasses.replace(
            opts,
            position_step=opts.position_step / 2,
            rotation_step=opts.rotation_step / 2,
            max_leg_step=opts.max_leg_step / 2,
        )
    result = _answer(am, plan, traj, s, problems, rate, noted, t0)
    result.law_durations = durations
    result.replans = attempt
    return result


def _replan_progress(progress: ProgressCallback | None, attempt: int, refinements: int) -> ProgressCallback | None:
    """``progress`` with every note saying that the path is being planned again."""
    if progress is None:
        return None
    inner = progress

    def noted(done: int, total: int, note: str) -> None:
        inner(done, total, f"re-plan {attempt}/{refinements} with half steps: {note}")

    inner(0, 1000, f"re-plan {attempt}/{refinements}: a sample failed its check, planning again with half steps")
    return noted


def _checked_plan_inputs(
    path: EEPath, options: PlanOptions | None, rate: float, refinements: int, time_law: str
) -> PlanOptions:
    """The planner's options of :func:`plan_trajectory`, or the error naming what is wrong
    (every bound checked before planning)."""
    check_bound("plan.rate", rate, "rate", TrajectoryError)
    if time_law not in (*TIME_LAWS, "auto"):
        raise TrajectoryError(f"time_law must be one of {', '.join(TIME_LAWS)} or auto, got {time_law!r}")
    opts = checked_options(options, PlanOptions, "options")
    check_bound("plan.refinements", refinements, "refinements", TrajectoryError)
    if not isinstance(path, EEPath):
        raise PathError(f"path must be an EEPath (EEPath.between(start, goal)), got {type(path).__name__}")
    return opts


#: Fractions of the legs' limits the optimal law tries, in turn, until every row holds.
OPTIMAL_SAFETIES = (0.95, 0.85, 0.7)


def _best_timed(
    am: AssemblerModel, plan: PlanResult, rate: float, choice: str, progress: ProgressCallback | None
) -> tuple[Trajectory, np.ndarray, list[str], dict[str, float]]:
    """The trajectory of ``choice`` (a law of :data:`TIME_LAWS`, or ``auto``: the shorter law
    whose rows all hold, the other when they do not), its ``s``, its problems and the duration
    each law tried reached [s] (or the reason it could not be used)."""
    laws = list(TIME_LAWS) if choice == "auto" else [choice]
    durations: dict[str, float] = {}
    reasons: dict[str, str] = {}
    order = []
    for law in laws:
        try:
            durations[law] = law_duration(am, plan, law)
            order.append(law)
        except TrajectoryError as exc:
            reasons[law] = str(exc)
    if not order:
        raise TrajectoryError("; ".join(f"{k} time law: {v}" for k, v in reasons.items()))
    order.sort(key=lambda law: durations[law])
    best = None
    for law in order:
        for safety in OPTIMAL_SAFETIES if law == "optimal" else (0.95,):
            traj, s = _timed(am, plan, rate, safety=safety, progress=progress, law=law)
            problems = verify_trajectory(am, traj)
            durations[law] = traj.duration
            if not problems:
                return traj, s, problems, durations
            if best is None:
                best = (traj, s, problems, durations)
            if not plan.success:  # a failed plan's prefix: the first timing is the answer
                return best
    assert best is not None
    return best


def law_duration(am: AssemblerModel, plan: PlanResult, law: str, safety: float = 0.95) -> float:
    """The duration of ``law`` on the plan [s], without evaluating rows."""
    from scipy.interpolate import PchipInterpolator

    leg = am.config.leg
    L = plan.lengths.reshape(len(plan.states), -1)
    spline = PchipInterpolator(np.arange(len(L), dtype=float), L, axis=0)
    problem = timing_problem(am, plan, spline, safety * leg.max_speed, safety * leg.max_acceleration, 16, law)
    return law_by_name(law).duration(problem)


def _answer(
    am: AssemblerModel,
    plan: PlanResult,
    traj: Trajectory,
    s: np.ndarray,
    problems: list[str],
    rate: float,
    progress: ProgressCallback | None,
    t0: float,
) -> MotionResult:
    """The MotionResult of a timed plan: its trajectory cut to the valid prefix when a row
    fails, ``meta["complete"]`` and ``meta["reason"]`` set."""
    success = plan.success and not problems
    reasons = ([] if plan.success else [plan.reason]) + problems
    final: Trajectory | None = traj
    if problems:
        final, cut = _valid_prefix(am, plan, traj, s, rate, progress)
        reasons.append(cut)
    reason = plan.reason if success else one_line("; ".join(reasons))
    if final is not None:
        final.meta.update(complete=success, reason=reason)
    return MotionResult(success, reason, plan, final, problems, time.perf_counter() - t0)


def law_by_name(name: str) -> TimeLaw:
    """The law called ``name`` (:data:`TIME_LAWS`)."""
    if name == "quintic":
        return QuinticLaw()
    if name == "optimal":
        return OptimalLaw()
    raise TrajectoryError(f"time law must be one of {', '.join(TIME_LAWS)} (or auto), got {name!r}")
