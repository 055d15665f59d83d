"""``assembler-pin map``: capability maps."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..exceptions import CLIError
from .common import add_scene_argument, config_from_args, dumps, finite_range, progress_for, scene_from_args, wrapped
from .paths import path_argument, writable_directory, writable_parent

if TYPE_CHECKING:
    from ..config.schema import AssemblerConfig


def add_parser(add) -> None:
    """Register the ``map`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("map", "capability map: reachability, optimized max|F|, payload capacity per cell (Dask, resumable)")
    p.add_argument(
        "--grid",
        required=True,
        metavar="SPEC",
        help="EE positions [m]: AXIS=VALUE or START:STOP:COUNT, e.g. x=0:0.6:10,y=0,z=0.5:1:10",
    )
    p.add_argument(
        "--orientations", metavar="SPEC", help='EE rotation vectors in degrees, e.g. "0 0 0; 0 30 0" (default level)'
    )
    p.add_argument(
        "--sweep",
        type=path_argument,
        nargs="+",
        metavar="FILE",
        help="design sweep: the map of each configuration file (config column: its name)",
    )
    p.add_argument(
        "--out",
        type=path_argument,
        required=True,
        metavar="DIR",
        help="map directory (Parquet parts; a rerun extends it)",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        help="local worker processes (default: the machine's cores; 0: here, no Dask)",
    )
    p.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler, e.g. tcp://10.0.0.5:8786")
    p.add_argument("--batch-size", type=int, default=None, metavar="N", help="cells per task (default automatic)")
    add_scene_argument(p, "every cell's pose keeps its clearance from it (part of the map: a rerun needs the same)")
    p.add_argument(
        "--png",
        type=path_argument,
        metavar="FILE",
        help="heatmaps of one slice: clearance [mm], max|F|, capacity, sag [mm], stiffness",
    )
    p.add_argument(
        "--html",
        type=path_argument,
        metavar="FILE",
        help="the cells as a point cloud colored by capacity, in the viewer",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress line (as the global --quiet)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def _check_options(args: argparse.Namespace):
    """The grid of ``--grid``/``--orientations`` and the scene of ``--scene`` (or None), every
    other option checked before any work."""
    from ..config.bounds import check_bound
    from ..maps import parse_grid
    from ..maps.cluster import check_scheduler

    writable_directory(args.out, "--out directory")
    for option, value in (("--png file", args.png), ("--html file", args.html)):
        if value:
            writable_parent(value, option)
    if args.workers is not None:
        check_bound("map.workers", args.workers, "--workers", CLIError)
    if args.batch_size is not None:
        check_bound("map.batch_size", args.batch_size, "--batch-size", CLIError)
    if args.scheduler is not None:
        check_scheduler(args.scheduler, "--scheduler")
    grid = parse_grid(args.grid, args.orientations, configs=len(args.sweep) if args.sweep else 1)
    if args.png and len(grid.varying_axes()) != 2:
        raise CLIError(f"--png draws a map varying along two position axes; --grid varies along {grid.varying_axes()}")
    return grid, scene_from_args(args)


def _configs(args: argparse.Namespace) -> list[tuple[str, AssemblerConfig]]:
    from ..config.schema import load_config

    if not args.sweep:
        return [(Path(args.config).stem if args.config else "default", config_from_args(args))]
    names = [Path(c).stem for c in args.sweep]
    if len(set(names)) != len(names):
        raise CLIError("--sweep files must have different names (the map's config column)")
    return [(name, load_config(c)) for name, c in zip(names, args.sweep, strict=True)]


def _pictures(args: argparse.Namespace, table, configs: list, doc: dict) -> None:
    """The ``--png`` heatmaps and the ``--html`` point cloud of the first configuration."""
    from ..model.assembler import AssemblerModel

    am = AssemblerModel.from_config(configs[0][1])
    if args.png:
        from ..maps.pictures import map_heatmaps
        from ..plots.figures import save

        scene = Path(args.scene).name if args.scene else ""
        figure = map_heatmaps(table, am, configs[0][0], scene=scene, obstacles=scene_from_args(args))
        doc["png"] = str(save(figure, args.png))
    if args.html:
        from ..maps.pictures import write_map_page
        from ..viz import StackViewer

        with StackViewer(am, scene=scene_from_args(args)) as viewer:  # the cells among the scene
            viewer.display(am.home, color_forces=False)
            doc["html"] = str(Path(args.html))
            write_map_page(viewer, table, doc["html"], config=configs[0][0])


def run(args: argparse.Namespace) -> int:
    """A capability map: per cell reachability, optimized max|F|, payload capacity, binding.

    Exit status 0 once every cell is computed, unreachable cells included (they are answers).
    """
    from ..maps import read_map, run_map

    grid, scene = _check_options(args)
    configs = _configs(args)
    prog = None if args.no_progress else progress_for(args, "map")
    try:
        run = run_map(
            grid,
            configs,
            args.out,
            workers=args.workers,
            scheduler=args.scheduler,
            batch_size=args.batch_size,
            progress=prog,
            scene=scene,
        )
    finally:
        if prog is not None:
            prog.close()
    table = read_map(args.out)
    doc = _summary(args, table, len(grid) * len(configs), run)
    if args.png or args.html:
        _pictures(args, table, configs, doc)
    if args.json:
        print(dumps(doc))
    else:
        _print_summary(doc, run, table.num_rows)
    return 0


def _summary(args: argparse.Namespace, table, cells: int, run) -> dict[str, Any]:
    """The answer's document: what was computed, how fast, and the ranges of the map's values."""
    import numpy as np

    force = np.asarray(table.column("max_abs_force").to_pylist(), dtype=float)
    near = np.asarray(table.column("clearance_m").to_pylist(), dtype=float)  # null: NaN
    cap = np.asarray(table.column("capacity_kg").to_pylist(), dtype=float)
    reach = np.asarray(table.column("reachable").to_pylist(), dtype=bool)
    return {
        "out": str(Path(args.out)),
        "cells": cells,
        "computed": run.computed,
        "already_done": run.skipped,
        "workers": run.workers,
        "time_s": run.time_s,
        "cells_per_s": run.cells_per_second,
        "reachable": int(reach.sum()),
        "max_abs_force_range": finite_range(force),
        "capacity_kg_range": finite_range(cap),
        "clearance_m_range": finite_range(near),
        "scene": str(Path(args.scene)) if args.scene else None,
    }


def _print_summary(doc: dict[str, Any], run, rows: int) -> None:
    """The text answer of :func:`run` (``rows``: the cells the map file holds)."""
    rate = f" ({run.cells_per_second:.2f} cells/s)" if doc["computed"] else ""  # a rerun computes nothing
    print(
        wrapped(
            f"map: {doc['computed']} cells computed, {doc['already_done']} already in {doc['out']}; "
            f"{run.workers or 'no'} workers, {run.time_s:.1f} s{rate}"
        )
    )
    print(f"reachable: {doc['reachable']} of {rows} cells")
    if doc["max_abs_force_range"]:
        lo, hi = doc["max_abs_force_range"]
        print(f"optimized max|F|: {lo:.1f} – {hi:.1f} N")
    if doc["capacity_kg_range"]:
        lo, hi = doc["capacity_kg_range"]
        print(f"payload capacity: {lo:.2f} – {hi:.2f} kg")
    if doc["clearance_m_range"]:
        lo, hi = doc["clearance_m_range"]
        within = f" (scene {doc['scene']})" if doc["scene"] else ""
        print(f"clearance: {1e3 * lo:.1f} – {1e3 * hi:.1f} mm{within}")
    for key in ("png", "html"):
        if key in doc:
            print(f"wrote {doc[key]}")
