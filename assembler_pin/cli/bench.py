"""``assembler-pin bench``: timings."""

from __future__ import annotations

import argparse
import os
from typing import TYPE_CHECKING

from ..exceptions import CLIError

if TYPE_CHECKING:
    pass
from .common import (
    config_from_args,
    dumps,
    progress_for,
)


def add_parser(add) -> None:
    """Register the ``bench`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("bench", "median time per call of the hot computations")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--repeat", type=int, default=300, help="calls per figure (default 300)")
    p.add_argument("--no-optimize", action="store_true", help="skip the optimization comparison (slow: ~10 s)")
    p.add_argument("--quick", action="store_true", help="minimal goal sets: a smoke test, not figures")
    p.add_argument("--grid", action="store_true", help="also solve the 120-goal level-EE grid (~2 min)")
    p.add_argument(
        "--platforms-sweep",
        action="store_true",
        help="only the cost of each stack size n = 1..64: build, memory, statics, FK, "
        "initial condition, optimization (~5 min)",
    )
    p.add_argument(
        "--maps", action="store_true", help="only the capability map's cells/s on 1 and 2 local Dask workers (~1 min)"
    )
    p.add_argument(
        "--mujoco", action="store_true", help="only MuJoCo against our statics: inverse statics and held poses (~15 s)"
    )
    p.add_argument(
        "--time-laws",
        action="store_true",
        help="only the quintic against the optimal time law on the README's three paths (~1 min)",
    )
    p.add_argument(
        "--truss",
        action="store_true",
        help="only the compliant truss: stiffness, loaded pose, compensated lengths, two-point support",
    )
    p.add_argument(
        "--speed",
        action="store_true",
        help="only BLAS threads, lazy starts, the statics kernel, one stack's statics at n = 4, 8, 16, "
        "capacity memory, CLI start-up, two-point support at n = 4, 64 (~3 min)",
    )
    p.add_argument(
        "--targets",
        action="store_true",
        help="only the speed targets, each figure beside its target: BLAS threads, solve on 60 random and "
        "120 grid goals, the default starts against every start on 40 goals, IPOPT on long stacks, "
        "statics, batched statics, the clearance, solve among ten obstacles, a map's memory (~20 min)",
    )
    p.add_argument(
        "--ratios",
        action="store_true",
        help="only the user's path against bare Pinocchio, in one process: evaluate_state and "
        "solve_statics ÷ Pinocchio's gravity and Jacobians, solve's p50 and p95 on 40 random goals (~10 s)",
    )
    p.add_argument(
        "--map-cells",
        type=int,
        default=None,
        metavar="N",
        help="with --targets: cells of the map whose memory is measured (default 1000; 0 skips the map)",
    )
    p.set_defaults(func=run)


def bench_header(am, what: str) -> str:
    """The two lines above the figures: what they are, on what machine, and how to read a key."""
    import platform

    import numpy
    import pinocchio

    machine = (
        f"Python {platform.python_version()}, pin {pinocchio.__version__}, numpy {numpy.__version__}, "
        f"{os.cpu_count()} CPUs ({platform.machine()})"
    )
    return (
        f"assembler-pin bench: {what}, {am.n} platforms\non {machine}\n"
        "units by suffix: _us µs, _ms ms, _s s, _per_s per second; compare figures within one run"
    )


def run(args: argparse.Namespace) -> int:
    """Median times of the hot computations; progress per figure on a terminal."""
    from ..bench.calls import run_benchmarks
    from ..config.bounds import check_bound
    from ..model.assembler import AssemblerModel

    check_bound("bench.repeat", args.repeat, "--repeat", CLIError)
    if args.map_cells is not None and not args.targets:
        raise CLIError("--map-cells applies to bench --targets only")
    if args.platforms_sweep:
        from ..bench.scaling import benchmark_platforms_sweep, format_sweep

        with progress_for(args, "bench: platforms") as prog:
            rows = benchmark_platforms_sweep(progress=prog)
        print(dumps(rows) if args.json else format_sweep(rows))
        return 0
    if args.maps:
        from ..bench.scaling import benchmark_maps, format_maps

        result = benchmark_maps()
        print(dumps(result) if args.json else format_maps(result))
        return 0
    am = AssemblerModel.from_config(config_from_args(args))
    if args.targets:
        return _targets(args, am)
    if args.ratios:
        from ..bench.ratios import benchmark_ratios, format_ratios

        doc = benchmark_ratios(am, repeat=args.repeat, goals=4 if args.quick else 40)
        print(dumps(doc) if args.json else format_ratios(doc))
        return 0
    if args.truss or args.speed:
        return _extra_figures(args, am)
    if args.time_laws:
        from ..bench.motion import benchmark_time_laws, format_time_laws

        rows = benchmark_time_laws(am)
        print(dumps(rows) if args.json else format_time_laws(rows))
        return 0
    if args.mujoco:
        from ..bench.motion import benchmark_mujoco, format_mujoco

        rows = benchmark_mujoco(am)
        print(dumps(rows) if args.json else format_mujoco(rows))
        return 0
    with progress_for(args, "bench") as prog:
        results = run_benchmarks(am, repeat=args.repeat, optimize=not args.no_optimize, quick=args.quick, progress=prog)
    if args.grid:
        from ..bench.calls import benchmark_solve_grid

        with progress_for(args, "bench: grid") as prog:
            results.update(benchmark_solve_grid(am, progress=prog))
    if args.json:
        print(dumps(results))
        return 0
    scenarios = results.pop("optimize_scenarios", None)
    print(bench_header(am, f"median of {args.repeat} calls per figure"))
    print(f"{'figure':>30}  {'median':>10}")
    for key, value in results.items():
        print(f"{key:>30}: {value:10.3f}" if isinstance(value, float | int) else f"{key:>30}: {value}")
    if scenarios:
        print("\noptimization per scenario (same run): time [s] and objective Ω")
        print(
            f"{'scenario':<24}{'slsqp s':>9}{'paper s':>9}{'speedup':>9}{'Ω initial':>11}{'Ω slsqp':>9}{'Ω paper':>9}"
        )
        for name, v in scenarios.items():
            print(
                f"{name:<24}{v['slsqp_s']:9.3f}{v['paper_s']:9.3f}{v['speedup']:9.1f}"
                f"{v['initial_objective']:11.2f}{v['slsqp_objective']:9.2f}{v['paper_objective']:9.2f}"
            )
    return 0


def _targets(args: argparse.Namespace, am) -> int:
    """``bench --targets``: the speed targets' table, or one JSON object with the figures."""
    from ..bench.targets import MAP_MEMORY_CELLS, benchmark_targets, format_targets, target_rows
    from ..config.bounds import check_bound

    cells = MAP_MEMORY_CELLS if args.map_cells is None else args.map_cells
    if cells:
        check_bound("bench.map_cells", cells, "--map-cells", CLIError)
    doc = benchmark_targets(am, map_cells=cells, quick=args.quick)
    rows = target_rows(doc)
    if args.json:
        doc["targets"] = [{"figure": r.what, "value": r.value, "target": r.target, "met": r.met} for r in rows]
        print(dumps(doc))
    else:
        print(format_targets(rows))
    return 0


