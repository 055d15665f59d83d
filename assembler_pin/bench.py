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

from .bounds import check_bound
from .kinematics import PlateArrays, q_from_plates, sp_forward_kinematics, stack_forward_kinematics
from .model import AssemblerModel
from .progress import ProgressCallback
from .statics import solve_statics, solve_statics_batch

__all__ = [
    "LEVEL_GRID",
    "benchmark_initial_condition",
    "benchmark_optimization",
    "benchmark_solve_grid",
    "median_time_us",
    "random_reachable_plates",
    "run_benchmarks",
]


def median_time_us(fn: Callable[[], object], repeat: int) -> float:
    """Median wall time of ``fn()`` over ``repeat`` calls, after one warm-up call [µs]."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times) * 1e6


def random_reachable_plates(
    am: AssemblerModel, rng: np.random.Generator, spread: float = 0.35
) -> tuple[np.ndarray, PlateArrays]:
    """Random in-stroke leg lengths and the plate poses they give (by stack FK).

    Args:
        spread: fraction of the stroke around mid-stroke that lengths are drawn from.

    Returns:
        (lengths (n, 6) [m], plate poses).
    """
    leg = am.config.leg
    half = 0.5 * spread * (leg.max_length - leg.min_length)
    while True:
        lengths = rng.uniform(leg.mid_length - half, leg.mid_length + half, (am.n, 6))
        fk = stack_forward_kinematics(am, lengths)
        if fk.success:
            return lengths, fk.plates


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
    """Median per-call times [µs] of statics, SP FK, stack FK and closed-form q, then the
    helper-arm initial condition (:func:`benchmark_initial_condition`: ``initial_scenarios_ms``,
    ``initial_random_ms`` [ms], ``initial_success_rate``), the CLI start-up in fresh processes
    beside its targets (``cli_help_s``, ``cli_statics_home_json_s``, ``bare_python_s`` [s],
    medians of 5: :func:`~assembler_pin.bench_speed.benchmark_startup`), then the
    optimization of each scenario by both methods (:func:`benchmark_optimization`).

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
        "statics_from_matrices_us": lambda: median_time_us(lambda: solve_statics(am, pick()[1].as_matrices()), repeat),
        "statics_batch_stacks_per_s": lambda: (
            len(batch) / (1e-6 * median_time_us(lambda: solve_statics_batch(am, batch), 5))
        ),
        "initial_condition": lambda: benchmark_initial_condition(am, n_random=3 if quick else 20, seed=seed),
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
    """The CLI start-up row (:func:`~assembler_pin.bench_speed.benchmark_startup`)."""
    from .bench_speed import benchmark_startup

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
    from .helper_arm import initial_condition
    from .optimize import OptimizeOptions, optimize_internal_poses
    from .scenarios import SCENARIOS

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
    from .helper_arm import initial_condition
    from .scenarios import SCENARIOS

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


#: The level-EE goal grid of :func:`benchmark_solve_grid`: x = -0.4…0.5, y = 0, 0.2,
#: z = 0.5…1.0 m, steps of 0.1 m, EE parallel to the base.
LEVEL_GRID = tuple(
    (round(x, 3), round(y, 3), round(z, 3))
    for x in np.arange(-0.4, 0.55, 0.1)
    for y in (0.0, 0.2)
    for z in np.arange(0.5, 1.05, 0.1)
)


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

    from .solver import solve

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


SWEEP_PLATFORMS = (1, 2, 4, 8, 16, 32, 64)


