"""``assembler-pin plan``: motions along an EE path."""

from __future__ import annotations

import argparse
import time
from typing import TYPE_CHECKING

from ..exceptions import CLIError

if TYPE_CHECKING:
    from ..model.assembler import AssemblerModel
from .common import add_scene_argument, config_from_args, dumps, progress_for, radians_checked, scene_from_args, wrapped
from .paths import path_argument, writable_parent


def add_parser(add) -> None:
    """Register the ``plan`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("plan", "a force-optimal motion along an EE path, as leg-length commands within the legs' limits")
    src = p.add_mutually_exclusive_group()
    src.add_argument(
        "--to",
        nargs=6,
        type=float,
        metavar=("X", "Y", "Z", "RX", "RY", "RZ"),
        help="EE goal (m, rotation vector in rad); from the home pose unless --from",
    )
    src.add_argument(
        "--waypoints",
        type=path_argument,
        metavar="FILE",
        help="JSON or CSV waypoints (TAA rows, optional times); from the home pose unless --from, as --to",
    )
    p.add_argument(
        "--from",
        dest="from_",
        nargs=6,
        type=float,
        metavar=("X", "Y", "Z", "RX", "RY", "RZ"),
        help="with --to or --waypoints: start at the optimized pose of this EE pose (default: the home pose)",
    )
    p.add_argument(
        "--path",
        choices=("screw", "linear"),
        default="screw",
        help="interpolation on SE(3): screw (geodesic, default) or linear (line + slerp)",
    )
    p.add_argument(
        "--time-law",
        choices=("auto", "quintic", "optimal"),
        default="auto",
        help="time law: quintic (one smooth rest-to-rest law), optimal (TOPP-RA: fastest within the legs' "
        "speed, acceleration and force limits, forces with the motion's part), auto (default: the faster "
        "one whose every row is valid)",
    )
    p.add_argument("--rate", type=float, default=50.0, help="output samples per second, 1..1000 (default 50)")
    p.add_argument("--w3", type=float, default=100.0, help="weight of the motion term Σ ΔL² [1/m²] (default 100)")
    p.add_argument(
        "--out", type=path_argument, metavar="FILE", help="write the trajectory (.csv, or JSON for any other suffix)"
    )
    p.add_argument(
        "--plot",
        type=path_argument,
        metavar="PNG",
        help="write the lengths, speeds and forces over time with their limits",
    )
    p.add_argument(
        "--compare",
        action="store_true",
        help="compare with the helper arm per sample and linear leg lengths (default paths: home to "
        f"{', '.join(COMPARE_SCENARIOS)})",
    )
    add_scene_argument(p, "every sample and the motion between samples keep their clearance (not with --compare)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


#: The paths ``plan --compare`` runs by default: from the home pose to these scenarios' goals.
COMPARE_SCENARIOS = ("translation", "vertical_lift", "orientation_transition")


def _plan_path(args: argparse.Namespace, am: AssemblerModel):
    """The EE path and start state of ``plan``: (path, start or None). Every path starts
    where ``--to`` starts: the home pose (its state given), or the ``--from`` pose (its
    optimized pose); a waypoint file is joined on after that start."""
    from ..kinematics import taa_to_se3
    from ..motion import EEPath, read_waypoints

    first = am.home[-1] if args.from_ is None else taa_to_se3(radians_checked(args.from_, "--from"), what="--from")
    start = am.home if args.from_ is None else None
    if not args.waypoints:
        return EEPath((first, taa_to_se3(radians_checked(args.to, "--to"), what="--to")), args.path), start
    path = read_waypoints(args.waypoints, kind=args.path)
    if _same_pose(path.waypoints[0], first):
        return EEPath((first, *path.waypoints[1:]), path.kind, path.times), start
    if path.times is not None:
        where = "the home pose" if args.from_ is None else "the --from pose"
        raise CLIError(
            f"--waypoints FILE has times and starts away from {where}: make its first waypoint "
            f"{_taa_text(first)} at t = 0, or drop the times"
        )
    return EEPath((first, *path.waypoints), path.kind), start


def _same_pose(a, b, tol: float = 1e-6) -> bool:
    """Whether two EE poses coincide: ``|log6(a⁻¹ b)| <= tol`` [m and rad together]."""
    import numpy as np
    import pinocchio as pin

    return bool(np.linalg.norm(pin.log6(a.actInv(b)).vector) <= tol)


def _taa_text(pose) -> str:
    """``x y z rx ry rz`` of a pose (m, rotation vector in rad), as a waypoint row reads."""
    from ..kinematics import se3_to_taa

    return " ".join(f"{v:.6g}" for v in se3_to_taa(pose))


def run(args: argparse.Namespace) -> int:
    """A force-optimal motion along an EE path, timed within the legs' limits.

    Exit status 0 when the motion reaches the end of the path with every row valid, 1 when
    it does not (the answer is printed and ``--out`` holds the valid prefix, if any).
    """
    from ..config.bounds import check_bound
    from ..model.assembler import AssemblerModel
    from ..motion import PlanOptions
    from ..motion.timing import plan_trajectory

    started = time.perf_counter()
    for option, value in (("--out file", args.out), ("--plot file", args.plot)):
        if value:
            writable_parent(value, option)
    check_bound("plan.rate", args.rate, "--rate", CLIError)
    if args.to is None and not args.waypoints and not args.compare:
        raise CLIError("give --to X Y Z RX RY RZ (from the home pose, or --from ..) or --waypoints FILE")
    try:
        options = PlanOptions(w3=args.w3)
    except ValueError as exc:
        raise CLIError(str(exc)) from None
    if args.compare and args.scene:
        raise CLIError("--compare plans without obstacles: give it without --scene")
    scene = scene_from_args(args)  # read before the model is built: a bad scene is refused at once
    am = AssemblerModel.from_config(config_from_args(args))
    if args.compare:
        return _plan_compare(args, am, options)
    path, start = _plan_path(args, am)
    prog = progress_for(args, "plan")
    try:
        motion = plan_trajectory(
            am, path, start, options, rate=args.rate, progress=prog, time_law=args.time_law, scene=scene
        )
        doc = _write_outputs(args, am, motion, prog)
        doc["start"] = "home" if args.from_ is None else "from"  # where the path starts (as --to)
    finally:
        prog.close()
    if args.json:
        print(dumps(doc))
    else:
        _print_summary(args, motion, doc, time.perf_counter() - started)
    return 0 if motion.success else 1


def _write_outputs(args: argparse.Namespace, am: AssemblerModel, motion, prog) -> dict:
    """``--out`` and ``--plot`` of a planned motion (valid rows only), each written atomically."""
    doc = motion.to_dict()
    traj = motion.trajectory
    if args.out and traj is not None:
        doc["out"] = str(traj.write(args.out))
    if args.plot and traj is not None:
        from ..common.files import atomic_path
        from ..motion.timing import trajectory_states
        from ..plots.trajectory import trajectory_plot

        times, states = trajectory_states(am, traj, 200, progress=prog)
        title = "planned motion" if args.to is None else "home → goal" if args.from_ is None else "--from → --to"
        fig = trajectory_plot(am, traj, states, times, title)
        with atomic_path(args.plot) as tmp:
            fig.savefig(tmp, dpi=150, format="png")
        doc["plot"] = str(args.plot)
    return doc


def _print_summary(args: argparse.Namespace, motion, doc: dict, elapsed: float) -> None:
    """The text answer of ``plan``: what was planned, the trajectory, the files written."""
    traj = motion.trajectory
    print(wrapped(f"plan: {'success' if doc['success'] else 'FAILED'} — {doc['reason']}"))
    print("start: the home pose" if doc["start"] == "home" else "start: the optimized pose of --from")
    if motion.plan.states:
        print(
            f"{doc['samples']} samples, peak max|F| {doc['peak_max_abs_force']:.2f} N, total leg travel "
            f"{doc['total_leg_travel_m']:.3f} m"
        )
    if motion.replans:
        print(f"re-planned {motion.replans} time(s) with half steps: an output sample failed its check")
    if traj is not None:
        extent = (
            "the whole path"
            if traj.complete
            else (f"the valid prefix only, to u = {doc['path_reached']:.4f} of {doc['path_segments']}")
        )
        print(
            wrapped(
                f"trajectory: {traj.duration:.2f} s at {args.rate:g} Hz ({len(traj.times)} samples, every one "
                f"valid), {extent}"
            )
        )
        laws = ", ".join(f"{k} {v:.2f} s" for k, v in motion.law_durations.items())
        print(
            f"time law: {motion.time_law} ({laws}); peak max|F| with the motion's part "
            f"{doc['peak_max_abs_dynamic_force']:.2f} N"
        )
    elif args.out:
        print(f"no valid trajectory: {args.out} not written")
    for key in ("out", "plot"):
        if key in doc:
            print(f"wrote {doc[key]}" + ("" if traj is None or traj.complete else " (valid prefix, complete: false)"))
    print(f"done in {elapsed:.1f} s")


def _plan_compare(args: argparse.Namespace, am: AssemblerModel, options) -> int:
    """``plan --compare``: our plan against the helper arm per sample and linear leg lengths."""
    from ..motion import EEPath
    from ..motion.compare import compare_motion
    from ..scenarios import scenario

    if args.to is not None or args.waypoints:
        path, start = _plan_path(args, am)
        runs = [("path", path, start)]
    else:
        runs = [(name, EEPath((am.home[-1], scenario(name).goal), args.path), am.home) for name in COMPARE_SCENARIOS]
    results = [
        compare_motion(am, path, start, options, rate=args.rate, name=name, time_law=args.time_law)
        for name, path, start in runs
    ]
    if args.json:
        print(
            dumps(
                [
                    {
                        "path": c.name,
                        "success": c.motion.success,
                        "reason": c.motion.reason,
                        "methods": {m: f.to_dict() for m, f in c.figures.items()},
                    }
                    for c in results
                ]
            )
        )
        return _compare_status(results)
    print(
        f"{'path':<24}{'plan':<16}{'peak max|F| N':>14}{'travel m':>9}{'time s':>8}"
        f"{'valid %':>8}{'limits %':>9}{'off path mm':>12}"
    )
    for c in results:
        if not c.figures:
            print(wrapped(f"{c.name:<24}no plan: {c.motion.reason}"))
        for m, f in c.figures.items():
            print(
                f"{c.name:<24}{m:<16}{f.peak_max_abs_force:14.2f}{f.total_leg_travel:9.3f}{f.duration:8.2f}"
                f"{100 * f.valid_fraction:8.1f}{100 * f.limits_fraction:9.1f}"
                f"{1e3 * f.max_path_deviation:12.2f}"
            )
    print(
        wrapped(
            "travel: total leg travel; time: duration; valid: every limit and the EE within "
            "the path tolerance at every output sample; limits: legs, joints and forces only"
        )
    )
    return _compare_status(results)


def _compare_status(results) -> int:
    """0 when every compared path was planned to its end (each ``success``), else 1: the
    exit status follows the ``success`` fields of the answer."""
    return 0 if all(c.motion.success for c in results) else 1
