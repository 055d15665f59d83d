"""Benchmarks: median wall time per call of the hot computations.

Run with ``assembler-pin bench [--json] [--repeat N]``. Times are medians over
``repeat`` calls on random valid poses of the default (or given) configuration; they
measure this machine, not a target.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ..common.progress import ProgressCallback
from ..config.bounds import check_bound
from ..helper_arm import initial_condition
from ..kinematics import PlateArrays, q_from_plates, sp_forward_kinematics, stack_forward_kinematics
from ..model.assembler import AssemblerModel
from ..optimize import OptimizeOptions, optimize_internal_poses
from ..scenarios import SCENARIOS
from ..solver.pipeline import solve
from ..statics.engine import solve_statics, solve_statics_batch
from .collision import benchmark_clearance, benchmark_solve_scene
from .speed import benchmark_startup
from .starts import STARTS_GOALS, benchmark_default_starts
from .timing import LEVEL_GRID, median_time_us, random_reachable_plates

__all__ = [
    "benchmark_initial_condition",
    "benchmark_optimization",
    "benchmark_solve_grid",
    "run_benchmarks",
]


#: Stacks per call of the batched statics figure.
BATCH_STACKS = 10_000


def run_benchmarks(
    am: AssemblerModel,
    repeat: int = 300,
    seed: int = 0,
    optimize: bool = True,
    quick: bool = False,
    progress: ProgressCallback | None = None,
) -> dict[str, Any]:
    """Median per-call times [µs] of statics, SP FK, stack FK, closed-form q and the
    clearance (:func:`~assembler_pin.bench.collision.benchmark_clearance`: the stack's own
    pairs, ``clearance_us``, and among the truss bay, ``clearance_scene_us``), ``solve`` with a scene of ten obstacles
    against without (:func:`~assembler_pin.bench.collision.benchmark_solve_scene`:
    ``solve_free_ms``, ``solve_scene_ms``, ``solve_scene_ratio``), then the
    helper-arm initial condition (:func:`benchmark_initial_condition`: ``initial_scenarios_ms``,
    ``initial_random_ms`` [ms], ``initial_success_rate``), ``solve`` by default against every
    start on random goals over the stroke (:func:`~assembler_pin.bench.starts.benchmark_default_starts`:
    ``solve_p50_ms``, ``solve_p95_ms``, ``solve_p95_over_p50``, ``solve_time_over_all``, ...),
    the CLI start-up in fresh processes beside its targets (``cli_help_s``,
    ``cli_statics_home_json_s``, ``bare_python_s`` [s], medians of 5:
    :func:`~assembler_pin.bench.speed.benchmark_startup`), then the optimization of each
    scenario by both methods (:func:`benchmark_optimization`).

    Each per-call figure is the median over ``repeat`` calls (bound ``bench.repeat``),
    cycling through 20 random poses. ``quick`` cuts the goal sets to a minimum (for smoke
    tests, not for figures). ``progress`` is called ``(done, total, figure)`` after each figure.
    """
    check_bound("bench.repeat", repeat, "repeat")
    rng = np.random.default_rng(seed)
    samples = [random_reachable_plates(am, rng) for _ in range(20)]
    counter = iter(range(10**9))

    def pick() -> tuple[np.ndarray, PlateArrays]:
        return samples[next(counter) % len(samples)]

    batch = np.array([s[1].as_matrices() for s in samples])
    batch = np.tile(batch, (max(1, BATCH_STACKS // len(batch)), 1, 1, 1))
    figures: dict[str, Callable[[], Any]] = {
        "statics_us": lambda: median_time_us(lambda: solve_statics(am, pick()[1]), repeat),
        "sp_fk_us": lambda: median_time_us(lambda: sp_forward_kinematics(am, 0, pick()[0][0]), repeat),
        "stack_fk_us": lambda: median_time_us(lambda: stack_forward_kinematics(am, pick()[0]), repeat),
        "q_from_plates_us": lambda: median_time_us(lambda: q_from_plates(am, pick()[1]), repeat),
        "clearance": lambda: benchmark_clearance(am, [s[1] for s in samples], repeat),
        "solve_scene": lambda: benchmark_solve_scene(am, rounds=1 if quick else 5),
        "statics_from_matrices_us": lambda: median_time_us(lambda: solve_statics(am, pick()[1].as_matrices()), repeat),
        "statics_batch_stacks_per_s": lambda: (
            len(batch) / (1e-6 * median_time_us(lambda: solve_statics_batch(am, batch), 5))
        ),
        "initial_condition": lambda: benchmark_initial_condition(am, n_random=3 if quick else 20, seed=seed),
        "solve_starts": lambda: benchmark_default_starts(am, count=3 if quick else STARTS_GOALS, seed=seed),
    }
    figures["startup"] = lambda: _startup(repeat=3 if quick else 5)
    if optimize:
        figures["optimization"] = lambda: benchmark_optimization(
            am, names=["orientation_transition"] if quick else None
        )
    results: dict[str, Any] = {}
    for k, (name, figure) in enumerate(figures.items()):
        value = figure()
        if isinstance(value, dict):
            results.update(value)
        else:
            results[name] = value
        if progress is not None:
            progress(k + 1, len(figures), name)
    return results


def _startup(repeat: int) -> dict[str, float]:
    """The CLI start-up row (:func:`~assembler_pin.bench.speed.benchmark_startup`)."""
    return benchmark_startup(repeat)


def benchmark_optimization(am: AssemblerModel, names: list[str] | None = None) -> dict[str, Any]:
    """Optimization of each scenario from its helper-arm initial condition, by the default
    method (``slsqp``: smooth, analytic gradients) and the paper's (``paper``: non-smooth,
    finite differences), in the same run.

    Returns:
        ``optimize_scenarios``: per scenario ``slsqp_s``, ``paper_s`` [s], ``speedup``
        (paper / slsqp time), ``slsqp_objective``, ``paper_objective`` (Ω), ``initial_objective``;
        ``optimize_slsqp_median_s``, ``optimize_paper_median_s``, ``optimize_speedup_median``;
        ``optimize_objective_not_worse``: fraction of scenarios where slsqp's Ω <= paper's.
    """
    per: dict[str, dict[str, float]] = {}
    for name in names or list(SCENARIOS):
        goal = SCENARIOS[name].goal
        init = initial_condition(am, goal)
        if not init.success:
            continue
        smooth = optimize_internal_poses(am, init.state, goal, OptimizeOptions(method="slsqp"))
        paper = optimize_internal_poses(am, init.state, goal, OptimizeOptions(method="paper"))
        per[name] = {
            "slsqp_s": smooth.time_s,
            "paper_s": paper.time_s,
            "speedup": paper.time_s / smooth.time_s,
            "initial_objective": smooth.objective_initial,
            "slsqp_objective": smooth.objective_optimized,
            "paper_objective": paper.objective_optimized,
        }
    if not per:
        return {"optimize_scenarios": {}}
    return {
        "optimize_scenarios": per,
        "optimize_slsqp_median_s": statistics.median(v["slsqp_s"] for v in per.values()),
        "optimize_paper_median_s": statistics.median(v["paper_s"] for v in per.values()),
        "optimize_speedup_median": statistics.median(v["speedup"] for v in per.values()),
        "optimize_objective_not_worse": float(
            np.mean([v["slsqp_objective"] <= v["paper_objective"] + 1e-9 for v in per.values()])
        ),
    }


def benchmark_initial_condition(am: AssemblerModel, n_random: int = 20, seed: int = 0) -> dict[str, float]:
    """Helper-arm initial condition: median solve time and success rate.

    Goals: the scenario goals (:data:`~assembler_pin.scenarios.SCENARIOS`) and ``n_random``
    random reachable goals (the EE pose of random in-stroke leg lengths over the middle 70 %
    of the stroke, by stack FK; fixed seed). Each goal is solved once, after one warm-up
    solve of every goal (so the helper arms of the link lengths used are built and cached).

    Returns:
        ``initial_scenarios_ms`` and ``initial_random_ms``: median wall time per goal [ms];
        ``initial_success_rate``: fraction of all those goals solved (kinematically valid).
    """
    rng = np.random.default_rng(seed)
    scenario_goals = [s.goal for s in SCENARIOS.values()]
    random_goals = [random_reachable_plates(am, rng, spread=0.7)[1].se3(am.n) for _ in range(n_random)]

    def solve_all(goals: list) -> tuple[list[float], int]:
        for goal in goals:  # warm-up: build the arms of every link length these goals use
            initial_condition(am, goal)
        times, solved = [], 0
        for goal in goals:
            t0 = time.perf_counter()
            result = initial_condition(am, goal)
            times.append(time.perf_counter() - t0)
            solved += int(result.success)
        return times, solved

    t_scen, ok_scen = solve_all(scenario_goals)
    t_rand, ok_rand = solve_all(random_goals)
    return {
        "initial_scenarios_ms": statistics.median(t_scen) * 1e3,
        "initial_random_ms": statistics.median(t_rand) * 1e3,
        "initial_success_rate": (ok_scen + ok_rand) / (len(scenario_goals) + len(random_goals)),
    }


def benchmark_solve_grid(
    am: AssemblerModel, goals: tuple = LEVEL_GRID, progress: ProgressCallback | None = None
) -> dict[str, Any]:
    """Whole ``solve`` (helper arm, then the optimizer from every start) on a goal grid.

    Returns:
        ``grid_goals``, ``grid_solved``; ``grid_p50_s``, ``grid_p95_s`` over every goal and
        ``grid_solved_p95_s`` over the solved ones [s]; ``grid_starts_won``: how often
        each start gave the kept optimum; ``grid_unsolved``: the goals without a feasible pose.
    """
    import pinocchio as pin

    times: list[float] = []
    solved_times: list[float] = []
    won: dict[str | None, int] = {}
    unsolved: list = []
    for xyz in goals:
        t0 = time.perf_counter()
        result = solve(am, pin.SE3(np.eye(3), np.array(xyz)))
        dt = time.perf_counter() - t0
        times.append(dt)
        if result.success:
            solved_times.append(dt)
            won[result.start] = won.get(result.start, 0) + 1
        else:
            unsolved.append(list(xyz))
        if progress is not None:
            progress(len(times), len(goals), "grid goal")
    return {
        "grid_goals": len(goals),
        "grid_solved": len(solved_times),
        "grid_p50_s": float(np.percentile(times, 50)),
        "grid_p95_s": float(np.percentile(times, 95)),
        "grid_solved_p95_s": float(np.percentile(solved_times, 95)) if solved_times else float("nan"),
        "grid_starts_won": won,
        "grid_unsolved": unsolved,
    }
