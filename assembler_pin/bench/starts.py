"""The default start portfolio against every start: ``solve`` on random goals over the stroke."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from ..model.assembler import AssemblerModel
from .speed import benchmark_solve_starts
from .timing import random_reachable_plates

__all__ = ["STARTS_GOALS", "STROKE_SPREAD", "benchmark_default_starts", "stroke_goals"]

#: How many random goals the row solves, each with the default and with every start.
STARTS_GOALS = 40

#: The share of the stroke the legs of those goals' stacks are drawn from: nearly all of it,
#: where the starts reach different local optima (the bench's other random goals stay near
#: mid-stroke, where every start ends at one optimum).
STROKE_SPREAD = 0.9


def stroke_goals(am: AssemblerModel, count: int = STARTS_GOALS, seed: int = 0) -> tuple[pin.SE3, ...]:
    """EE poses (world) of ``count`` random stacks with legs over :data:`STROKE_SPREAD` of the
    stroke (stack FK, fixed seed): goals known to be reachable."""
    rng = np.random.default_rng(seed)
    goals = []
    for _ in range(count):
        plates = random_reachable_plates(am, rng, spread=STROKE_SPREAD)[1]
        goals.append(pin.SE3(plates.R[-1].copy(), plates.p[-1].copy()))
    return tuple(goals)


def benchmark_default_starts(am: AssemblerModel, count: int = STARTS_GOALS, seed: int = 0) -> dict[str, Any]:
    """``solve`` by default and with ``starts="all"`` on :func:`stroke_goals`, interleaved
    (:func:`~assembler_pin.bench.speed.benchmark_solve_starts`): the default's p50 and p95
    [ms] and their ratio (target ≤ 3), every start's p50 and p95 [ms], the default's total time
    over every start's (target ≤ 1), its slowest goal's ratio (target < 2) and the goals where
    its optimum is worse by more than 0.1 % (target 0)."""
    out = benchmark_solve_starts(am, stroke_goals(am, count, seed))
    return {
        "solve_p50_ms": 1e3 * out["first_p50_s"],
        "solve_p95_ms": 1e3 * out["first_p95_s"],
        "solve_p95_over_p50": out["first_p95_s"] / out["first_p50_s"],
        "solve_all_p50_ms": 1e3 * out["all_p50_s"],
        "solve_all_p95_ms": 1e3 * out["all_p95_s"],
        "solve_time_over_all": out["first_time_over_all"],
        "solve_slowest_goal_over_all": out["first_slowest_goal_over_all"],
        "solve_goals_worse_than_all": out["first_goals_worse"],
    }
