"""Time law of a planned motion: leg-length trajectories within the legs' speed and
acceleration limits, resampled at a user rate, written to and read from CSV/JSON.

The planned samples are joined by a monotone cubic (PCHIP) in the path parameter ``s``
(sample index): C¹ with bounded second derivative, and it never overshoots two
neighbouring samples, so a leg does not leave its stroke between them.

The time law is the simple one, documented rather than time-optimal: the whole motion
follows ``s(t) = S·σ(t/T)`` with the quintic ``σ(τ) = 10τ³ − 15τ⁴ + 6τ⁵`` (rest to rest,
zero acceleration at both ends) and the shortest duration ``T`` that keeps every leg's
speed ``|L'(s) ṡ|`` and acceleration ``|L''(s) ṡ² + L'(s) s̈|`` within ``safety`` × the
configured limits (default 0.95) on a dense grid. Speeds and accelerations scale as 1/T and
1/T², so ``T`` is exact up to the grid. It is slower than a time-optimal law (TOPP) on long
paths whose hardest part is short; :func:`verify_trajectory` checks the resampled result
against the full limits by finite differences.
"""

from __future__ import annotations

import csv
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..constraints import GoalTolerance, leg_limit_margins
from ..exceptions import TrajectoryError
from ..kinematics import PlateArrays, se3_to_taa, stack_forward_kinematics
from ..model import AssemblerModel
from ..options import checked_options
from ..state import StackState, evaluate_state
from .planner import PlanResult

__all__ = [
    "MotionResult",
    "Trajectory",
    "TrajectoryError",
    "plan_trajectory",
    "read_trajectory",
    "time_parametrize",
    "trajectory_states",
    "verify_trajectory",
]


@dataclass
class Trajectory:
    """Leg-length commands over time, with what they do.

    Attributes:
        times: (T,) [s], from 0.
        lengths: (T, n, 6) leg lengths [m].
        ee: (T, 6) EE pose as TAA (position [m], rotation vector [rad]), from stack FK.
        max_abs_force: (T,) max|F| [N].
        margins: per constraint kind, (T,) the smallest margin over the legs:
            ``stroke`` [m], ``deflection`` [rad], ``rise`` [m], ``force`` [N] (limit − |F|),
            ``path_position`` [m] and ``path_rotation`` [rad] (tolerance − distance from
            the planned path); negative means violated.
        feasible: (T,) every constraint holds.
        platforms: n.
    """

    times: np.ndarray
    lengths: np.ndarray
    ee: np.ndarray
    max_abs_force: np.ndarray
    margins: dict[str, np.ndarray]
    feasible: np.ndarray
    platforms: int
    meta: dict = field(default_factory=dict)

    @property
    def duration(self) -> float:
        return float(self.times[-1])

    def speeds(self) -> np.ndarray:
        """(T-1, n, 6) leg speeds by finite differences [m/s]."""
        return np.diff(self.lengths, axis=0) / np.diff(self.times)[:, None, None]

    def accelerations(self) -> np.ndarray:
        """(T-2, n, 6) leg accelerations by finite differences [m/s²]."""
        v = self.speeds()
        mid = 0.5 * (self.times[1:] + self.times[:-1])
        return np.diff(v, axis=0) / np.diff(mid)[:, None, None]

    def __repr__(self) -> str:
        return (
            f"Trajectory({len(self.times)} samples, {self.duration:.2f} s, peak max|F| "
            f"{self.max_abs_force.max():.2f} N, all feasible: {bool(self.feasible.all())})"
        )

    # ------------------------------------------------------------------ files
    def columns(self) -> list[str]:
        legs = [f"L_sp{j}_leg{i}" for j in range(self.platforms) for i in range(6)]
        return ["t", *legs, "ee_x", "ee_y", "ee_z", "ee_rx", "ee_ry", "ee_rz", "max_abs_force",
                *[f"margin_{k}" for k in self.margins], "feasible"]  # fmt: skip

    def rows(self) -> np.ndarray:
        T = len(self.times)
        return np.hstack([self.times[:, None], self.lengths.reshape(T, -1), self.ee, self.max_abs_force[:, None],
                          np.stack(list(self.margins.values()), axis=1), self.feasible[:, None]])  # fmt: skip

    def write(self, path: str | Path) -> Path:
        """Write as CSV (``.csv``) or JSON (any other suffix); units SI, forces in N."""
        path = Path(path)
        if path.suffix.lower() == ".csv":
            with path.open("w", newline="") as fh:
                w = csv.writer(fh)
                w.writerow(self.columns())
                for row in self.rows():
                    w.writerow([repr(float(x)) for x in row])
        else:
            doc = {"platforms": self.platforms, "columns": self.columns(), "rows": self.rows().tolist(),
                   "meta": self.meta}  # fmt: skip
            path.write_text(json.dumps(doc))
        return path


