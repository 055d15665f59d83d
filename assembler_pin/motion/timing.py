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
import math
import time

import numpy as np

from ..bounds import BOUNDS, check_bound
from ..exceptions import PathError, TrajectoryError
from ..messages import one_line
from ..model import AssemblerModel
from ..options import checked_options
from ..progress import ProgressCallback
from ..threads import one_blas_thread
from .paths import EEPath
from .planner import PlanResult
from .result import MotionResult, first_bad_row, verify_trajectory
from .rows import check_trajectory, trajectory_states
from .trajfile import Trajectory, read_trajectory

__all__ = [
    "MotionResult",
    "Trajectory",
    "TrajectoryError",
    "check_trajectory",
    "plan_trajectory",
    "read_trajectory",
    "time_parametrize",
    "trajectory_states",
    "verify_trajectory",
]


def _quintic(tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """σ(τ) = 10τ³ − 15τ⁴ + 6τ⁵ and its first two derivatives: rest to rest on [0, 1]."""
    return (
        tau**3 * (10 - 15 * tau + 6 * tau**2),
        30 * tau**2 * (1 - tau) ** 2,
        60 * tau * (1 - tau) * (1 - 2 * tau),
    )


def _shortest_duration(spline, s0: float, s1: float, v_max: float, a_max: float, grid: int) -> float:
    """Smallest T such that ``L(s0 + (s1 − s0)·σ(t/T))`` keeps every leg within the limits.

    Speed is ``L'·span·σ'/T`` and acceleration ``(L''·span²·σ'² + L'·span·σ'')/T²``: both
    scale with T, so T follows from their largest values on a dense grid of τ.
    """
    span = s1 - s0
    tau = np.linspace(0.0, 1.0, grid)
    sigma, d_sigma, dd_sigma = _quintic(tau)
    s = s0 + span * sigma
    d1, d2 = spline(s, 1), spline(s, 2)
    speed = np.abs(d1 * (span * d_sigma)[:, None]).max()
    accel = np.abs(d2 * ((span * d_sigma) ** 2)[:, None] + d1 * (span * dd_sigma)[:, None]).max()
    return max(speed / v_max, np.sqrt(accel / a_max), 1e-9)


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


def _time_grid(
    spline, plan: PlanResult, rate: float, v_max: float, a_max: float, grid_per_sample: int
) -> tuple[np.ndarray, np.ndarray]:
    """(times [s], s of each time) of the time law (see the module docstring), after checking
    its duration and row count against the bounds table, before allocating the rows."""
    pieces = []
    for i0, i1, given in _pieces(plan):
        shortest = _shortest_duration(spline, i0, i1, v_max, a_max, grid_per_sample * (i1 - i0 + 1) + 1)
        if given is not None and shortest > given * (1 + 1e-9):
            u0, u1 = plan.parameters[i0], plan.parameters[i1]
            raise TrajectoryError(
                f"waypoint times: the segment u = {u0:g} → {u1:g} needs at least {shortest:.4g} s "
                f"at the legs' limits (x safety), the path gives {given:.4g} s"
            )
        pieces.append((i0, i1, shortest if given is None else given))
    total = sum(d for *_, d in pieces)
    limit = BOUNDS["plan.duration"].high
    if not total <= limit:
        raise TrajectoryError(
            f"the motion would take {total:.4g} s (leg.max_speed, leg.max_acceleration, waypoint times), "
            f"over the {limit:g} s a planned motion may last (plan.duration)"
        )
    counts = [max(1, math.ceil(d * rate - 1e-9)) for *_, d in pieces]
    rows = sum(counts) + 1
    if rows > BOUNDS["plan.samples"].high:
        raise TrajectoryError(
            f"{rows} output samples ({rate:g} Hz x {total:.4g} s) is over the "
            f"{BOUNDS['plan.samples'].high:,.0f} a trajectory may hold: lower the rate"
        )
    times, s = [np.zeros(1)], [np.zeros(1)]
    start = 0.0
    for (i0, i1, d), c in zip(pieces, counts, strict=True):
        tau = np.arange(1, c + 1) / c
        times.append(start + d * tau)
        s.append(i0 + (i1 - i0) * _quintic(tau)[0])
        start += d
    return np.concatenate(times), np.concatenate(s)


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

    Raises:
        TrajectoryError: fewer than 2 samples, settings out of their bounds, a motion that
            would last over ``plan.duration`` or hold over ``plan.samples`` rows, waypoint
            times too short for the limits, or (strict) a failed FK.
    """
    return _timed(am, plan, rate, max_speed, max_acceleration, safety, grid_per_sample, strict, progress)[0]


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
) -> tuple[Trajectory, np.ndarray]:
    """:func:`time_parametrize`, and the path sample index ``s`` of each row."""
    from scipy.interpolate import PchipInterpolator

    from .rows import evaluate_rows

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
    times, s = _time_grid(spline, plan, rate, safety * v_max, safety * a_max, grid_per_sample)
    lengths = spline(s).reshape(len(times), am.n, 6)
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
    }
    return evaluate_rows(am, plan, times, lengths, u_of_s, meta, strict, progress), s


def _plan_prefix(plan: PlanResult, m: int, why: str) -> PlanResult:
    """The plan's first ``m`` samples, marked failed with ``why``."""
    return dataclasses.replace(
        plan,
        success=False,
        reason=why,
        states=plan.states[:m],
        parameters=plan.parameters[:m],
        solve_times_s=plan.solve_times_s[:m],
    )


def _rows_prefix(traj: Trajectory, count: int) -> Trajectory:
    """The trajectory's first ``count`` rows (a new object, meta copied)."""
    return Trajectory(
        traj.times[:count],
        traj.lengths[:count],
        traj.ee[:count],
        traj.max_abs_force[:count],
        {k: v[:count] for k, v in traj.margins.items()},
        traj.feasible[:count],
        traj.platforms,
        dict(traj.meta),
    )


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
        plan = _plan_prefix(plan, m, plan.reason)
        traj, s = _timed(am, plan, rate, progress=progress)
    bad = first_bad_row(am, traj)
    if bad is None:
        return traj, f"the trajectory ends at rest at u = {plan.parameters[-1]:.4f}"
    if bad < 2:
        return None, "no valid trajectory prefix"
    return _rows_prefix(traj, bad), f"the trajectory stops, in motion, at t = {traj.times[bad - 1]:.3f} s"


@one_blas_thread
def plan_trajectory(
    am: AssemblerModel,
    path,
    start=None,
    options=None,
    rate: float = 50.0,
    refinements: int = 2,
    progress: ProgressCallback | None = None,
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

    Returns:
        A :class:`MotionResult`. Its trajectory holds valid rows only: the whole path when
        ``success``, else the valid prefix (``trajectory.meta["complete"]`` false, the
        reason in ``meta["reason"]``), or None when no prefix of 2 rows is valid.

    Raises:
        TrajectoryError: ``rate`` out of its bounds (checked before planning).
    """
    from .planner import PlanOptions, plan_path

    check_bound("plan.rate", rate, "rate", TrajectoryError)
    t0 = time.perf_counter()
    opts = checked_options(options, PlanOptions, "options")
    check_bound("plan.refinements", refinements, "refinements", TrajectoryError)
    if not isinstance(path, EEPath):
        raise PathError(f"path must be an EEPath (EEPath.between(start, goal)), got {type(path).__name__}")
    for attempt in range(refinements + 1):
        plan = plan_path(am, path, start, opts, progress=progress)
        if len(plan.states) < 2:
            return MotionResult(False, plan.reason, plan, None, [plan.reason], time.perf_counter() - t0)
        try:
            traj, s = _timed(am, plan, rate, progress=progress)
        except TrajectoryError as exc:  # a duration or row count over the bounds, waypoint times too short
            return MotionResult(False, str(exc), plan, None, [str(exc)], time.perf_counter() - t0)
        problems = verify_trajectory(am, traj)
        if not problems or not plan.success or attempt == refinements:
            break
        opts = dataclasses.replace(
            opts,
            position_step=opts.position_step / 2,
            rotation_step=opts.rotation_step / 2,
            max_leg_step=opts.max_leg_step / 2,
        )
    return _answer(am, plan, traj, s, problems, rate, progress, t0)


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