def benchmark_platform_count(n: int, repeat: int = 50, seed: int = 0, optimize: bool = True) -> dict[str, Any]:
    """Costs of one stack size n, in this process: model build [s], resident memory after the
    build [MB], statics and stack FK per call [µs], the helper-arm initial condition and the
    optimization [s] of one goal (the EE of random in-stroke lengths, by stack FK)."""
    import resource

    import pinocchio as pin

    from .helper_arm import initial_condition
    from .optimize import optimize_internal_poses

    t0 = time.perf_counter()
    am = AssemblerModel.from_config({"platforms": n})
    row: dict[str, Any] = {"platforms": n, "build_s": time.perf_counter() - t0}
    row["resident_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    rng = np.random.default_rng(seed)
    lengths, plates = random_reachable_plates(am, rng, spread=0.5)
    row["statics_us"] = median_time_us(lambda: solve_statics(am, plates), repeat)
    row["stack_fk_us"] = median_time_us(lambda: stack_forward_kinematics(am, lengths), repeat)
    goal = pin.SE3(plates.se3(n))
    t0 = time.perf_counter()
    init = initial_condition(am, goal)
    row["initial_s"] = time.perf_counter() - t0
    row["initial_success"] = init.success
    if optimize and init.success:
        result = optimize_internal_poses(am, init.state, goal)
        row["optimize_s"], row["optimize_success"] = result.time_s, result.success
    return row


def benchmark_platforms_sweep(
    counts: tuple[int, ...] = SWEEP_PLATFORMS, optimize_limit_s: float = 60.0, progress: ProgressCallback | None = None
) -> list[dict]:
    """:func:`benchmark_platform_count` for each n, each in a fresh process (so the resident
    memory is that size's own); the optimization is skipped, and said so, where it would take
    longer than ``optimize_limit_s`` (estimated from the previous size, growing as n³)."""
    import json
    import subprocess
    import sys

    rows: list[dict] = []
    for n in counts:
        previous = rows[-1] if rows else None
        estimate = None
        if previous and previous.get("optimize_s"):
            estimate = previous["optimize_s"] * (n / previous["platforms"]) ** 3
        optimize = estimate is None or estimate <= optimize_limit_s
        code = (
            "import json; from assembler_pin.bench import benchmark_platform_count; "
            f"print(json.dumps(benchmark_platform_count({n}, optimize={optimize})))"
        )
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
        row = json.loads(out.strip().splitlines()[-1])
        if not optimize:
            row["optimize_note"] = f"skipped: estimated {estimate:.0f} s > {optimize_limit_s:.0f} s"
        rows.append(row)
        if progress is not None:
            progress(len(rows), len(counts), f"n = {n}")
    return rows


def format_sweep(rows: list[dict]) -> str:
    """The sweep as a text table."""
    head = f"{'n':>3} {'build s':>8} {'RSS MB':>7} {'statics µs':>11} {'stack FK µs':>12} "
    head += f"{'initial s':>10} {'optimize s':>11}"
    lines = [head, "-" * len(head)]
    for r in rows:
        opt = f"{r['optimize_s']:11.2f}" if "optimize_s" in r else f"{'skipped':>11}"
        lines.append(
            f"{r['platforms']:>3} {r['build_s']:8.3f} {r['resident_mb']:7.0f} {r['statics_us']:11.0f} "
            f"{r['stack_fk_us']:12.0f} {r['initial_s']:10.2f} {opt}"
        )
    notes = [f"n = {r['platforms']}: {r['optimize_note']}" for r in rows if "optimize_note" in r]
    return "\n".join(lines + notes)


def benchmark_mujoco(am: AssemblerModel, n_random: int = 8, seed: int = 42, seconds: float = 1.5) -> list[dict]:
    """MuJoCo against our statics, per pose (home, random stacks, each scenario's optimized
    pose): the inverse statics' gap [N], the held pose's gap as a fraction of the tolerance
    max(1% of max|F|, 0.5 N), the same at MuJoCo's settled pose, the EE sag [m], the largest
    ball-joint gap [m] and the wall time of the simulation [s] (``assembler-pin bench --mujoco``)."""
    from .scenarios import SCENARIOS
    from .simulate import MujocoStack, hold_pose, mujoco_statics
    from .solver import solve

    rng = np.random.default_rng(seed)
    poses: dict[str, PlateArrays] = {"home": PlateArrays.from_se3(am.home)}
    for k in range(n_random):
        poses[f"random {k}"] = random_reachable_plates(am, rng, spread=0.8)[1]
    for name, s in SCENARIOS.items():
        result = solve(am, s.goal)
        if result.optimized is not None:
            poses[name] = result.optimized.plates
    stack = MujocoStack(am)
    rows = []
    for name, plates in poses.items():
        ours = solve_statics(am, plates).forces
        tol = max(0.01 * float(np.abs(ours).max()), 0.5)
        inverse = mujoco_statics(am, plates, stack)
        t0 = time.perf_counter()
        held = hold_pose(am, plates, seconds=seconds, samples=10, joint_limits=False, stack=stack)
        wall = time.perf_counter() - t0
        settled = solve_statics(am, held.plates).forces
        rows.append(
            {
                "pose": name,
                "max_abs_force_n": float(np.abs(ours).max()),
                "inverse_gap_n": float(np.abs(inverse.forces - ours).max()),
                "held": held.held,
                "held_gap_of_tolerance": float(np.abs(held.final_forces - ours).max() / tol),
                "settled_gap_of_tolerance": float(np.abs(held.final_forces - settled).max() / tol),
                "ee_sag_m": float(held.ee_drift[-1]),
                "ball_gap_m": float(held.closure_residual.max()),
                "wall_s": wall,
            }
        )
    return rows


def format_mujoco(rows: list[dict]) -> str:
    """The table of :func:`benchmark_mujoco`."""
    lines = [
        f"{'pose':<24}{'max|F| N':>9}{'inverse N':>11}{'held':>6}{'held/tol':>9}{'settled/tol':>12}"
        f"{'sag mm':>8}{'ball mm':>8}{'wall s':>7}",
    ]
    for r in rows:
        lines.append(
            f"{r['pose']:<24}{r['max_abs_force_n']:9.2f}{r['inverse_gap_n']:11.1e}{'yes' if r['held'] else 'NO':>6}"
            f"{r['held_gap_of_tolerance']:9.2f}{r['settled_gap_of_tolerance']:12.3f}{1e3 * r['ee_sag_m']:8.2f}"
            f"{1e3 * r['ball_gap_m']:8.3f}{r['wall_s']:7.2f}"
        )
    lines.append("tolerance = max(1% of max|F|, 0.5 N); held/tol ≤ 1 meets it")
    return "\n".join(lines)


#: The grid of ``bench --maps``: 12 cells in front of the base, mostly reachable.
MAP_BENCH_GRID = "x=0.1:0.55:4,y=0.05,z=0.7:0.95:3"


def benchmark_maps(grid_spec: str = MAP_BENCH_GRID, workers: tuple[int, ...] = (1, 2)) -> dict[str, Any]:
    """Cells per second of a map on 1 and 2 local Dask workers, the scaling efficiency and
    an estimate for a 64-core cluster (64 × the one-worker rate × the measured efficiency).

    Each run starts from an empty output directory and includes starting the local cluster.
    """
    import tempfile

    from .config import load_config
    from .maps import parse_grid, run_map

    grid = parse_grid(grid_spec)
    rates = {}
    per_cell = {}
    with tempfile.TemporaryDirectory() as tmp:
        for w in workers:
            run = run_map(grid, [("default", load_config())], f"{tmp}/w{w}", workers=w)
            rates[w] = run.cells_per_second
            per_cell[w] = run.time_s * w / max(run.computed, 1)
    one, most = min(workers), max(workers)
    efficiency = rates[most] / (rates[one] * most / one)
    return {
        "grid": grid_spec,
        "cells": len(grid),
        "cells_per_s": {str(w): rates[w] for w in workers},
        "core_seconds_per_cell": per_cell[one],
        "efficiency": efficiency,
        "estimate_64_cores_cells_per_s": 64 * rates[one] / one * efficiency,
    }


def format_maps(result: dict[str, Any]) -> str:
    """The ``bench --maps`` table."""
    lines = [f"map of {result['cells']} cells ({result['grid']}), local Dask cluster, one thread per worker"]
    for w, rate in result["cells_per_s"].items():
        lines.append(f"  {w} worker(s): {rate:6.2f} cells/s")
    lines.append(f"  scaling efficiency {max(result['cells_per_s'])} workers: {100 * result['efficiency']:.0f} %")
    lines.append(
        f"  {result['core_seconds_per_cell']:.2f} core-seconds per cell; a 64-core cluster at this "
        f"efficiency: ~{result['estimate_64_cores_cells_per_s']:.0f} cells/s"
    )
    return "\n".join(lines)


#: The README's three paths (from the home pose).
COMPARE_PATHS = ("translation", "vertical_lift", "orientation_transition")


def benchmark_time_laws(am: AssemblerModel, names: tuple[str, ...] = COMPARE_PATHS) -> list[dict]:
    """Durations of the quintic and the optimal (TOPP-RA) time law on the paths from the home
    pose to the scenarios' goals, and the optimal law's time on a grid of ~1,000 points."""
    import dataclasses

    from scipy.interpolate import PchipInterpolator

    from .motion import EEPath, plan_path
    from .motion.timing import _law_duration, _problem
    from .motion.toppra_law import OptimalLaw
    from .scenarios import scenario

    rows = []
    leg = am.config.leg
    for name in names:
        plan = plan_path(am, EEPath((am.home[-1], scenario(name).goal)), am.home)
        quintic = _law_duration(am, plan, "quintic")
        optimal = _law_duration(am, plan, "optimal")
        L = plan.lengths.reshape(len(plan.states), -1)
        spline = PchipInterpolator(np.arange(len(L), dtype=float), L, axis=0)
        problem = _problem(am, plan, spline, 0.95 * leg.max_speed, 0.95 * leg.max_acceleration, 16, "optimal")
        problem = dataclasses.replace(problem, forces=_cached_forces(problem.forces))
        law = OptimalLaw(grid_per_sample=max(1, -(-1000 // (len(L) - 1))), max_grid=1000)
        grid = law.grid(problem)
        problem.forces(grid)  # the force coefficients at the samples, computed once
        t0 = time.perf_counter()
        law.profile(problem, grid)
        rows.append(
            {
                "path": name,
                "samples": len(L),
                "quintic_s": quintic,
                "optimal_s": optimal,
                "shorter_pct": 100.0 * (1.0 - optimal / quintic),
                "grid_points": len(grid),
                "toppra_s": law.last_solve_s,
                "law_s": time.perf_counter() - t0,
            }
        )
    return rows


def _cached_forces(forces: Callable) -> Callable:
    """``forces(grid)`` with the samples' coefficients computed on first use (they are the
    planner's poses, not the time law's work)."""
    cache: dict[int, tuple] = {}

    def wrapped(grid: np.ndarray) -> tuple:
        key = hash(grid.tobytes())
        if key not in cache:
            cache[key] = forces(grid)
        return cache[key]

    return wrapped


def format_time_laws(rows: list[dict]) -> str:
    """The table of :func:`benchmark_time_laws`."""
    lines = [f"{'path':<24}{'samples':>8}{'quintic s':>10}{'optimal s':>10}{'shorter':>9}{'grid':>6}{'TOPP-RA s':>10}"]
    for r in rows:
        lines.append(
            f"{r['path']:<24}{r['samples']:8d}{r['quintic_s']:10.2f}{r['optimal_s']:10.2f}{r['shorter_pct']:8.1f}%"
            f"{r['grid_points']:6d}{r['toppra_s']:10.3f}"
        )
    return "\n".join(lines)
