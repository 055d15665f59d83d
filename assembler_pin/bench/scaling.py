"""Benchmarks of how the figures scale: the number of platforms (each size in a fresh
process) and a capability map on one and two Dask workers (``assembler-pin bench
--platforms-sweep`` / ``--maps``)."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..common.progress import ProgressCallback
from ..config.schema import load_config
from ..helper_arm import initial_condition
from ..kinematics import stack_forward_kinematics
from ..maps import parse_grid, run_map
from ..model.assembler import AssemblerModel
from ..optimize import optimize_internal_poses
from ..statics.engine import solve_statics
from .timing import median_time_us, random_reachable_plates

__all__ = [
    "MAP_BENCH_GRID",
    "SWEEP_PLATFORMS",
    "benchmark_maps",
    "benchmark_platform_count",
    "benchmark_platforms_sweep",
    "format_maps",
    "format_sweep",
]


SWEEP_PLATFORMS = (1, 2, 4, 8, 16, 32, 64)


def benchmark_platform_count(n: int, repeat: int = 50, seed: int = 0, optimize: bool = True) -> dict[str, Any]:
    """Costs of one stack size n, in this process: model build [s], resident memory after the
    build [MB], statics and stack FK per call [µs], the helper-arm initial condition and the
    optimization [s] of one goal (the EE of random in-stroke lengths, by stack FK)."""
    import resource

    import pinocchio as pin

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
            "import json; from assembler_pin.bench.scaling import benchmark_platform_count; "
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


MAP_BENCH_GRID = "x=0.1:0.55:4,y=0.05,z=0.7:0.95:3"


def benchmark_maps(grid_spec: str = MAP_BENCH_GRID, workers: tuple[int, ...] = (1, 2)) -> dict[str, Any]:
    """Cells per second of a map on 1 and 2 local Dask workers, the scaling efficiency and
    an estimate for a 64-core cluster (64 × the one-worker rate × the measured efficiency).

    Each run starts from an empty output directory and includes starting the local cluster.
    """
    import tempfile

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
