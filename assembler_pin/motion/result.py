"""What :func:`~assembler_pin.motion.timing.plan_trajectory` answers, and the check of a
timed trajectory against the legs' limits."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..model.assembler import AssemblerModel
from .planner import PlanResult
from .trajfile import Trajectory

__all__ = ["MotionResult", "first_bad_row", "plan_prefix", "rows_prefix", "verify_trajectory"]


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


def first_bad_row(am: AssemblerModel, traj: Trajectory, rtol: float = 1e-6) -> int | None:
    """Index of the first row that is infeasible or ends a speed or acceleration over the
    config's limits (finite differences), None when every row is good."""
    leg = am.config.leg
    bad = [int(np.argmax(~traj.feasible))] if not traj.feasible.all() else []
    fast = (np.abs(traj.speeds()) > leg.max_speed * (1 + rtol)).any(axis=(1, 2))
    if fast.any():
        bad.append(int(np.argmax(fast)) + 1)
    if len(traj.times) > 2:
        jerk = (np.abs(traj.accelerations()) > leg.max_acceleration * (1 + rtol)).any(axis=(1, 2))
        if jerk.any():
            bad.append(int(np.argmax(jerk)) + 2)
    return min(bad) if bad else None


@dataclass
class MotionResult:
    """A planned, timed and checked motion (:func:`plan_trajectory`).

    Attributes:
        success: the plan reached the end of the path and every output sample of the
            trajectory is valid and within the legs' speed and acceleration limits.
        reason: why not, or what happened.
        plan: the force-optimized samples (:class:`~assembler_pin.motion.planner.PlanResult`).
        trajectory: the timed leg-length commands, valid rows only: the whole path when
            ``success``, else the valid prefix (None when no prefix of 2 rows is valid).
        problems: what the trajectory check found (empty when nothing).
        time_s: wall time of planning, timing and checking [s].
        law_durations: the duration [s] each time law tried reached on the plan
            (:mod:`~assembler_pin.motion.laws`).
        replans: how many times the whole path was planned again with half steps because
            an output sample failed its check (0: the first plan held).
    """

    success: bool
    reason: str
    plan: PlanResult
    trajectory: Trajectory | None
    problems: list[str]
    time_s: float
    law_durations: dict[str, float] = field(default_factory=dict)
    replans: int = 0

    @property
    def time_law(self) -> str | None:
        """The time law of the trajectory (None without one)."""
        return None if self.trajectory is None else self.trajectory.meta.get("time_law")

    @property
    def complete(self) -> bool:
        """The trajectory covers the whole path (False: the valid prefix, or none)."""
        return self.trajectory is not None and self.trajectory.complete

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
            "time_law": self.time_law,
            "law_durations_s": dict(self.law_durations),
            "replans": self.replans,
            "peak_max_abs_dynamic_force": (
                float(np.nanmax(self.trajectory.max_abs_dynamic_force)) if self.trajectory is not None else None
            ),
            "complete": self.complete,
            "rows": len(self.trajectory.times) if self.trajectory is not None else 0,
            "path_reached": float(self.plan.parameters[-1]) if self.plan.states else None,
            "path_segments": self.plan.path.segments,
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


def plan_prefix(plan: PlanResult, m: int, why: str) -> PlanResult:
    """The plan's first ``m`` samples, marked failed with ``why``."""
    return dataclasses.replace(
        plan,
        success=False,
        reason=why,
        states=plan.states[:m],
        parameters=plan.parameters[:m],
        solve_times_s=plan.solve_times_s[:m],
    )


def rows_prefix(traj: Trajectory, count: int) -> Trajectory:
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
        None if traj.dynamic_forces is None else traj.dynamic_forces[:count],
    )
