"""``assembler-pin statics``: the forces of given plate poses."""

from __future__ import annotations

import argparse

from ..exceptions import CLIError
from .common import (
    add_carrier_arguments,
    add_pose_source,
    add_scene_argument,
    carrier_from_args,
    config_from_args,
    dumps,
    format_carrier,
    format_state_table,
    plates_from_args,
    scene_from_args,
)


def add_parser(add) -> None:
    """Register the ``statics`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("statics", "actuator forces of given plate poses (tension positive, newtons)")
    add_pose_source(p)
    add_carrier_arguments(p, " (the plates are then relative to the base plate)")
    p.add_argument(
        "--stiffness",
        action="store_true",
        help="add the EE's sag and stiffness (legs as springs of leg.stiffness N/m; the keys of stiffness --json)",
    )
    p.add_argument(
        "--support",
        choices=("base", "ee", "both"),
        default="base",
        help="the plates held: base (plate 0, default), ee (the EE plate alone), both (see 'support')",
    )
    add_scene_argument(p, "the clearance is measured against it too")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


#: The arguments ``statics --home --json`` may carry for the fast path (any other option
#: given, such as ``--carrier``, takes the full path).
_FAST_HOME_ARGS = frozenset({"command", "func", "verbose", "quiet", "config", "home", "json"})
#: options whose default leaves the fast path open (their value when not given)
_FAST_HOME_DEFAULTS = {"support": "base"}


def _fast_home(args: argparse.Namespace) -> bool:
    """Answer ``statics --home --json`` without Pinocchio (:mod:`~assembler_pin.statics.home`)
    when no other option is given and the home pose is strictly inside every limit."""
    given = {k: v for k, v in vars(args).items() if k not in _FAST_HOME_ARGS and v and v != _FAST_HOME_DEFAULTS.get(k)}
    if not (args.home and args.json) or given:
        return False
    from ..collision.home import home_clearance
    from ..statics.home import home_anchors, home_state_document

    cfg = config_from_args(args)
    doc = home_state_document(cfg, home_clearance(cfg, *home_anchors(cfg)))
    if doc is not None:
        print(dumps(doc))
    return doc is not None


def run(args: argparse.Namespace) -> int:
    """The forces of the given pose. Exit status 0 when the pose meets every constraint
    (``feasible``: stroke, deflection, forces, the clearance with ``--scene``; on a carrier its
    joints' effort limits too), 1 when it does not (the answer is printed all the same:
    ``feasible: NO`` and the violations)."""
    if _fast_home(args):
        return 0
    from ..model.assembler import AssemblerModel
    from ..state import evaluate_state

    if args.support != "base" and args.carrier is not None:
        raise CLIError("--support ee or both holds the stack at its own plates: give it without --carrier")
    if args.scene and (args.carrier is not None or args.support != "base"):
        raise CLIError("--scene is checked on a fixed base: give it without --carrier or --support ee|both")
    scene = scene_from_args(args)  # read before the model is built: a bad scene is refused at once
    am = AssemblerModel.from_config(config_from_args(args))
    carrier, q = carrier_from_args(args)
    plates = plates_from_args(args, am, "give --plates FILE (or - for stdin) or --home")
    if (carrier is not None or args.support != "base") and args.stiffness:
        raise CLIError(
            "--stiffness is the stiffness of the stack on a fixed base: not with --carrier or --support ee|both"
        )
    if args.support != "base":
        from .support import held_statics

        return held_statics(am, plates, args.support, args.json)
    if carrier is not None:
        from ..carrier import carrier_statics

        statics = carrier_statics(am, carrier, q, plates)
        if args.json:
            print(dumps(statics.state.to_dict() | statics.to_dict()))
            return 0 if statics.within_limits else 1
        print(format_state_table(statics.state, f"Statics of {am.n} platforms on {carrier.name} (world gravity)"))
        print(format_carrier(carrier, statics))
        return 0 if statics.within_limits else 1
    state = evaluate_state(am, plates, scene=scene)
    from .stiffness import stiffness_blocks

    blocks, stiff_ok, stiff_text = stiffness_blocks(am, plates) if args.stiffness else ({}, True, None)
    if args.json:
        print(dumps(state.to_dict() | blocks))
    else:
        print(
            format_state_table(
                state,
                f"Statics of {am.n} platforms, payload {am.config.payload.mass:g} kg at {am.config.payload.offset:g} m",
            )
        )
        if stiff_text is not None:
            print(stiff_text)
    return 0 if stiff_ok and state.feasible else 1
