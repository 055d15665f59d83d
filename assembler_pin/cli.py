"""The ``assembler-pin`` command.

Subcommands: ``export`` (URDF + closure sidecar), ``statics`` (forces of given plate
poses), ``bench`` (timings). Errors in the input end the command with exit status 2 and
one line on stderr saying what was wrong.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

import numpy as np

from .config import AssemblerConfig, load_config
from .exceptions import AssemblerError, CLIError
from .export import export_model_files
from .labels import leg_label, platform_label
from .model import AssemblerModel
from .state import StackState, evaluate_state

logger = logging.getLogger("assembler_pin")


class _Parser(argparse.ArgumentParser):
    """argparse with one-line refusals (a :class:`CLIError`, not a usage dump and exit) and
    negative numbers in scientific notation read as numbers (``--goal -1e-3 ...``)."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?$|^-(?:inf|nan)$", re.I)

    def error(self, message: str) -> NoReturn:
        raise CLIError(f"{message} (see '{self.prog} --help')")


def _dumps(doc: object) -> str:
    """Strict JSON: a NaN or infinite number (a singular pose's forces) is written as null."""

    def clean(x: object) -> object:
        if isinstance(x, float):
            return x if math.isfinite(x) else None
        if isinstance(x, dict):
            return {k: clean(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [clean(v) for v in x]
        return x

    return json.dumps(clean(doc), allow_nan=False)


def _writable_parent(path: str, what: str) -> Path:
    """``path`` whose directory exists and is writable, else a CLIError naming it."""
    target = Path(path)
    parent = target.parent if target.parent != Path("") else Path(".")
    if not parent.is_dir():
        raise CLIError(f"{what} '{path}': directory '{parent}' does not exist")
    if not os.access(parent, os.W_OK):
        raise CLIError(f"{what} '{path}': directory '{parent}' is not writable")
    if target.is_dir() and what.endswith("file"):
        raise CLIError(f"{what} '{path}' is a directory")
    return target


def _config(args: argparse.Namespace) -> AssemblerConfig:
    return load_config(args.config) if args.config else load_config()


def _read_json(source: str) -> object:
    try:
        text = sys.stdin.read() if source == "-" else Path(source).read_text(encoding="utf-8")
    except OSError as exc:
        raise CLIError(f"cannot read '{source}': {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise CLIError(f"'{source}' is not UTF-8 text") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise CLIError(f"'{source}' is not valid JSON: {exc}") from None
    except RecursionError:
        raise CLIError(f"'{source}' is nested too deeply to be a plate file") from None


def _plates_from_file(source: str) -> list:
    """The ``plates`` list of a JSON plate file (``{"plates": [n+1 4x4 world transforms]}``)."""
    doc = _read_json(source)
    if not isinstance(doc, dict) or "plates" not in doc:
        raise CLIError('the input must be a JSON object {"plates": [n+1 4x4 world transforms]}')
    plates = doc["plates"]
    if not isinstance(plates, list):
        raise CLIError('"plates" must be a list of n+1 4x4 matrices, plate 0 first')
    return plates


def _plates_from_args(args: argparse.Namespace, am: AssemblerModel, missing: str) -> list:
    """The pose of ``--home`` or ``--plates FILE``; a CLIError saying ``missing`` when neither."""
    if args.home:
        return am.home
    if args.plates is not None:
        return _plates_from_file(args.plates)
    raise CLIError(missing)


def format_state_table(state: StackState, title: str = "") -> str:
    """A readable table of a state: forces and lengths per actuator, then summary lines.

    Row ``i``, column ``SPj`` is leg ``i`` of platform ``j``, both 0-based
    (:mod:`~assembler_pin.labels`), the indices of ``forces[j, i]`` and of the JSON.
    """
    n = state.forces.shape[0]
    lines = [title] if title else []
    header = "leg | " + " | ".join(f"{platform_label(j)} F [N]  L [mm]" for j in range(n))
    lines += [header, "-" * len(header)]
    for i in range(6):
        cells = [f"{state.forces[j, i]:9.3f} {1e3 * state.leg_lengths[j, i]:7.2f}" for j in range(n)]
        lines.append(f"{i:>3} | " + " | ".join(cells))
    j, i = np.unravel_index(np.abs(state.forces).argmax(), state.forces.shape)
    lines.append(
        f"max |F| = {state.max_abs_force:.3f} N ({leg_label(j, i)}), "
        f"mean |F| = {state.mean_abs_force:.3f} N   (tension positive)"
    )
    w = state.statics.base_wrench
    lines.append(
        f"base wrench [N, N·m]: f = ({w[0]:.3f}, {w[1]:.3f}, {w[2]:.3f}), m = ({w[3]:.3f}, {w[4]:.3f}, {w[5]:.3f})"
    )
    if state.feasible:
        lines.append("feasible: yes (every constraint holds)")
    else:
        lines.append(f"feasible: NO — {len(state.violations)} violation(s):")
        lines += [f"  - {v}" for v in state.violations]
    return "\n".join(lines)


def cmd_export(args: argparse.Namespace) -> int:
    cfg = _config(args)
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise CLIError(f"--out '{args.out}' exists and is not a directory")
    paths = export_model_files(cfg, args.out, mjcf=args.mjcf)
    for role, path in paths.items():
        print(f"wrote {role}: {path}")
    return 0


def cmd_statics(args: argparse.Namespace) -> int:
    am = AssemblerModel.from_config(_config(args))
    carrier, q = _carrier_from_args(args)
    plates = _plates_from_args(args, am, "give --plates FILE (or - for stdin) or --home")
    if carrier is not None:
        from .carrier import carrier_statics

        statics = carrier_statics(am, carrier, q, plates)
        if args.json:
            print(_dumps(statics.state.to_dict() | statics.to_dict()))
            return 0
        print(format_state_table(statics.state, f"Statics of {am.n} platforms on {carrier.name} (world gravity)"))
        print(_format_carrier(carrier, statics))
        return 0
    state = evaluate_state(am, plates)
    if args.json:
        print(_dumps(state.to_dict()))
    else:
        print(
            format_state_table(
                state,
                f"Statics of {am.n} platforms, payload {am.config.payload.mass:g} kg at {am.config.payload.offset:g} m",
            )
        )
    return 0


def _goal_from_args(args: argparse.Namespace):
    """The EE goal of ``solve``: ``--goal`` (rotation vector in rad) or ``--goal-deg`` (in deg)."""
    from .kinematics import taa_to_se3

    if args.goal is not None:
        return taa_to_se3(args.goal, what="--goal")
    if args.goal_deg is not None:
        return taa_to_se3(args.goal_deg, degrees=True, what="--goal-deg")
    raise CLIError("give the EE goal: --goal X Y Z RX RY RZ (m, rad) or --goal-deg X Y Z RX RY RZ (m, deg)")


def _optimize_options(args: argparse.Namespace):
    from .constraints import GoalTolerance
    from .optimize import OptimizeOptions

    ee = None
    if args.ee_tolerance is not None:
        pos, rot = args.ee_tolerance
        if not (pos > 0 and rot > 0):
            raise CLIError("--ee-tolerance POSITION ROTATION must both be > 0 (m, rad)")
        ee = GoalTolerance(position=pos, rotation=rot)
    try:
        return OptimizeOptions(method=args.method, w1=args.w1, w2=args.w2, ee_tolerance=ee,
                               max_iterations=args.max_iterations, ftol=args.ftol)  # fmt: skip
    except ValueError as exc:
        raise CLIError(str(exc)) from None


def cmd_solve(args: argparse.Namespace) -> int:
    """Internal poses for an EE goal: helper-arm initial condition, then (by default) the
    force optimization. An unreachable goal is an answer (exit 0, success false)."""
    from .helper_arm import HelperArmOptions
    from .kinematics import se3_to_taa
    from .solve import solve

    goal = _goal_from_args(args)
    try:
        helper = HelperArmOptions(d_step=args.d_step, max_attempts=args.max_attempts)
    except ValueError as exc:
        raise CLIError(str(exc)) from None
    options = None if args.no_optimize else _optimize_options(args)
    am = AssemblerModel.from_config(_config(args))
    carrier, q = _carrier_from_args(args)
    if carrier is not None:
        return _solve_on_carrier(args, am, carrier, q, goal)
    result = solve(am, goal, optimize=not args.no_optimize, options=options, helper_options=helper)
    capacity = None
    if args.capacity:
        from .capacity import payload_capacity

        start = result.optimized.plates if result.success and result.optimized is not None else None
        capacity = payload_capacity(am, goal, start=start)
    if args.json:
        doc = result.to_dict()
        if capacity is not None:
            doc["capacity"] = capacity.to_dict()
        print(_dumps(doc))
        return 0
    taa = se3_to_taa(result.goal)
    print(
        f"goal: p = ({', '.join(f'{x:.4f}' if abs(x) < 1e6 else f'{x:.4g}' for x in taa[:3])}) m, "
        f"rotation vector = ({np.rad2deg(taa[3]):.2f}, {np.rad2deg(taa[4]):.2f}, {np.rad2deg(taa[5]):.2f}) deg"
    )
    init = result.initial_result
    status = "valid" if init.success else "FAILED"
    print(f"initial condition (helper arm): {status} — {init.message} [{1e3 * init.time_s:.1f} ms]")
    title = "Initial condition" if init.success else "Home pose (no valid initial condition)"
    print(format_state_table(init.state, title))
    opt = result.optimization
    if opt is not None:
        print()
        print(f"optimization ({opt.method}): {'success' if result.success else 'FAILED'} — {result.message}; "
              f"{opt.iterations} iterations, {opt.evaluations} evaluations, {opt.time_s:.3f} s")  # fmt: skip
        starts = ", ".join(f"{name} {r.optimized.max_abs_force:.1f} N{'' if r.success else ' (failed)'}"
                           for name, r in result.runs.items())  # fmt: skip
        print(f"starts (max|F| reached): {starts}; kept: {result.start}")
        print(f"objective Ω = w1·max|F| + w2·sqrt(Σλ²): {opt.objective_initial:.3f} (start) -> "
              f"{opt.objective_optimized:.3f}")  # fmt: skip
        print(format_state_table(opt.optimized, "Optimized"))
    elif not args.no_optimize:
        print(f"\nno optimization: {result.message}")
    if capacity is not None:
        if capacity.success:
            print(f"\npayload capacity: {capacity.capacity_kg:.3f} kg ({capacity.binding} at its limit; "
                  f"{capacity.iterations} optimizations, {capacity.time_s:.2f} s)")  # fmt: skip
        else:
            print(f"\npayload capacity: none — {capacity.message}")
    return 0


def _solve_on_carrier(args: argparse.Namespace, am: AssemblerModel, carrier, q, goal) -> int:
    """``solve --carrier``: a world goal, the carrier moving unless ``--fixed-carrier``."""
    from .carrier import solve_on_carrier

    result = solve_on_carrier(am, carrier, goal, q, move_carrier=not args.fixed_carrier)
    if args.json:
        print(_dumps(result.to_dict()))
        return 0
    print(f"solve on {carrier.name} ({'carrier held' if args.fixed_carrier else 'carrier moving'}): "
          f"{'success' if result.success else 'FAILED'} — {result.message} [{result.time_s:.2f} s]")  # fmt: skip
    for t, cq, _score, note in result.candidates:
        print(f"  placement t = {t:.2f}: q = {np.round(cq, 3).tolist()}: {note}")
    if result.statics is not None:
        print(f"carrier q = {np.round(result.statics.q, 4).tolist()} rad")
        print(format_state_table(result.statics.state, "Optimized (world gravity)"))
        print(_format_carrier(carrier, result.statics))
    return 0


def cmd_reproduce(args: argparse.Namespace) -> int:
    """The paper's scenarios, initial vs optimized, with a markdown report and figures."""
    from .reproduce import force_tables, run_scenarios, summary_table, write_report
    from .scenarios import SCENARIOS

    names = args.scenario or list(SCENARIOS)
    unknown = [n for n in names if n not in SCENARIOS]
    if unknown:
        raise CLIError(f"unknown scenario {', '.join(unknown)}; valid: {', '.join(SCENARIOS)}")
    if args.out:
        _writable_parent(args.out, "--out directory")
    am = AssemblerModel.from_config(_config(args))
    outcomes = run_scenarios(am, names, _optimize_options(args))
    print(f"The paper's scenarios on {am.n} platforms, payload {am.config.payload.mass:g} kg "
          f"at {am.config.payload.offset:g} m (forces in N, tension positive)\n")  # fmt: skip
    print(summary_table(outcomes))
    for outcome in outcomes:
        print()
        print(force_tables(outcome))
    if args.out:
        path = write_report(am, outcomes, args.out)
        print(f"\nwrote report: {path}")
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    from .bench import run_benchmarks

    if args.repeat < 1:
        raise CLIError(f"--repeat must be an integer >= 1, got {args.repeat}")
    if args.platforms_sweep:
        from .bench import benchmark_platforms_sweep, format_sweep

        rows = benchmark_platforms_sweep()
        print(_dumps(rows) if args.json else format_sweep(rows))
        return 0
    if args.maps:
        from .bench import benchmark_maps, format_maps

        result = benchmark_maps()
        print(_dumps(result) if args.json else format_maps(result))
        return 0
    am = AssemblerModel.from_config(_config(args))
    if args.mujoco:
        from .bench import benchmark_mujoco, format_mujoco

        rows = benchmark_mujoco(am)
        print(_dumps(rows) if args.json else format_mujoco(rows))
        return 0
    results = run_benchmarks(am, repeat=args.repeat, optimize=not args.no_optimize, quick=args.quick)
    if args.grid:
        from .bench import benchmark_solve_grid

        results.update(benchmark_solve_grid(am))
    if args.json:
        print(_dumps(results))
        return 0
    scenarios = results.pop("optimize_scenarios", None)
    for key, value in results.items():
        print(f"{key:>30}: {value:10.3f}" if isinstance(value, float | int) else f"{key:>30}: {value}")
    if scenarios:
        print("\noptimization per scenario (same run): time [s] and objective Ω")
        print(
            f"{'scenario':<24}{'slsqp s':>9}{'paper s':>9}{'speedup':>9}{'Ω initial':>11}{'Ω slsqp':>9}{'Ω paper':>9}"
        )
        for name, v in scenarios.items():
            print(f"{name:<24}{v['slsqp_s']:9.3f}{v['paper_s']:9.3f}{v['speedup']:9.1f}"
                  f"{v['initial_objective']:11.2f}{v['slsqp_objective']:9.2f}{v['paper_objective']:9.2f}")  # fmt: skip
    return 0


def _finite_range(values: np.ndarray) -> list[float] | None:
    """[min, max] of the finite values, None without any."""
    ok = np.isfinite(values)
    return [float(values[ok].min()), float(values[ok].max())] if ok.any() else None


def cmd_map(args: argparse.Namespace) -> int:
    """A capability map: per cell reachability, optimized max|F|, payload capacity, binding."""
    from .config import load_config
    from .maps import parse_grid, read_map, run_map

    for option, value in (("--png file", args.png), ("--html file", args.html)):
        if value:
            _writable_parent(value, option)
    grid = parse_grid(args.grid, args.orientations)
    if args.workers is not None and args.workers < 0:
        raise CLIError(f"--workers must be >= 0, got {args.workers}")
    if args.batch_size is not None and args.batch_size < 1:
        raise CLIError(f"--batch-size must be >= 1, got {args.batch_size}")
    if args.sweep:
        names = [Path(c).stem for c in args.sweep]
        if len(set(names)) != len(names):
            raise CLIError("--sweep files must have different names (the map's config column)")
        configs = [(name, load_config(c)) for name, c in zip(names, args.sweep, strict=True)]
    else:
        configs = [(Path(args.config).stem if args.config else "default", _config(args))]
    run = run_map(grid, configs, args.out, workers=args.workers, scheduler=args.scheduler,
                  batch_size=args.batch_size, progress=not args.no_progress)  # fmt: skip
    table = read_map(args.out)
    reach = np.asarray(table.column("reachable").to_pylist(), dtype=bool)
    cap = np.asarray(table.column("capacity_kg").to_pylist(), dtype=float)
    force = np.asarray(table.column("max_abs_force").to_pylist(), dtype=float)
    doc = {"out": str(Path(args.out)), "cells": len(grid) * len(configs), "computed": run.computed,
           "already_done": run.skipped, "workers": run.workers, "time_s": run.time_s,
           "cells_per_s": run.cells_per_second, "reachable": int(reach.sum()),
           "max_abs_force_range": _finite_range(force), "capacity_kg_range": _finite_range(cap)}  # fmt: skip
    if args.png or args.html:
        am = AssemblerModel.from_config(configs[0][1])
        if args.png:
            from .maps.pictures import map_heatmaps
            from .plots import save

            doc["png"] = str(save(map_heatmaps(table, am, configs[0][0]), args.png))
        if args.html:
            from .maps.pictures import show_map_points
            from .viewer import StackViewer

            with StackViewer(am) as viewer:
                viewer.display(am.home)
                lo, hi = show_map_points(viewer, table, config=configs[0][0])
                viewer.set_title(f"Capability map: payload capacity {lo:.1f} (light) – {hi:.1f} kg (dark); "
                                 "gray: not reachable")  # fmt: skip
                doc["html"] = str(Path(args.html).resolve())
                viewer.static_html(doc["html"])
    if args.json:
        print(_dumps(doc))
        return 0
    print(f"map: {doc['computed']} cells computed, {doc['already_done']} already in {doc['out']}; "
          f"{run.workers or 'no'} workers, {run.time_s:.1f} s ({run.cells_per_second:.2f} cells/s)")  # fmt: skip
    print(f"reachable: {doc['reachable']} of {len(reach)} cells")
    if doc["max_abs_force_range"]:
        lo, hi = doc["max_abs_force_range"]
        print(f"optimized max|F|: {lo:.1f} – {hi:.1f} N")
    if doc["capacity_kg_range"]:
        lo, hi = doc["capacity_kg_range"]
        print(f"payload capacity: {lo:.2f} – {hi:.2f} kg")
    for key in ("png", "html"):
        if key in doc:
            print(f"wrote {doc[key]}")
    return 0


#: The paths ``plan --compare`` runs by default: from the home pose to these scenarios' goals.
COMPARE_SCENARIOS = ("translation", "vertical_lift", "orientation_transition")


def _plan_path(args: argparse.Namespace, am: AssemblerModel):
    """The EE path and start state of ``plan``: (path, start or None)."""
    from .kinematics import taa_to_se3
    from .motion import EEPath, read_waypoints

    if args.waypoints:
        return read_waypoints(args.waypoints, kind=args.path), None
    goal = taa_to_se3(args.to, what="--to")
    if args.from_ is None:
        return EEPath((am.home[-1], goal), args.path), am.home
    return EEPath((taa_to_se3(args.from_, what="--from"), goal), args.path), None


def cmd_plan(args: argparse.Namespace) -> int:
    """A force-optimal motion along an EE path, timed within the legs' limits."""
    from .motion import PlanOptions
    from .motion.timing import plan_trajectory

    for option, value in (("--out file", args.out), ("--plot file", args.plot)):
        if value:
            _writable_parent(value, option)
    if args.to is None and not args.waypoints and not args.compare:
        raise CLIError("give --to X Y Z RX RY RZ (from the home pose, or --from ...) or --waypoints FILE")
    try:
        options = PlanOptions(w3=args.w3)
    except ValueError as exc:
        raise CLIError(str(exc)) from None
    am = AssemblerModel.from_config(_config(args))
    if args.compare:
        return _plan_compare(args, am, options)
    path, start = _plan_path(args, am)
    motion = plan_trajectory(am, path, start, options, rate=args.rate)
    doc = motion.to_dict()
    traj = motion.trajectory
    if args.out and traj is not None:
        doc["out"] = str(traj.write(args.out))
    if args.plot and traj is not None:
        from .motion.timing import trajectory_states
        from .plots import save, trajectory_plot

        times, states = trajectory_states(am, traj, 200)
        title = "planned motion" if args.to is None else "home → goal" if args.from_ is None else "--from → --to"
        doc["plot"] = str(save(trajectory_plot(am, traj, states, times, title), args.plot))
    if args.json:
        print(_dumps(doc))
        return 0
    print(f"plan: {'success' if doc['success'] else 'FAILED'} — {doc['reason']}")
    if motion.plan.states:
        print(f"{doc['samples']} samples, peak max|F| {doc['peak_max_abs_force']:.2f} N, total leg travel "
              f"{doc['total_leg_travel_m']:.3f} m, planned in {motion.plan.time_s:.2f} s")  # fmt: skip
    if traj is not None:
        print(f"trajectory: {traj.duration:.2f} s at {args.rate:g} Hz ({len(traj.times)} samples), every sample valid: "
              f"{'yes' if traj.feasible.all() else 'NO'}")  # fmt: skip
    for key in ("out", "plot"):
        if key in doc:
            print(f"wrote {doc[key]}")
    return 0


def _plan_compare(args: argparse.Namespace, am: AssemblerModel, options) -> int:
    """``plan --compare``: our plan against the helper arm per sample and linear leg lengths."""
    from .motion import EEPath
    from .motion.compare import compare_motion
    from .scenarios import scenario

    if args.to is not None or args.waypoints:
        path, start = _plan_path(args, am)
        runs = [("path", path, start)]
    else:
        runs = [(name, EEPath((am.home[-1], scenario(name).goal), args.path), am.home) for name in COMPARE_SCENARIOS]
    results = [compare_motion(am, path, start, options, rate=args.rate, name=name) for name, path, start in runs]
    if args.json:
        print(_dumps([{"path": c.name, "success": c.motion.success, "reason": c.motion.reason,
                       "methods": {m: f.to_dict() for m, f in c.figures.items()}} for c in results]))  # fmt: skip
        return 0
    print(f"{'path':<24}{'plan':<16}{'peak max|F| N':>14}{'leg travel m':>13}{'duration s':>11}"
          f"{'valid %':>9}{'limits %':>9}{'off path mm':>12}")  # fmt: skip
    for c in results:
        if not c.figures:
            print(f"{c.name:<24}no plan: {c.motion.reason}")
        for m, f in c.figures.items():
            print(f"{c.name:<24}{m:<16}{f.peak_max_abs_force:14.2f}{f.total_leg_travel:13.3f}{f.duration:11.2f}"
                  f"{100 * f.valid_fraction:9.1f}{100 * f.limits_fraction:9.1f}"
                  f"{1e3 * f.max_path_deviation:12.2f}")  # fmt: skip
    print("valid: every limit and the EE within the path tolerance at every output sample; "
          "limits: legs, joints and forces only")  # fmt: skip
    return 0


def cmd_simulate(args: argparse.Namespace) -> int:
    """Hold a pose with MuJoCo's position actuators: EE drift and actuator forces over time."""
    from .simulate import hold_pose

    if args.html:
        _writable_parent(args.html, "--html file")
    am = AssemblerModel.from_config(_config(args))
    if args.trajectory:
        if args.html:
            raise CLIError("--html shows a held pose; with --trajectory use 'view --trajectory FILE --html'")
        return _simulate_trajectory(args, am)
    ours = evaluate_state(am, _plates_from_args(args, am, "give --plates FILE (or - for stdin) or --home"))
    result = hold_pose(am, ours.plates, seconds=args.seconds, samples=args.samples,
                       drift_tolerance=1e-3 * args.drift_tolerance)  # fmt: skip
    gap = np.abs(result.final_forces - ours.forces)
    if args.json:
        doc = result.to_dict()
        doc["statics_forces"] = ours.forces.tolist()
        doc["max_force_difference_n"] = float(gap.max())
        print(_dumps(doc))
    else:
        print(f"MuJoCo holding the pose for {result.times[-1]:.2f} s ({am.n} platforms, actuators at our leg lengths)")
        print(f"{'t [s]':>7} {'EE drift [mm]':>14} {'EE turn [deg]':>14} {'max|F| [N]':>11} {'at limit':>9}")
        for k in np.unique(np.linspace(0, len(result.times) - 1, 11).round().astype(int)):
            turn_deg = np.rad2deg(result.ee_rotation_drift[k])
            print(f"{result.times[k]:7.3f} {1e3 * result.ee_drift[k]:14.3f} {turn_deg:14.3f} "
                  f"{np.abs(result.forces[k]).max():11.3f} {int(result.saturated[k].sum()):9d}")  # fmt: skip
        j, i = np.unravel_index(gap.argmax(), gap.shape)
        print(f"final forces vs statics: max difference {gap.max():.3f} N ({leg_label(j, i)}), "
              f"statics max|F| = {ours.max_abs_force:.3f} N")  # fmt: skip
        print(f"held: {'yes' if result.held else 'NO'} — {result.message}")
    if args.html:
        from .viewer import StackViewer

        with StackViewer(am) as viewer:
            viewer.animate([evaluate_state(am, pa) for pa in result.samples])
            viewer.frame()
            path = Path(args.html).resolve()
            viewer.static_html(path)
        print(f"wrote {path}")
    return 0


def _simulate_trajectory(args: argparse.Namespace, am: AssemblerModel) -> int:
    """``simulate --trajectory``: MuJoCo's servos run a planned trajectory."""
    from .motion.timing import read_trajectory
    from .simulate import follow_trajectory

    traj = read_trajectory(args.trajectory)
    result = follow_trajectory(am, traj, tolerance=1e-3 * args.drift_tolerance)
    if args.json:
        print(_dumps(result.to_dict()))
        return 0
    print(f"MuJoCo running {Path(args.trajectory).name}: {traj.duration:.2f} s, then 0.5 s settling")
    print(f"{'t [s]':>7} {'EE off plan [mm]':>17} {'max|F| MuJoCo':>14} {'max|F| plan':>12} {'at limit':>9}")
    for k in np.unique(np.linspace(0, len(result.times) - 1, 11).round().astype(int)):
        print(f"{result.times[k]:7.2f} {1e3 * result.ee_error[k]:17.3f} {result.max_abs_force[k]:14.2f} "
              f"{result.planned_max_abs_force[k]:12.2f} {int(result.saturated[k]):9d}")  # fmt: skip
    print(f"followed: {'yes' if result.followed else 'NO'} — {result.message}")
    return 0


def _view_on_carrier(args: argparse.Namespace, am: AssemblerModel, viewer, carrier, q) -> StackState:
    """``view --carrier``: the stack on its carrier (a world goal is solved with the carrier moving)."""
    from .carrier import carrier_statics, solve_on_carrier

    if args.trajectory:
        raise CLIError("--trajectory cannot be shown on a carrier")
    if args.scenario or args.goal is not None or args.goal_deg is not None:
        if args.scenario:
            raise CLIError("--scenario goals are in the base frame; give a world --goal with --carrier")
        result = solve_on_carrier(am, carrier, _goal_from_args(args), q)
        if result.statics is None:
            raise CLIError(f"no pose to show: {result.message}")
        statics = result.statics
        print(f"solve on {carrier.name}: {'success' if result.success else 'FAILED'} — {result.message}",
              file=sys.stderr)  # fmt: skip
    else:
        statics = carrier_statics(am, carrier, q, _plates_from_args(args, am, "give --goal, --plates FILE or --home"))
    shown = viewer.display(statics.state)
    viewer.show_carrier(carrier, statics.q)
    viewer.set_title(f"On {carrier.name}: max|F| {shown.max_abs_force:.1f} N, carrier torque up to "
                     f"{100 * statics.carrier_ratio:.0f} % of its effort limit ({statics.binding} binds)")  # fmt: skip
    viewer.frame()
    return shown


def _view_title(args: argparse.Namespace, result) -> str:
    """Title of ``view --goal/--scenario``: what was asked and max|F| initial → optimized."""
    from .scenarios import scenario

    if args.scenario:
        what = f"Scenario {args.scenario}: {scenario(args.scenario).title}"
    else:
        taa = args.goal if args.goal is not None else args.goal_deg
        unit = "rad" if args.goal is not None else "deg"
        what = (
            f"Goal ({', '.join(f'{x:g}' for x in taa[:3])}) m, rotation ({', '.join(f'{x:g}' for x in taa[3:])}) {unit}"
        )
    init = f"{result.initial.max_abs_force:.1f} N" if result.initial is not None else "none"
    opt = f"{result.optimized.max_abs_force:.1f} N" if result.optimized is not None else "none"
    return f"{what} — max|F| initial {init} → optimized {opt}"


def _animate_trajectory(viewer, am: AssemblerModel, path: str, frames: int) -> StackState:
    """Store a trajectory file's motion in the viewer, in real time; returns its peak state."""
    from .motion.timing import read_trajectory, trajectory_states

    if not 2 <= frames <= 2000:
        raise CLIError(f"--frames must be an integer in [2, 2000], got {frames}")
    traj = read_trajectory(path)
    _, states = trajectory_states(am, traj, frames)
    viewer.animate(states, fps=max(1.0, (len(states) - 1) / max(traj.duration, 1e-9)), color_forces=True)
    peak = max(st.max_abs_force for st in states)
    viewer.set_title(f"Trajectory {Path(path).name}: {traj.duration:.1f} s, peak max|F| {peak:.1f} N "
                     "(legs: sleeve colored by force, frame by frame)")  # fmt: skip
    print(f"trajectory: {traj.duration:.2f} s, {len(states)} frames", file=sys.stderr)
    return max(states, key=lambda st: st.max_abs_force)


def cmd_view(args: argparse.Namespace) -> int:
    """Show a pose in Meshcat: write a standalone page (--html) or serve until Ctrl-C."""
    # Long by design: the live server's start, signal handling and serving loop read as one flow.
    import time
    import webbrowser

    from .viewer import StackViewer, interrupt_on_signals

    if args.html:
        _writable_parent(args.html, "--html file")
    am = AssemblerModel.from_config(_config(args))
    restore_signals = interrupt_on_signals()  # kill / a closed terminal stop it as Ctrl-C does
    viewer = None
    try:
        viewer = StackViewer(am, host=args.host, force_scale=args.force_scale)
        carrier, carrier_q = _carrier_from_args(args)
        if carrier is not None:
            shown = _view_on_carrier(args, am, viewer, carrier, carrier_q)
        elif args.scenario:
            from .kinematics import se3_to_taa
            from .scenarios import scenario

            args.goal = list(se3_to_taa(scenario(args.scenario).goal))
        if carrier is not None:
            pass
        elif args.goal is not None or args.goal_deg is not None:
            try:
                from .solve import solve  # lazy: the solver is only needed for --goal
            except ImportError as exc:
                raise CLIError(f"--goal needs assembler_pin.solve, which cannot be imported: {exc}") from None

            result = solve(am, _goal_from_args(args))
            if result.initial is None and result.optimized is None:
                raise CLIError(f"no pose to show: {result.message}")
            arm = getattr(getattr(result, "initial_result", None), "arm_points", None)
            viewer.show_comparison(result.initial, result.optimized, None if args.no_arm else arm)
            viewer.set_title(_view_title(args, result))
            shown = result.optimized if result.optimized is not None else result.initial
            if args.animate and result.initial is not None and result.optimized is not None:
                from .viewer import interpolate_states

                viewer.animate(interpolate_states(am, result.initial, result.optimized, args.animate))
            print(f"solve: {'success' if result.success else 'FAILED'} — {result.message}", file=sys.stderr)
        elif args.trajectory:
            shown = _animate_trajectory(viewer, am, args.trajectory, args.frames)
        else:
            plates = _plates_from_args(args, am, "give one of --goal, --goal-deg, --plates FILE or --home")
            shown = viewer.display(plates)
            verdict = "" if shown.feasible else " (VIOLATES limits)"
            name = "Home pose" if args.home else Path(args.plates).name
            viewer.set_title(f"{name} — max|F| {shown.max_abs_force:.1f} N{verdict}")
            viewer.frame()
        print(
            f"max |F| = {shown.max_abs_force:.3f} N, feasible: {'yes' if shown.feasible else 'NO'}",
            file=sys.stderr,
        )
        if args.html:
            path = Path(args.html).resolve()
            viewer.static_html(path)
            print(f"wrote {path}")
            if args.open:
                webbrowser.open(path.as_uri())
            return 0
        viewer.frame()
        try:
            print(viewer.url, flush=True)
            if args.open:
                webbrowser.open(viewer.url)
            while True:
                time.sleep(0.5)
        except KeyboardInterrupt:
            return 0  # serving until stopped: stopping is the normal end
    except KeyboardInterrupt as stop:  # stopped before the view was ready
        print(f"assembler-pin view: {stop or 'interrupted'} before the view was ready", file=sys.stderr)
        return 128 + getattr(stop, "signum", 2)  # the shell's status for a signal (SIGINT = 2)
    finally:
        if viewer is not None:
            viewer.close()
        restore_signals()


def _add_carrier_arguments(p: argparse.ArgumentParser, note: str = "") -> None:
    """``--carrier NAME``, ``--carrier-q`` and ``--mount``, read by :func:`_carrier_from_args`."""
    from .carrier import CARRIERS

    p.add_argument("--carrier", metavar="NAME",
                   help="mount the stack on a carrier arm from example-robot-data: "
                        f"{', '.join(CARRIERS)}{note}")  # fmt: skip
    p.add_argument("--carrier-q", nargs="+", type=float, metavar="Q",
                   help="the carrier's joint angles [rad] (default: its upright configuration)")  # fmt: skip
    p.add_argument("--mount", nargs=6, type=float, metavar=("X", "Y", "Z", "RX", "RY", "RZ"),
                   help="base plate pose in the carrier's tool frame [m, rad] (default identity)")  # fmt: skip


def _carrier_from_args(args: argparse.Namespace):
    """(carrier, q) of ``--carrier``, or (None, None) without one."""
    if not getattr(args, "carrier", None):
        if getattr(args, "carrier_q", None) or getattr(args, "mount", None):
            raise CLIError("--carrier-q and --mount need --carrier NAME")
        return None, None
    from .carrier import Carrier
    from .kinematics import taa_to_se3

    carrier = Carrier(args.carrier, None if args.mount is None else taa_to_se3(args.mount, what="--mount"))
    q = carrier.upright_q if args.carrier_q is None else carrier.check_q(args.carrier_q, "--carrier-q")
    return carrier, q


def _format_carrier(carrier, statics) -> str:
    """The carrier's joint torques against their effort limits, and what binds."""
    lines = [f"carrier {carrier.name}: joint torques [N·m] (effort limit, use)"]
    for k, (tau, limit, ratio) in enumerate(zip(statics.torques, carrier.effort_limit, statics.torque_ratio,
                                                strict=True)):  # fmt: skip
        lines.append(f"  joint {k}: {tau:9.3f}  ({limit:g}, {100 * ratio:5.1f} %)")
    lines.append(f"stack at {100 * statics.stack_ratio:.1f} % of its force limit, carrier at "
                 f"{100 * statics.carrier_ratio:.1f} % of its effort limit: {statics.binding} binds; "
                 f"within every limit: {'yes' if statics.within_limits else 'NO'}")  # fmt: skip
    return "\n".join(lines)


def _add_goal_arguments(group: argparse._MutuallyExclusiveGroup, note: str = "") -> None:
    """``--goal`` (rotation vector in rad) and ``--goal-deg``, read by :func:`_goal_from_args`."""
    taa = ("X", "Y", "Z", "RX", "RY", "RZ")
    group.add_argument("--goal", nargs=6, type=float, metavar=taa,
                       help="EE goal: position [m] and rotation vector [rad], world frame" + note)  # fmt: skip
    group.add_argument("--goal-deg", nargs=6, type=float, metavar=taa,
                       help="as --goal with the rotation vector in degrees")  # fmt: skip


def _add_optimize_arguments(p: argparse.ArgumentParser) -> None:
    """The optimizer's options; defaults and choices come from :class:`OptimizeOptions`."""
    from .optimize import METHODS, OptimizeOptions

    d = OptimizeOptions()
    p.add_argument("--method", choices=METHODS, default=d.method,
                   help=f"slsqp: smooth epigraph form, analytic gradients; paper: the paper's non-smooth objective "
                        f"with finite differences (default {d.method})")  # fmt: skip
    p.add_argument("--w1", type=float, default=d.w1, help=f"weight of max|F| [1/N] (default {d.w1:g})")
    p.add_argument("--w2", type=float, default=d.w2,
                   help=f"weight of the plate deviation term [1/rad] (default {d.w2:g})")  # fmt: skip
    p.add_argument("--ee-tolerance", type=float, nargs=2, metavar=("POSITION", "ROTATION"),
                   help="let the EE move this far from the goal [m, rad] (default: fixed at the goal)")  # fmt: skip
    p.add_argument("--max-iterations", type=int, default=d.max_iterations,
                   help=f"solver iteration limit (default {d.max_iterations})")  # fmt: skip
    p.add_argument("--ftol", type=float, default=d.ftol, help=f"solver tolerance on the objective (default {d.ftol:g})")


def _add_helper_arm_arguments(p: argparse.ArgumentParser) -> None:
    """The helper arm's options; defaults come from :class:`HelperArmOptions`."""
    from .helper_arm import HelperArmOptions

    d = HelperArmOptions()
    p.add_argument("--d-step", type=float, default=d.d_step, metavar="M",
                   help=f"helper-arm link-length scan step [m] (default {d.d_step:g})")  # fmt: skip
    p.add_argument("--max-attempts", type=int, default=d.max_attempts, metavar="N",
                   help=f"helper-arm recursion limit: link lengths tried (default {d.max_attempts})")  # fmt: skip


def build_parser() -> argparse.ArgumentParser:
    """The ``assembler-pin`` argument parser (one-line refusals, see :class:`_Parser`)."""
    # Long by design: a declarative list of the subcommands and their options.
    parser = _Parser(
        prog="assembler-pin",
        description="Serialized Stewart platforms (the Assembler) on Pinocchio: model, statics, solve.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress to stderr")
    sub = parser.add_subparsers(dest="command", required=True)

    def add(name: str, help_: str) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=help_, description=help_)
        p.add_argument("--config", metavar="FILE", help="YAML configuration (default: built-in)")
        return p

    p = add("export", "write assembler.urdf, its closure sidecar assembler.yaml and the helper arm's URDF")
    p.add_argument("--out", default="urdf", metavar="DIR", help="output directory (default: urdf)")
    p.add_argument("--mjcf", action="store_true", help="also write assembler.xml, the MuJoCo model (loops closed)")
    p.set_defaults(func=cmd_export)

    p = add("statics", "actuator forces of given plate poses (tension positive, newtons)")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--plates", metavar="FILE", help='JSON {"plates": [n+1 4x4]} file, or - for stdin')
    src.add_argument("--home", action="store_true", help="use the home pose")
    _add_carrier_arguments(p, " (the plates are then relative to the base plate)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_statics)

    p = add("solve", "a valid pose of the whole stack for an end-effector goal")
    _add_goal_arguments(p.add_mutually_exclusive_group())
    p.add_argument("--no-optimize", action="store_true", help="only the helper-arm initial condition")
    _add_helper_arm_arguments(p)
    _add_optimize_arguments(p)
    _add_carrier_arguments(p, " (the goal is then in the world; the carrier's joints join the search)")
    p.add_argument("--fixed-carrier", action="store_true", help="with --carrier: hold it at --carrier-q")
    p.add_argument("--capacity", action="store_true",
                   help="also the largest payload [kg] some valid internal pose holds at the goal")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_solve)

    p = add("reproduce", "the paper's scenarios: initial vs optimized forces, tables, report with figures")
    p.add_argument("--out", metavar="DIR", help="write report.md and PNG figures into DIR")
    p.add_argument("--scenario", action="append", metavar="NAME", help="only this scenario (repeatable)")
    _add_optimize_arguments(p)
    p.set_defaults(func=cmd_reproduce)

    p = add("bench", "median time per call of the hot computations")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--repeat", type=int, default=300, help="calls per figure (default 300)")
    p.add_argument("--no-optimize", action="store_true", help="skip the optimization comparison (slow: ~10 s)")
    p.add_argument("--quick", action="store_true", help="minimal goal sets: a smoke test, not figures")
    p.add_argument("--grid", action="store_true", help="also solve the 120-goal level-EE grid (~2 min)")
    p.add_argument("--platforms-sweep", action="store_true",
                   help="only the cost of each stack size n = 1..64: build, memory, statics, FK, "
                        "initial condition, optimization (~5 min)")  # fmt: skip
    p.add_argument("--maps", action="store_true",
                   help="only the capability map's cells/s on 1 and 2 local Dask workers (~1 min)")  # fmt: skip
    p.add_argument("--mujoco", action="store_true",
                   help="only MuJoCo against our statics: inverse statics and held poses (~15 s)")  # fmt: skip
    p.set_defaults(func=cmd_bench)

    p = add("plan", "a force-optimal motion along an EE path, as leg-length commands within the legs' limits")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--to", nargs=6, type=float, metavar=("X", "Y", "Z", "RX", "RY", "RZ"),
                     help="EE goal (m, rotation vector in rad); from the home pose unless --from")  # fmt: skip
    src.add_argument("--waypoints", metavar="FILE", help="JSON or CSV waypoints (TAA rows, optional times)")
    p.add_argument("--from", dest="from_", nargs=6, type=float, metavar=("X", "Y", "Z", "RX", "RY", "RZ"),
                   help="with --to: start at the optimized pose of this EE pose")  # fmt: skip
    p.add_argument("--path", choices=("screw", "linear"), default="screw",
                   help="interpolation on SE(3): screw (geodesic, default) or linear (line + slerp)")  # fmt: skip
    p.add_argument("--rate", type=float, default=50.0, help="output samples per second (default 50)")
    p.add_argument("--w3", type=float, default=100.0, help="weight of the motion term Σ ΔL² [1/m²] (default 100)")
    p.add_argument("--out", metavar="FILE", help="write the trajectory (.csv, or JSON for any other suffix)")
    p.add_argument("--plot", metavar="PNG", help="write the lengths, speeds and forces over time with their limits")
    p.add_argument("--compare", action="store_true",
                   help="compare with the helper arm per sample and linear leg lengths (default paths: home to "
                        f"{', '.join(COMPARE_SCENARIOS)})")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_plan)

    p = add("map", "capability map: reachability, optimized max|F|, payload capacity per cell (Dask, resumable)")
    p.add_argument("--grid", required=True, metavar="SPEC",
                   help="EE positions [m]: AXIS=VALUE or START:STOP:COUNT, e.g. x=0:0.6:10,y=0,z=0.5:1:10")  # fmt: skip
    p.add_argument("--orientations", metavar="SPEC",
                   help='EE rotation vectors in degrees, e.g. "0 0 0; 0 30 0" (default level)')  # fmt: skip
    p.add_argument("--sweep", nargs="+", metavar="FILE",
                   help="design sweep: the map of each configuration file (config column: its name)")  # fmt: skip
    p.add_argument("--out", required=True, metavar="DIR", help="map directory (Parquet parts; a rerun extends it)")
    p.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default: the machine's cores; 0: here, no Dask)")  # fmt: skip
    p.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler, e.g. tcp://10.0.0.5:8786")
    p.add_argument("--batch-size", type=int, default=None, metavar="N", help="cells per task (default automatic)")
    p.add_argument("--png", metavar="FILE", help="heatmap slices: reachability, max|F|, capacity")
    p.add_argument("--html", metavar="FILE", help="the cells as a point cloud colored by capacity, in the viewer")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_map)

    p = add("simulate", "hold a pose in MuJoCo with force-limited position actuators: EE drift, forces over time")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--plates", metavar="FILE", help='JSON {"plates": [n+1 4x4]} file, or - for stdin')
    src.add_argument("--home", action="store_true", help="hold the home pose")
    src.add_argument("--trajectory", metavar="FILE", help="run a trajectory written by 'plan --out' on the servos")
    p.add_argument("--seconds", type=float, default=2.0, help="simulated time [s] (default 2)")
    p.add_argument("--samples", type=int, default=50, help="stored samples (default 50)")
    p.add_argument("--drift-tolerance", type=float, default=5.0, metavar="MM",
                   help="largest EE displacement of a held pose [mm] (default 5)")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--html", metavar="FILE", help="also write the simulated motion as a standalone viewer page")
    p.set_defaults(func=cmd_simulate)

    p = add("view", "show a pose in Meshcat (live server until Ctrl-C, or a standalone HTML page)")
    src = p.add_mutually_exclusive_group(required=True)
    _add_goal_arguments(src, " (shows the initial and optimized poses)")
    src.add_argument("--plates", metavar="FILE", help='JSON {"plates": [n+1 4x4]} file, or - for stdin')
    src.add_argument("--home", action="store_true", help="show the home pose")
    from .scenarios import SCENARIOS
    from .viewer import FORCE_SCALES

    src.add_argument("--scenario", choices=list(SCENARIOS),
                     help="solve a scenario's goal and show its initial and optimized poses")  # fmt: skip
    src.add_argument("--trajectory", metavar="FILE",
                     help="animate a trajectory written by 'plan --out' (legs colored by force)")  # fmt: skip
    _add_carrier_arguments(p, " (--home/--plates relative to its base plate, --goal in the world)")
    p.add_argument("--force-scale", choices=FORCE_SCALES, default="auto",
                   help="where leg colors saturate: auto (default: max|F|, at least 10%% of the limit), "
                        "limit, max")  # fmt: skip
    p.add_argument("--frames", type=int, default=150, help="with --trajectory: frames of the animation (default 150)")
    p.add_argument("--html", metavar="FILE", help="write a standalone HTML page instead of serving")
    p.add_argument("--open", action="store_true", help="open the page / viewer URL in a web browser")
    p.add_argument(
        "--animate",
        type=int,
        default=0,
        metavar="STEPS",
        help="with --goal: animate initial -> optimized in STEPS leg-length steps",
    )
    p.add_argument("--no-arm", action="store_true", help="with --goal: do not draw the helper arm")
    p.add_argument("--host", default="127.0.0.1",
                   help="interface the live page listens on (default 127.0.0.1: this machine only; "
                        "0.0.0.0: every interface)")  # fmt: skip
    p.set_defaults(func=cmd_view)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command; input problems end it with exit status 2 and one line on stderr."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except CLIError as exc:
        print(f"assembler-pin: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s"
    )
    try:
        return int(args.func(args))
    except AssemblerError as exc:
        print(f"assembler-pin {args.command}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except OSError as exc:  # an output path that cannot be written
        where = f" '{exc.filename}'" if exc.filename else ""
        print(f"assembler-pin {args.command}: error: cannot write{where}: {exc.strerror or exc}", file=sys.stderr)
        return 2


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())


if __name__ == "__main__":
    sys.exit(main())
