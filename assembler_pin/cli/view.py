"""``assembler-pin view``: the Meshcat viewer."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from ..exceptions import CLIError

if TYPE_CHECKING:
    from ..model.assembler import AssemblerModel
    from ..state import StackState
from .common import (
    add_carrier_arguments,
    add_goal_arguments,
    add_scene_argument,
    carrier_from_args,
    config_from_args,
    goal_from_args,
    plates_from_args,
    scene_from_args,
)
from .paths import path_argument, writable_parent


def add_parser(add) -> None:
    """Register the ``view`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("view", "show a pose in Meshcat (live server until Ctrl-C, or a standalone HTML page)")
    src = p.add_mutually_exclusive_group(required=True)
    add_goal_arguments(src, " (shows the initial and optimized poses)")
    src.add_argument(
        "--plates", type=path_argument, metavar="FILE", help='JSON {"plates": [n+1 4x4]} file, or - for stdin'
    )
    src.add_argument("--home", action="store_true", help="show the home pose")
    from ..config.choices import FORCE_SCALES, SCENARIO_NAMES

    src.add_argument(
        "--scenario",
        choices=SCENARIO_NAMES,
        metavar="NAME",
        help=f"solve a scenario's goal and show its initial and optimized poses ({', '.join(SCENARIO_NAMES)})",
    )
    src.add_argument(
        "--trajectory",
        type=path_argument,
        metavar="FILE",
        help="animate a trajectory written by 'plan --out' (legs colored by force)",
    )
    add_carrier_arguments(p, " (--home/--plates relative to its base plate, --goal in the world)")
    p.add_argument(
        "--force-scale",
        choices=FORCE_SCALES,
        default="auto",
        help="where leg colors saturate: auto (default: max|F|, at least 10%% of the limit), limit, max",
    )
    p.add_argument("--frames", type=int, default=150, help="with --trajectory: frames of the animation (default 150)")
    p.add_argument("--html", type=path_argument, metavar="FILE", help="write a standalone HTML page instead of serving")
    p.add_argument("--open", action="store_true", help="open the page / viewer URL in a web browser")
    p.add_argument(
        "--animate",
        type=int,
        default=0,
        metavar="STEPS",
        help="with --goal: animate initial -> optimized in STEPS leg-length steps",
    )
    p.add_argument("--no-arm", action="store_true", help="with --goal: do not draw the helper arm")
    add_scene_argument(
        p,
        "drawn with the stack; the shown pose's closest pair of bodies marked, its distance [m] in the legend; "
        "--goal/--scenario solved keeping clear of it (not with --carrier)",
    )
    _add_compliance_arguments(p)
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help="interface the live page listens on (default 127.0.0.1: this machine only; 0.0.0.0: every interface)",
    )
    p.set_defaults(func=run)


def _add_compliance_arguments(p: argparse.ArgumentParser) -> None:
    """``--loaded [--exaggerate F]`` and ``--ellipsoid [--ellipsoid-force N]``."""
    p.add_argument(
        "--loaded",
        action="store_true",
        help="also draw the loaded pose: the legs as springs (leg.stiffness) under gravity and payload, "
        "commanded to the shown pose's lengths; a teal ghost with every displacement exaggerated",
    )
    p.add_argument(
        "--exaggerate",
        type=float,
        metavar="F",
        help="with --loaded: draw each plate F times its displacement from the rigid pose "
        "(default: a 1-2-5 factor drawing the largest about 5 cm; the factor is in the legend)",
    )
    p.add_argument(
        "--ellipsoid",
        action="store_true",
        help="also draw the EE's compliance ellipsoid (principal axes of the translational compliance)",
    )
    p.add_argument(
        "--ellipsoid-force",
        type=float,
        metavar="N",
        help="with --ellipsoid: each semi-axis is the EE's sag under N newtons along it (default 100)",
    )


def _view_on_carrier(args: argparse.Namespace, am: AssemblerModel, viewer, carrier, q) -> StackState:
    """``view --carrier``: the stack on its carrier (a world goal is solved with the carrier moving)."""
    from ..carrier import carrier_statics, solve_on_carrier

    if args.trajectory:
        raise CLIError("--trajectory cannot be shown on a carrier")
    if args.scenario or args.goal is not None or args.goal_deg is not None:
        if args.scenario:
            raise CLIError("--scenario goals are in the base frame; give a world --goal with --carrier")
        result = solve_on_carrier(am, carrier, goal_from_args(args), q)
        if result.statics is None:
            raise CLIError(f"no pose to show: {result.message}")
        statics = result.statics
        print(
            f"solve on {carrier.name}: {'success' if result.success else 'FAILED'} — {result.message}", file=sys.stderr
        )
    else:
        statics = carrier_statics(am, carrier, q, plates_from_args(args, am, "give --goal, --plates FILE or --home"))
    shown = viewer.display(statics.state)
    viewer.show_carrier(carrier, statics.q)
    viewer.set_title(
        f"On {carrier.name}: max|F| {shown.max_abs_force:.1f} N, carrier torque up to "
        f"{100 * statics.carrier_ratio:.0f} % of its effort limit ({statics.binding} binds)"
    )
    return shown


def _view_title(args: argparse.Namespace, result) -> str:
    """Title of ``view --goal/--scenario``: what was asked and max|F| initial → optimized."""
    from ..scenarios import scenario

    if args.scenario:
        what = f"Scenario {args.scenario}: {scenario(args.scenario).title}"
    else:
        taa = args.goal if args.goal is not None else args.goal_deg
        unit = "rad" if args.goal is not None else "deg"
        xyz, rotation = ", ".join(f"{x:g}" for x in taa[:3]), ", ".join(f"{x:g}" for x in taa[3:])
        what = f"Goal ({xyz}) m, rotation vector ({rotation}) {unit}"
    init = f"{result.initial.max_abs_force:.1f} N" if result.initial is not None else "none"
    opt = f"{result.optimized.max_abs_force:.1f} N" if result.optimized is not None else "none"
    return f"{what} — max|F| initial {init} → optimized {opt}"


def _animate_trajectory(viewer, am: AssemblerModel, path: str, frames: int) -> StackState:
    """Store a trajectory file's motion in the viewer, in real time; returns its peak state."""
    from ..motion.timing import read_trajectory, trajectory_states

    traj = read_trajectory(path)
    _, states = trajectory_states(am, traj, frames)  # every row held to stack FK of its lengths
    viewer.animate(states, fps=max(1.0, (len(states) - 1) / max(traj.duration, 1e-9)), color_forces=True)
    peak = max(st.max_abs_force for st in states)
    viewer.set_title(
        f"Trajectory {Path(path).name}: {traj.duration:.1f} s, peak max|F| {peak:.1f} N "
        "(legs: sleeve colored by force, frame by frame)"
    )
    print(f"trajectory: {traj.duration:.2f} s, {len(states)} frames", file=sys.stderr)
    return max(states, key=lambda st: st.max_abs_force)


DEFAULT_ELLIPSOID_FORCE = 100.0
"""``view --ellipsoid``: the force [N] whose sag the ellipsoid's semi-axes are, by default."""


def _check_options(args: argparse.Namespace) -> None:
    """Refuse, before anything is computed, counts and factors out of their bounds,
    options given without the one they qualify and a trajectory that is not a regular file
    (CLIError: one line, exit 2)."""
    from ..config.bounds import check_bound
    from ..config.inputs import checked_input_path

    if args.trajectory:  # read after the viewer starts: its path checked now
        checked_input_path(args.trajectory, "trajectory", CLIError)
    check_bound("view.animate", args.animate, "--animate", CLIError)
    check_bound("view.frames", args.frames, "--frames", CLIError)
    if args.exaggerate is not None:
        if not args.loaded:
            raise CLIError("--exaggerate needs --loaded (it scales the loaded pose's displacements)")
        check_bound("view.exaggerate", args.exaggerate, "--exaggerate", CLIError)
    if args.ellipsoid_force is not None:
        if not args.ellipsoid:
            raise CLIError("--ellipsoid-force needs --ellipsoid (it sizes the compliance ellipsoid)")
        check_bound("view.ellipsoid_force", args.ellipsoid_force, "--ellipsoid-force", CLIError)
    if (args.loaded or args.ellipsoid) and args.trajectory:
        raise CLIError("--loaded and --ellipsoid draw one pose: give --home, --plates, --goal or --scenario")
    if args.html:
        writable_parent(args.html, "--html file")
    if args.scene and args.carrier:
        raise CLIError("--scene is checked on a fixed base and is not available with --carrier")


def _view_goal(args: argparse.Namespace, am: AssemblerModel, viewer) -> StackState:
    """``view --goal/--scenario``: solve, show initial (ghost) and optimized, maybe animate."""
    try:
        from ..solver.pipeline import solve  # lazy: the solver is only needed for --goal
    except ImportError as exc:
        raise CLIError(f"--goal needs assembler_pin.solver.pipeline, which cannot be imported: {exc}") from None
    if args.scenario:
        from ..kinematics import se3_to_taa
        from ..scenarios import scenario

        args.goal = list(se3_to_taa(scenario(args.scenario).goal))
    result = solve(am, goal_from_args(args), scene=viewer.scene)
    if result.initial is None and result.optimized is None:
        raise CLIError(f"no pose to show: {result.message}")
    arm = getattr(getattr(result, "initial_result", None), "arm_points", None)
    viewer.show_comparison(result.initial, result.optimized, None if args.no_arm else arm)
    viewer.set_title(_with_clearance(_view_title(args, result), viewer))
    if args.animate and result.initial is not None and result.optimized is not None:
        from ..viz import interpolate_states

        viewer.animate(interpolate_states(am, result.initial, result.optimized, args.animate))
    print(f"solve: {'success' if result.success else 'FAILED'} — {result.message}", file=sys.stderr)
    best = result.optimized if result.optimized is not None else result.initial
    assert best is not None  # refused above when both are None
    return best


def _view_plates(args: argparse.Namespace, am: AssemblerModel, viewer) -> StackState:
    """``view --home/--plates``: the pose, legs colored by force."""
    plates = plates_from_args(args, am, "give one of --goal, --goal-deg, --plates FILE or --home")
    shown = viewer.display(plates)
    verdict = "" if shown.feasible else " (VIOLATES limits)"
    name = "Home pose" if args.home else Path(args.plates).name
    viewer.set_title(_with_clearance(f"{name} — max|F| {shown.max_abs_force:.1f} N{verdict}", viewer))
    return shown


def _with_clearance(title: str, viewer) -> str:
    """``title`` and, with a scene, the marked closest pair (distance [m] and the two bodies)."""
    pair = viewer.closest
    if pair is None:
        return title
    return f"{title}; clearance {pair.distance:.4f} m ({pair.between[0]} – {pair.between[1]})"


def _draw(args: argparse.Namespace, am: AssemblerModel, viewer) -> StackState:
    """Draw what the options ask for; returns the state whose numbers are reported."""
    carrier, carrier_q = carrier_from_args(args)
    if carrier is not None:
        shown = _view_on_carrier(args, am, viewer, carrier, carrier_q)
    elif args.scenario or args.goal is not None or args.goal_deg is not None:
        shown = _view_goal(args, am, viewer)
    elif args.trajectory:
        shown = _animate_trajectory(viewer, am, args.trajectory, args.frames)
    else:
        shown = _view_plates(args, am, viewer)
    _draw_compliance(args, viewer, shown)
    viewer.frame()
    return shown


def _draw_compliance(args: argparse.Namespace, viewer, shown: StackState) -> None:
    """``--loaded`` and ``--ellipsoid``: the compliant truss at the shown pose."""
    if args.loaded:
        view = viewer.show_loaded(shown.plates, args.exaggerate)
        sag = 1e3 * math.hypot(*view.loaded.translation)
        print(f"loaded pose: EE sag {sag:.4f} mm, drawn with displacements × {view.factor:g}", file=sys.stderr)
    if args.ellipsoid:
        force = DEFAULT_ELLIPSOID_FORCE if args.ellipsoid_force is None else args.ellipsoid_force
        ell = viewer.show_ellipsoid(shown.plates, force)
        axes = ", ".join(f"{1e3 * a:.4g}" for a in ell.semi_axes)
        print(f"compliance ellipsoid: semi-axes {axes} mm (sag under {force:g} N)", file=sys.stderr)


def _serve(args: argparse.Namespace, viewer) -> int:
    """Write the standalone page (--html) or serve the live one until stopped."""
    import time
    import webbrowser

    from ..common.signals import forget_interrupt

    if args.html:
        path = Path(args.html)
        viewer.static_html(path)
        print(f"wrote {path}")
        if args.open:
            webbrowser.open(path.resolve().as_uri())
        return 0
    try:
        print(viewer.url, flush=True)
        if args.open:
            webbrowser.open(viewer.url)
        while True:
            time.sleep(0.5)
    except KeyboardInterrupt:
        forget_interrupt()
        return 0  # serving until stopped: stopping is the normal end


def run(args: argparse.Namespace) -> int:
    """Show a pose in Meshcat: write a standalone page (--html) or serve until Ctrl-C."""
    from ..common.signals import forget_interrupt, interrupt_on_signals
    from ..model.assembler import AssemblerModel
    from ..viz import StackViewer

    _check_options(args)
    scene = scene_from_args(args)  # a bad scene is refused before the server starts
    am = AssemblerModel.from_config(config_from_args(args))
    restore_signals = interrupt_on_signals()  # kill / a closed terminal stop it as Ctrl-C does
    viewer = None
    try:
        viewer = StackViewer(am, host=args.host, force_scale=args.force_scale, scene=scene)
        shown = _draw(args, am, viewer)
        feasible = "yes" if shown.feasible else "NO"
        print(f"max |F| = {shown.max_abs_force:.3f} N, feasible: {feasible}", file=sys.stderr)
        if viewer.closest is not None:
            print(viewer.closest.label, file=sys.stderr)
        return _serve(args, viewer)
    except KeyboardInterrupt as stop:  # stopped before the view was ready
        forget_interrupt()
        print(f"assembler-pin view: {stop or 'interrupted'} before the view was ready", file=sys.stderr)
        return 128 + getattr(stop, "signum", 2)  # the shell's status for a signal (SIGINT = 2)
    finally:
        if viewer is not None:
            viewer.close()
        restore_signals()