def _extra_figures(args: argparse.Namespace, am) -> int:
    """``bench --truss`` and ``bench --speed``: one figure per line, or one JSON object."""
    doc: dict = {}
    if args.truss:
        from ..bench.supports import benchmark_supports
        from ..bench.truss import benchmark_stiffness

        doc["stiffness"] = benchmark_stiffness(am)
        doc["supports"] = benchmark_supports(am)
    if args.speed:
        from ..bench.speed import (
            benchmark_capacity_memory,
            benchmark_long_stacks,
            benchmark_single_statics,
            benchmark_solve_starts,
            benchmark_startup,
            benchmark_statics_kernel,
            benchmark_threads,
            benchmark_two_point,
        )
        from ..bench.timing import LEVEL_GRID

        doc["threads"] = benchmark_threads(am)
        doc["starts"] = benchmark_solve_starts(am, LEVEL_GRID[::12])
        doc["statics_kernel"] = benchmark_statics_kernel(am)
        doc["single_statics"] = benchmark_single_statics()
        doc["capacity_memory"] = benchmark_capacity_memory(am)
        doc["startup"] = benchmark_startup()
        doc["two_point"] = benchmark_two_point()
        from ..bench.hexapod import benchmark_hexapod

        doc["hexapod"] = benchmark_hexapod()
        doc["long_stacks"] = benchmark_long_stacks()
    if args.json:
        print(dumps(doc))
        return 0
    print(bench_header(am, "medians"))
    for group, figures in doc.items():
        timed = group in PER_CALL_GROUPS
        print(f"{group} (median time per call):" if timed else f"{group}:")
        for key, value in figures.items() if isinstance(figures, dict) else [("", figures)]:
            key = f"{key}_s" if timed else key  # the header's unit suffix: these keys carry none
            print(f"  {key:>34}: {value:.4g}" if isinstance(value, float) else f"  {key:>34}: {value}")
    return 0


#: The groups of ``bench --truss`` whose figures are times per call [s] under keys named
#: after the call alone (``stiffness``: the time of a stiffness, not a stiffness).
PER_CALL_GROUPS = ("stiffness", "supports")