def read_trajectory(path: str | Path) -> Trajectory:
    """A trajectory written by :meth:`Trajectory.write` (CSV or JSON).

    Raises:
        TrajectoryError: unreadable, or not a trajectory file.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise TrajectoryError(f"cannot read trajectory '{path}': {exc}") from None
    meta: dict = {}
    try:
        if path.suffix.lower() == ".csv":
            lines = list(csv.reader(text.splitlines()))
            columns, rows = lines[0], np.array([[float(x) for x in r] for r in lines[1:] if r])
        else:
            doc = json.loads(text)
            columns, rows, meta = doc["columns"], np.array(doc["rows"], dtype=float), doc.get("meta", {})
        legs = [c for c in columns if c.startswith("L_sp")]
        n = len(legs) // 6
        if n < 1 or len(legs) != 6 * n or columns[0] != "t" or rows.ndim != 2 or rows.shape[1] != len(columns):
            raise ValueError("columns do not describe a trajectory")
    except (ValueError, KeyError, IndexError, TypeError, json.JSONDecodeError) as exc:
        raise TrajectoryError(f"'{path}' is not a trajectory file: {exc}") from None
    col = {c: k for k, c in enumerate(columns)}
    margins = {c[len("margin_") :]: rows[:, k] for c, k in col.items() if c.startswith("margin_")}
    return Trajectory(
        times=rows[:, 0],
        lengths=rows[:, [col[c] for c in legs]].reshape(-1, n, 6),
        ee=rows[:, [col[f"ee_{a}"] for a in ("x", "y", "z", "rx", "ry", "rz")]],
        max_abs_force=rows[:, col["max_abs_force"]],
        margins=margins,
        feasible=rows[:, col["feasible"]] > 0.5,
        platforms=n,
        meta=meta,
    )


# ---------------------------------------------------------------------- time law
def _quintic(tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """σ(τ) = 10τ³ − 15τ⁴ + 6τ⁵ and its first two derivatives: rest to rest on [0, 1]."""
    return (
        tau**3 * (10 - 15 * tau + 6 * tau**2),
        30 * tau**2 * (1 - tau) ** 2,
        60 * tau * (1 - tau) * (1 - 2 * tau),
    )


def _shortest_duration(spline, span: float, v_max: float, a_max: float, grid: int) -> float:
    """Smallest T such that ``L(span·σ(t/T))`` keeps every leg within the limits.

    Speed is ``L'·span·σ'/T`` and acceleration ``(L''·span²·σ'² + L'·span·σ'')/T²``: both
    scale with T, so T follows from their largest values on a dense grid of τ.
    """
    tau = np.linspace(0.0, 1.0, grid)
    sigma, d_sigma, dd_sigma = _quintic(tau)
    s = span * sigma
    d1, d2 = spline(s, 1), spline(s, 2)
    speed = np.abs(d1 * (span * d_sigma)[:, None]).max()
    accel = np.abs(d2 * ((span * d_sigma) ** 2)[:, None] + d1 * (span * dd_sigma)[:, None]).max()
    return max(speed / v_max, np.sqrt(accel / a_max), 1e-9)


def time_parametrize(
    am: AssemblerModel,
    plan: PlanResult,
    rate: float = 50.0,
    max_speed: float | None = None,
    max_acceleration: float | None = None,
    safety: float = 0.95,
    grid_per_sample: int = 16,
    strict: bool = True,
) -> Trajectory:
    """The trajectory of a plan: time law within the leg limits, resampled at ``rate``.

    Args:
        plan: a plan with at least 2 samples (its valid prefix when it failed).
        rate: output samples per second [Hz].
        max_speed, max_acceleration: leg limits [m/s], [m/s²] (default: the config's).
        safety: fraction of the limits the time law uses (0 < safety <= 1).
        grid_per_sample: grid points of the duration check per planned step.
        strict: raise when stack FK fails at an output sample; otherwise mark that sample
            infeasible (its pose and margins NaN) — for comparing plans that may be invalid.

    Raises:
        TrajectoryError: fewer than 2 samples, invalid settings, or (strict) a failed FK.
    """
    from scipy.interpolate import PchipInterpolator

    leg = am.config.leg
    v_max = leg.max_speed if max_speed is None else max_speed
    a_max = leg.max_acceleration if max_acceleration is None else max_acceleration
    for name, value in (("rate", rate), ("max_speed", v_max), ("max_acceleration", a_max)):
        if not (np.isfinite(value) and value > 0):
            raise TrajectoryError(f"{name} must be a finite number > 0, got {value}")
    if not 0 < safety <= 1:
        raise TrajectoryError(f"safety must be in (0, 1], got {safety}")
    if len(plan.states) < 2:
        raise TrajectoryError("a trajectory needs a plan with at least 2 samples")
    L = plan.lengths.reshape(len(plan.states), -1)
    s_knots = np.arange(len(L), dtype=float)
    spline = PchipInterpolator(s_knots, L, axis=0)
    span = float(s_knots[-1])
    duration = _shortest_duration(spline, span, safety * v_max, safety * a_max, grid_per_sample * len(L) + 1)
    count = max(2, int(np.ceil(duration * rate)) + 1)
    times = np.linspace(0.0, duration, count)
    s_of_t = span * _quintic(times / duration)[0]
    lengths = spline(s_of_t).reshape(count, am.n, 6)
    u_of_s = np.interp(s_of_t, s_knots, plan.parameters)
    meta = {"rate_hz": rate, "max_speed": v_max, "max_acceleration": a_max, "path_kind": plan.path.kind,
            "base": plan.states[0].plates.se3(0).homogeneous.tolist()}  # fmt: skip
    return _evaluate(am, plan, times, lengths, u_of_s, meta, strict)


def _evaluate(am: AssemblerModel, plan: PlanResult, times: np.ndarray, lengths: np.ndarray, u: np.ndarray,
              meta: dict, strict: bool = True) -> Trajectory:  # fmt: skip
    """Stack FK, statics and every constraint margin at each resampled time."""
    leg = am.config.leg
    tol: GoalTolerance = (
        plan.path_tolerance if hasattr(plan, "path_tolerance") else GoalTolerance(2e-3, np.deg2rad(0.5))
    )
    T = len(times)
    ee = np.empty((T, 6))
    force = np.empty(T)
    margins = {k: np.empty(T) for k in ("stroke", "deflection", "rise", "force", "path_position", "path_rotation")}
    feasible = np.empty(T, dtype=bool)
    base = plan.states[0].plates.se3(0)
    guess = plan.states[0].plates
    knots = plan.parameters
    for k in range(T):
        near = int(np.clip(np.searchsorted(knots, u[k]), 0, len(knots) - 1))
        fk = stack_forward_kinematics(am, lengths[k], base=base, guess=plan.states[near].plates if k == 0 else guess)
        if not fk.success and k > 0:  # after a fast stretch, the nearest planned sample is the better guess
            fk = stack_forward_kinematics(am, lengths[k], base=base, guess=plan.states[near].plates)
        if not fk.success:
            if strict:
                raise TrajectoryError(f"stack FK failed at t = {times[k]:.3f} s: {fk.message}")
            ee[k], force[k], feasible[k] = np.nan, np.nan, False
            for values in margins.values():
                values[k] = np.nan
            continue
        guess = fk.plates
        target = plan.path.at(u[k])
        state = evaluate_state(am, fk.plates, goal=target, tolerance=tol)
        pose = fk.plates.se3(am.n)
        ee[k] = se3_to_taa(pose)
        force[k] = state.max_abs_force
        rows = leg_limit_margins(leg, state.legs.lengths, np.cos(state.legs.deflection), state.legs.rise, 0.0)
        margins["stroke"][k] = rows[:2].min()
        margins["deflection"][k] = leg.max_deflection - state.legs.deflection.max()  # [rad], not the cosine rows
        margins["rise"][k] = rows[4].min()
        margins["force"][k] = min(leg.max_tension - state.forces.max(), leg.max_compression + state.forces.min())
        margins["path_position"][k] = tol.position - np.linalg.norm(pose.translation - target.translation)
        margins["path_rotation"][k] = tol.rotation - np.linalg.norm(pin.log3(target.rotation.T @ pose.rotation))
        feasible[k] = state.feasible
    return Trajectory(times, lengths, ee, force, margins, feasible, am.n, meta)


def trajectory_states(
    am: AssemblerModel, traj: Trajectory, frames: int | None = None, tolerance: float = 1e-6
) -> tuple[np.ndarray, list[StackState]]:
    """The stack at the trajectory's samples, rebuilt from its leg lengths by stack FK.

    Each FK starts from the previous pose (the first from the home pose), and the EE it
    gives must match the EE pose written in the trajectory; the base is the trajectory's
    ``meta["base"]`` (the home base plate when absent).

    Args:
        frames: how many evenly spaced samples (default: all).
        tolerance: largest EE mismatch with the file [m, rad].

    Returns:
        (times [s], states) of the chosen samples.

    Raises:
        TrajectoryError: a different stack size, a failed FK, or an EE that does not match.
    """
    if traj.platforms != am.n:
        raise TrajectoryError(f"the trajectory is for {traj.platforms} platforms, the model has {am.n}")
    count = len(traj.times) if frames is None else max(2, min(int(frames), len(traj.times)))
    picks = np.unique(np.round(np.linspace(0, len(traj.times) - 1, count)).astype(int))
    base = pin.SE3(np.asarray(traj.meta["base"], dtype=float)) if "base" in traj.meta else am.home[0]
    home = evaluate_state(am, am.home).plates
    guess = PlateArrays(home.R.copy(), home.p.copy())
    guess.R[0], guess.p[0] = base.rotation, base.translation
    states = []
    for k in picks:
        fk = stack_forward_kinematics(am, traj.lengths[k], base=base, guess=guess)
        if not fk.success:
            raise TrajectoryError(f"stack FK failed at t = {traj.times[k]:.3f} s: {fk.message}")
        ee = fk.plates.se3(am.n)
        mismatch = np.abs(se3_to_taa(ee) - traj.ee[k]).max()
        if not mismatch <= tolerance:
            raise TrajectoryError(f"at t = {traj.times[k]:.3f} s the lengths put the EE {mismatch:.2e} from the "
                                  "pose written in the file")  # fmt: skip
        guess = fk.plates
        states.append(evaluate_state(am, fk.plates))
    return traj.times[picks], states


def verify_trajectory(am: AssemblerModel, traj: Trajectory, rtol: float = 1e-6) -> list[str]:
    """Problems of a trajectory (empty when none): infeasible samples, leg speeds or
    accelerations over the config's limits (finite differences of the samples)."""
    leg = am.config.leg
    problems = []
    if not traj.feasible.all():
        problems.append(f"{int((~traj.feasible).sum())} infeasible samples")
    v = np.abs(traj.speeds()).max()
    if v > leg.max_speed * (1 + rtol):
        problems.append(f"leg speed {v:.4g} m/s over the limit {leg.max_speed:g}")
    if len(traj.times) > 2:
        a = np.abs(traj.accelerations()).max()
        if a > leg.max_acceleration * (1 + rtol):
            problems.append(f"leg acceleration {a:.4g} m/s² over the limit {leg.max_acceleration:g}")
    return problems


@dataclass
class MotionResult:
    """A planned, timed and checked motion (:func:`plan_trajectory`).

    Attributes:
        success: the plan reached the end of the path and every output sample of the
            trajectory is valid and within the legs' speed and acceleration limits.
        reason: why not, or what happened.
        plan: the force-optimized samples (:class:`~assembler_pin.motion.planner.PlanResult`).
        trajectory: the timed leg-length commands (None when the plan has < 2 samples).
        problems: what the trajectory check found (empty when nothing).
        time_s: wall time of planning, timing and checking [s].
    """

    success: bool
    reason: str
    plan: PlanResult
    trajectory: Trajectory | None
    problems: list[str]
    time_s: float

    @property
    def samples(self) -> int:
        """Number of planned (force-optimized) samples."""
        return len(self.plan.states)

    @property
    def peak_max_abs_force(self) -> float:
        """Largest max|F| over the trajectory (over the samples without one) [N]."""
        if self.trajectory is not None:
            return float(self.trajectory.max_abs_force.max())
        return float(self.plan.max_abs_forces.max()) if self.plan.states else math.nan

    @property
    def total_leg_travel(self) -> float:
        """Σ over legs of the distance each travels along the planned samples [m]."""
        return float(np.abs(np.diff(self.plan.lengths, axis=0)).sum()) if self.samples > 1 else 0.0

    @property
    def duration(self) -> float:
        """Duration of the trajectory [s] (nan without one)."""
        return self.trajectory.duration if self.trajectory is not None else math.nan

    def to_dict(self) -> dict:
        """The JSON of ``assembler-pin plan --json``."""
        solve_times = self.plan.solve_times_s[1:]
        return {
            "success": self.success,
            "reason": self.reason,
            "samples": self.samples,
            "peak_max_abs_force": self.peak_max_abs_force if self.plan.states else None,
            "total_leg_travel_m": self.total_leg_travel,
            "duration_s": self.duration if self.trajectory is not None else None,
            "median_sample_time_s": float(np.median(solve_times)) if len(solve_times) else None,
            "plan_time_s": self.plan.time_s,
            "time_s": self.time_s,
        }

    def __repr__(self) -> str:
        return (
            f"MotionResult(success={self.success}, {self.samples} samples, peak max|F| "
            f"{self.peak_max_abs_force:.2f} N, travel {self.total_leg_travel:.3f} m, duration "
            f"{self.duration:.2f} s, reason={self.reason!r})"
        )


def plan_trajectory(
    am: AssemblerModel,
    path,
    start=None,
    options=None,
    rate: float = 50.0,
    refinements: int = 2,
) -> MotionResult:
    """Plan a path, time it, and check every output sample; when a check fails between
    samples, plan again with steps half as long (up to ``refinements`` times).

    Args:
        path: the EE path (:class:`~assembler_pin.motion.paths.EEPath`).
        start: the stack's state at the path's start (e.g. ``am.home``); default the
            force-optimized pose of the path's first pose.
        options: :class:`~assembler_pin.motion.planner.PlanOptions`.
        rate: output samples per second [Hz].
        refinements: how many times the whole path may be planned again with half steps.

    Returns:
        A :class:`MotionResult`: the plan, the trajectory (None when the plan has fewer
        than 2 samples) and the problems the check found.
    """
    import dataclasses

    from .planner import PlanOptions, plan_path

    t0 = time.perf_counter()
    opts = checked_options(options, PlanOptions, "options")
    for attempt in range(refinements + 1):
        plan = plan_path(am, path, start, opts)
        if len(plan.states) < 2:
            return MotionResult(False, plan.reason, plan, None, [plan.reason], time.perf_counter() - t0)
        traj = time_parametrize(am, plan, rate=rate)
        problems = verify_trajectory(am, traj)
        if not problems or attempt == refinements:
            success = plan.success and not problems
            reason = (
                plan.reason
                if plan.success and not problems
                else "; ".join(([] if plan.success else [plan.reason]) + problems)
            )
            return MotionResult(success, reason, plan, traj, problems, time.perf_counter() - t0)
        opts = dataclasses.replace(opts, position_step=opts.position_step / 2, rotation_step=opts.rotation_step / 2,
                                   max_leg_step=opts.max_leg_step / 2)  # fmt: skip
    raise AssertionError("unreachable")
