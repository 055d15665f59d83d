"""Benchmarks of motion: MuJoCo's servos holding our poses, and the time laws on the
README's paths (``assembler-pin bench --mujoco`` / ``--time-laws``)."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from ..kinematics import PlateArrays
from ..model.assembler import AssemblerModel
from ..motion import EEPath, plan_path
from ..motion.timing import law_duration, timing_problem
from ..motion.toppra_law import OptimalLaw
from ..scenarios import SCENARIOS, scenario
from ..simulate import MujocoStack, hold_pose, mujoco_statics
from ..solver.pipeline import solve
from ..statics.engine import solve_statics
from .timing import random_reachable_plates

__all__ = ["COMPARE_PATHS", "benchmark_mujoco", "benchmark_time_laws", "format_mujoco", "format_time_laws"]


def benchmark_mujoco(am: AssemblerModel, n_random: int = 8, seed: int = 42, seconds: float = 1.5) -> list[dict]:
    """MuJoCo against our statics, per pose (home, random stacks, each scenario's optimized
    pose): the inverse statics' gap [N], the held pose's gap as a fraction of the tolerance
    max(1% of max|F|, 0.5 N), the same at MuJoCo's settled pose, the EE sag [m], the largest
    ball-joint gap [m] and the wall time of the simulation [s] (``assembler-pin bench --mujoco``)."""
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
COMPARE_PATHS = ("translation", "vertical_lift", "orientation_transition")


def benchmark_time_laws(am: AssemblerModel, names: tuple[str, ...] = COMPARE_PATHS) -> list[dict]:
    """Durations of the quintic and the optimal (TOPP-RA) time law on the paths from the home
    pose to the scenarios' goals, and the optimal law's time on a grid of ~1,000 points."""
    import dataclasses

    from scipy.interpolate import PchipInterpolator

    rows = []
    leg = am.config.leg
    for name in names:
        plan = plan_path(am, EEPath((am.home[-1], scenario(name).goal)), am.home)
        quintic = law_duration(am, plan, "quintic")
        optimal = law_duration(am, plan, "optimal")
        L = plan.lengths.reshape(len(plan.states), -1)
        spline = PchipInterpolator(np.arange(len(L), dtype=float), L, axis=0)
        problem = timing_problem(am, plan, spline, 0.95 * leg.max_speed, 0.95 * leg.max_acceleration, 16, "optimal")
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
