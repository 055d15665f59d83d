"""``assembler-pin simulate``: MuJoCo holding a pose or running a trajectory."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from ..exceptions import CLIError

if TYPE_CHECKING:
    from ..model.assembler import AssemblerModel
from .common import add_pose_source, config_from_args, dumps, plates_from_args
from .paths import path_argument, writable_parent


def add_parser(add) -> None:
    """Register the ``simulate`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("simulate", "hold a pose in MuJoCo with force-limited position actuators: EE drift, forces over time")
    src = add_pose_source(p, "hold the home pose", required=True)
    src.add_argument(
        "--trajectory",
        type=path_argument,
        metavar="FILE",
        help="run a trajectory written by 'plan --out' on the servos",
    )
    p.add_argument("--seconds", type=float, default=2.0, help="simulated time [s] (default 2)")
    p.add_argument("--samples", type=int, default=50, help="stored samples (default 50)")
    p.add_argument(
        "--drift-tolerance",
        type=float,
        default=5.0,
        metavar="MM",
        help="largest EE displacement of a held pose [mm] (default 5)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--html", type=path_argument, metavar="FILE", help="also write the simulated motion as a standalone viewer page"
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Hold a pose with MuJoCo's position actuators: EE drift and actuator forces over time
    (exit 0 when held, 1 when not: the answer is printed either way)."""
    import numpy as np

    from ..common.labels import leg_label
    from ..config.bounds import check_bound
    from ..model.assembler import AssemblerModel
    from ..simulate import hold_pose
    from ..state import evaluate_state

    check_bound("simulate.drift_tolerance", args.drift_tolerance, "--drift-tolerance", CLIError)
    if not args.trajectory:
        check_bound("simulate.seconds", args.seconds, "--seconds", CLIError)
        check_bound("simulate.samples", args.samples, "--samples", CLIError)
    if args.html:
        writable_parent(args.html, "--html file")
    am = AssemblerModel.from_config(config_from_args(args))
    if args.trajectory:
        if args.html:
            raise CLIError("--html shows a held pose; with --trajectory use 'view --trajectory FILE --html'")
        return _simulate_trajectory(args, am)
    ours = evaluate_state(am, plates_from_args(args, am, "give --plates FILE (or - for stdin) or --home"))
    result = hold_pose(
        am, ours.plates, seconds=args.seconds, samples=args.samples, drift_tolerance=1e-3 * args.drift_tolerance
    )
    gap = np.abs(result.final_forces - ours.forces)
    if args.json:
        doc = result.to_dict()
        doc["statics_forces"] = ours.forces.tolist()
        doc["max_force_difference_n"] = float(gap.max())
        print(dumps(doc))
    else:
        print(f"MuJoCo holding the pose for {result.times[-1]:.2f} s ({am.n} platforms, actuators at our leg lengths)")
        print(f"{'t [s]':>7} {'EE drift [mm]':>14} {'EE turn [deg]':>14} {'max|F| [N]':>11} {'at limit':>9}")
        for k in np.unique(np.linspace(0, len(result.times) - 1, 11).round().astype(int)):
            turn_deg = np.rad2deg(result.ee_rotation_drift[k])
            unloaded = result.times[k] == 0.0
            force = f"{'unloaded':>11}" if unloaded else f"{np.abs(result.forces[k]).max():11.3f}"
            print(
                f"{result.times[k]:7.3f} {1e3 * result.ee_drift[k]:14.3f} {turn_deg:14.3f} "
                f"{force} {int(result.saturated[k].sum()):9d}"
            )
        print(hold_note(am, ours, result))
        j, i = np.unravel_index(gap.argmax(), gap.shape)
        print(
            f"final forces vs statics: max difference {gap.max():.3f} N ({leg_label(j, i)}), "
            f"statics max|F| = {ours.max_abs_force:.3f} N"
        )
        print(f"held: {'yes' if result.held else 'NO'} — {result.message}")
    if args.html:
        from ..viz import StackViewer

        with StackViewer(am) as viewer:
            viewer.animate([evaluate_state(am, pa) for pa in result.samples])
            viewer.frame()
            path = Path(args.html)
            viewer.static_html(path)
        print(f"wrote {path}")
    return 0 if result.held else 1


#: Why a table's t = 0 row carries no MuJoCo force (two lines, 100 characters at most).
UNLOADED_NOTE = (
    "At t = 0 the servos stand at the commanded lengths and push nothing; they take up the load\nas the stack settles."
)


def hold_note(am: AssemblerModel, ours, result) -> str:
    """What the hold table shows, below it: why the first row carries no force, and the EE's
    drift beside the legs' sag alone (``assembler-pin stiffness``)."""
    import numpy as np

    from ..compliance import stiffness

    springs = stiffness(am, ours)
    sag = f"{1e3 * float(np.linalg.norm(springs.sag_translation)):.3f} mm" if springs.success else "none"
    return (
        f"{UNLOADED_NOTE} EE drift {1e3 * result.ee_drift[-1]:.3f} mm; the legs' sag alone "
        f"('assembler-pin stiffness'): {sag}.\n"
        "The servos are as stiff as those legs; the rest is MuJoCo's soft ball joints and loop\n"
        "closures, which the stiffness model takes as rigid (docs: MuJoCo)."
    )


def _simulate_trajectory(args: argparse.Namespace, am: AssemblerModel) -> int:
    """``simulate --trajectory``: MuJoCo's servos run a planned trajectory."""
    import numpy as np

    from ..motion.timing import read_trajectory
    from ..simulate import follow_trajectory

    traj = read_trajectory(args.trajectory)  # the format; follow_trajectory holds every row to the model
    result = follow_trajectory(am, traj, tolerance=1e-3 * args.drift_tolerance)
    if args.json:
        print(dumps(result.to_dict()))
        return 0 if result.followed else 1
    print(f"MuJoCo running {Path(args.trajectory).name}: {traj.duration:.2f} s, then 0.5 s settling")
    print(f"{'t [s]':>7} {'EE off plan [mm]':>17} {'max|F| MuJoCo':>14} {'max|F| plan':>12} {'at limit':>9}")
    for k in np.unique(np.linspace(0, len(result.times) - 1, 11).round().astype(int)):
        ours = f"{'unloaded':>14}" if result.times[k] == 0.0 else f"{result.max_abs_force[k]:14.2f}"
        print(
            f"{result.times[k]:7.2f} {1e3 * result.ee_error[k]:17.3f} {ours} "
            f"{result.planned_max_abs_force[k]:12.2f} {int(result.saturated[k]):9d}"
        )
    if result.times[0] == 0.0:
        print(UNLOADED_NOTE)
    print(f"followed: {'yes' if result.followed else 'NO'} — {result.message}")
    return 0 if result.followed else 1
