"""``assembler-pin hexapod stand|capacity|walk``: k stacks under one body, the structure's
equilibrium, the body it carries and its walk."""

from __future__ import annotations

import argparse

from .common import add_scene_argument, config_from_args, dumps, scene_from_args
from .paths import path_argument, writable_parent

#: The hexapod's actions.
ACTIONS = ("stand", "capacity", "walk")


def add_parser(add) -> None:
    """Register the ``hexapod`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add(
        "hexapod",
        "stacks under one rigid body (the config's hexapod section): the whole structure's equilibrium",
    )
    p.add_argument(
        "action",
        choices=ACTIONS,
        help="stand: the equilibrium for the commanded lengths; capacity: the largest body mass within every "
        "limit; walk: a walk on the floor to --to, every sample checked",
    )
    p.add_argument("--stacks", type=int, metavar="K", help="stacks under the body (default: hexapod.stacks)")
    p.add_argument(
        "--radius", type=float, metavar="R", help="radius of the feet's circle [m] (default: hexapod.radius)"
    )
    p.add_argument("--body-mass", type=float, metavar="M", help="the body's mass [kg] (default: hexapod.body_mass)")
    p.add_argument(
        "--feet",
        choices=("welded", "resting"),
        help="welded: the feet are held; resting: they stand on the floor (friction, lift-off, tipping) "
        "(default: welded; walk: resting)",
    )
    p.add_argument(
        "--commands",
        choices=("own", "optimal"),
        default="own",
        help="the legs' commanded lengths: own (each pose's own) or optimal (the min max|F| distribution, "
        "then the smallest sum of squares, realized exactly)",
    )
    add_scene_argument(p, "the clearance of every stack and of the body to its obstacles and floor")
    p.add_argument(
        "--html",
        type=path_argument,
        metavar="PAGE",
        help="write a standalone page of the machine: legs by force, the body, the support polygon, the centre of mass",
    )
    p.add_argument(
        "--plot",
        type=path_argument,
        metavar="PNG",
        help="write the feet from above and the legs by force from the side",
    )
    _add_walk_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def _add_walk_arguments(p) -> None:
    p.add_argument(
        "--to",
        type=float,
        nargs=3,
        metavar=("X", "Y", "YAW"),
        help="walk: the body's displacement, x and y [m] and yaw [rad] (|yaw| <= pi)",
    )
    p.add_argument("--gait", choices=("tripod", "wave"), default="tripod", help="walk: the stacks step in groups")
    p.add_argument("--step", type=float, default=0.1, metavar="L", help="walk: a foot's longest step [m], in (0, 2]")
    p.add_argument("--samples", type=int, default=4, metavar="N", help="walk: samples per phase, 1..50")
    p.add_argument("--lift", type=float, default=0.03, metavar="H", help="walk: a swinging foot's lift [m], in [0, 1]")
    p.add_argument(
        "--out",
        type=path_argument,
        metavar="FILE",
        help="walk: write the trajectory (every sample's feet, commands and forces; docs/formats.md)",
    )


def _config(args: argparse.Namespace):
    """The configuration with the options given on the command line in its ``hexapod`` section
    (checked by the section's own reader) and no tool payload on the stacks (the body is the
    load)."""
    import dataclasses

    from ..config.schema import PayloadConfig
    from ..exceptions import CLIError, ConfigError

    cfg = config_from_args(args)
    changes = {"stacks": args.stacks, "radius": args.radius, "body_mass": args.body_mass}
    flags = {"stacks": "--stacks", "radius": "--radius", "body_mass": "--body-mass"}
    section = cfg.hexapod
    for key, value in changes.items():
        if value is None:
            continue
        try:
            section = dataclasses.replace(section, **{key: value})
        except ConfigError as exc:
            raise CLIError(f"{flags[key]}: {str(exc).split(' is invalid: ')[-1]}") from None
    return cfg.replace(hexapod=section, payload=PayloadConfig(mass=0.0))


def stand_document(am, result, commands: str = "own") -> dict:
    """The JSON answer of ``hexapod stand`` (``docs/guides/hexapod.md``)."""
    import math

    import numpy as np

    from ..hexapod import length_sensitivity

    margin = result.stability_margin_m
    per_micron = 1e-6 * float(np.abs(length_sensitivity(am, result)).sum(axis=1).max()) if result.converged else None
    return {
        "feasible": result.feasible,
        "violations": list(result.violations),
        "feet": result.feet,
        "stacks": int(result.forces.shape[0]),
        "forces": result.forces.tolist(),
        "max_abs_force": result.max_abs_force,
        "foot_wrenches": result.foot_wrenches.tolist(),
        "lifted": result.lifted.tolist(),
        "body_displacement": result.body_displacement.tolist(),
        "stability_margin_m": None if math.isnan(margin) else margin,
        "com": result.com.tolist(),
        "mass": result.mass,
        "converged": result.converged,
        "stable": result.stable,
        "clearance": result.clearance.to_dict(),
        "commands": commands,
        "lengths": result.lengths.tolist(),
        "force_per_micron": per_micron,
    }


def run(args: argparse.Namespace) -> int:
    """``stand``: exit 0 when the machine stands within every limit, 1 when not (the answer is
    still printed); ``capacity``: 0 when it carries a body, 1 when not even an empty one;
    ``walk``: 0 when the walk succeeds, 1 when it stops (and why); 2 for refused input."""
    from ..exceptions import CLIError
    from ..model.assembler import AssemblerModel

    walking = args.action == "walk"
    if walking != (args.to is not None):
        raise CLIError("--to X Y YAW is needed by walk, and only by walk")
    if not walking and args.out:
        raise CLIError("--out is for walk (its trajectory file)")
    if args.out:
        writable_parent(args.out, "--out file")
    if args.feet is None:
        args.feet = "resting" if walking else "welded"
    am = AssemblerModel.from_config(_config(args))
    if walking:
        if args.plot or args.html or args.commands != "own" or args.scene is not None:
            raise CLIError("walk takes neither --plot, --html, --commands nor --scene")
        return _walk(am, args)
    if args.action == "capacity":
        if args.plot or args.html or args.commands != "own" or args.body_mass is not None:
            raise CLIError("capacity takes neither --plot, --html, --commands nor --body-mass (it finds the mass)")
        return _capacity(am, args)
    return _stand(am, args)


def _capacity(am, args: argparse.Namespace) -> int:
    """``hexapod capacity``: the largest body mass with the poses' own lengths
    (:func:`~assembler_pin.hexapod.hexapod_capacity`) and, welded, with the force-optimal
    commands of every mass (:func:`~assembler_pin.walk.macro_capacity`)."""
    from ..hexapod import configured_hexapod, hexapod_capacity
    from ..walk import macro_capacity

    hc = am.config.hexapod
    stacks, _, body_com = configured_hexapod(am)
    scene = scene_from_args(args)
    got = hexapod_capacity(am, stacks, body_com, None, args.feet, hc.friction, hc.min_margin, scene=scene)
    optimal, note = macro_capacity(am, stacks, body_com)
    doc = {
        "feet": args.feet,
        "capacity_kg": got.mass,
        "limit": got.limit,
        "max_abs_force": got.at_capacity.max_abs_force,
        "optimal_commands_capacity_kg": optimal,
        "optimal_commands_note": note,
    }
    if args.json:
        print(dumps(doc))
    else:
        head = f"hexapod of {len(stacks)} stacks, feet {args.feet}: carries {got.mass:.2f} kg"
        print(head)
        print(f"  above it: {got.limit}"[:100])
        print(f"  with the force-optimal commands of every mass, welded: {optimal:.2f} kg")
    return 0 if got.mass > 0 else 1


def _stand(am, args: argparse.Namespace) -> int:
    from ..hexapod import configured_hexapod, stand

    if args.plot:
        writable_parent(args.plot, "--plot file")
    if args.html:
        writable_parent(args.html, "--html file")
    scene = scene_from_args(args)
    hc = am.config.hexapod
    stacks, body_mass, body_com = configured_hexapod(am)
    lengths, missing, commands = None, None, args.commands
    if commands == "optimal":
        from ..hexapod import force_optimal_commands

        chosen = force_optimal_commands(am, stacks, body_mass, body_com, smallest=True)
        if chosen.success:
            lengths = chosen.lengths
        else:  # answered with the poses' own lengths, infeasible, and why
            missing, commands = f"no force-optimal commands: {chosen.message}", "own"
    result = stand(am, stacks, body_mass, body_com, lengths, args.feet, hc.friction, hc.min_margin, scene)
    if missing is not None:
        result = result.with_violation(missing)
    if args.plot:
        from ..hexapod.figure import save_stand_figure

        save_stand_figure(am, result, args.plot)
    if args.html:
        from ..viz.hexapod import write_hexapod_page

        write_hexapod_page(am, result, args.html)
    doc = stand_document(am, result, commands)
    print(dumps(doc) if args.json else format_stand(doc))
    return 0 if result.feasible else 1


def format_stand(doc: dict) -> str:
    """A compact text report (lines ≤ 100 characters)."""
    import numpy as np

    margin = doc["stability_margin_m"]
    verdict = "feasible" if doc["feasible"] else f"{len(doc['violations'])} violations"
    lines = [
        f"hexapod of {doc['stacks']} stacks, feet {doc['feet']}: {verdict}; max|F| {doc['max_abs_force']:.3f} N",
        f"  body moved {np.round(1e6 * np.array(doc['body_displacement'][:3]), 2).tolist()} µm, "
        f"turned {np.round(1e6 * np.array(doc['body_displacement'][3:]), 2).tolist()} µrad",
        f"  machine {doc['mass']:.3f} kg, centre of mass {np.round(doc['com'], 4).tolist()} m"
        + ("" if margin is None else f", stability margin {margin:.4f} m"),
        f"  commands {doc['commands']}: one µm on every leg moves a force by up to "
        + ("?" if doc["force_per_micron"] is None else f"{doc['force_per_micron']:.3g} N"),
        f"  clearance {doc['clearance']['min_distance']:.4g} m ({' / '.join(doc['clearance']['between'])})"[:100],
    ]
    lines += [f"  violation: {v}"[:100] for v in doc["violations"]]
    for i, (w, lifted) in enumerate(zip(doc["foot_wrenches"], doc["lifted"], strict=True)):
        state = "lifted" if lifted else f"force {np.round(w[:3], 3).tolist()} N"
        lines.append(f"  foot {i}: {state}"[:100])
    return "\n".join(lines)


def walk_document(result) -> dict:
    """The JSON answer of ``hexapod walk`` (``docs/guides/hexapod.md``)."""
    import math

    def number(x: float) -> float | None:
        return None if math.isnan(x) else x

    return {
        "success": result.success,
        "reason": result.reason,
        "gait": result.gait,
        "feet": result.feet,
        "steps": result.cycles,
        "samples": [
            {
                "t": s.t,
                "step": s.step,
                "phase": s.phase,
                "body_pose": s.body_pose.tolist(),
                "stance": s.stance.tolist(),
                "stability_margin_m": number(s.stability_margin_m),
                "max_abs_force": number(s.max_abs_force),
                "violations": list(s.violations),
            }
            for s in result.samples
        ],
    }


def _walk(am, args: argparse.Namespace) -> int:
    from ..exceptions import CLIError, HexapodError
    from ..hexapod import walk, write_walk

    try:
        got = walk(am, args.to, args.gait, args.step, args.feet, args.samples, args.lift)
    except HexapodError as exc:
        raise CLIError(str(exc)) from None
    doc = walk_document(got)
    if args.out:
        write_walk(args.out, got)
    if args.json:
        print(dumps(doc))
    else:
        last = doc["samples"][-1]
        verdict = "walks" if got.success else "stops"
        print(f"hexapod {args.gait} walk, feet {args.feet}: {verdict} in {got.cycles} steps, {last['t']:.3f} s")
        margins = [s["stability_margin_m"] for s in doc["samples"] if s["stability_margin_m"] is not None]
        forces = [s["max_abs_force"] for s in doc["samples"] if s["max_abs_force"] is not None]
        if margins:
            print(f"  smallest stability margin {min(margins):.4f} m")
        if forces:
            print(f"  largest leg force {max(forces):.3f} N over {len(doc['samples'])} samples")
        if got.reason:
            print(f"  {got.reason}"[:100])
    return 0 if got.success else 1
