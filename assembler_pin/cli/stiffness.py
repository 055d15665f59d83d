"""``assembler-pin stiffness``: the EE's stiffness and sag of a pose, the legs as springs."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from .common import add_goal_arguments, config_from_args, dumps, goal_from_args, plates_from_args

if TYPE_CHECKING:
    from ..ee_stiffness import StiffnessResult
    from ..kinematics import PlateArrays


def add_parser(add) -> None:
    """Register the ``stiffness`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("stiffness", "EE stiffness, compliance and sag under gravity and payload (legs of leg.stiffness N/m)")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--plates", metavar="FILE", help='JSON {"plates": [n+1 4x4]} file, or - for stdin')
    src.add_argument("--home", action="store_true", help="use the home pose")
    add_goal_arguments(src, " (the pose: solve's force optimum for it)")
    p.add_argument(
        "--compensated",
        action="store_true",
        help="command the compensated lengths (the loaded pose is then the given one: no sag)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Exit 0 with the stiffness; 1 when there is none (singular, unstable, no pose for the goal)."""
    from ..ee_stiffness import stiffness
    from ..model import AssemblerModel

    am = AssemblerModel.from_config(config_from_args(args))
    plates: PlateArrays | list
    if args.goal is not None or args.goal_deg is not None:
        from ..solver import solve

        solved = solve(am, goal_from_args(args))
        if not solved.success:
            doc = {"success": False, "message": f"no pose for the goal: {solved.message}"}
            print(dumps(doc) if args.json else f"stiffness: {doc['message']}")
            return 1
        assert solved.optimized is not None  # a successful solve optimizes (the default)
        plates = solved.optimized.plates
    else:
        plates = plates_from_args(args, am, "give --plates FILE (or - for stdin), --home or --goal X Y Z RX RY RZ")
    lengths = None
    if args.compensated:
        from ..compliance import compensated_lengths

        lengths = compensated_lengths(am, plates).lengths
    result = stiffness(am, plates, lengths=lengths)
    if args.json:
        print(dumps(result.to_dict()))
    else:
        print(format_stiffness(result, am))
    return 0 if result.success else 1


def stiffness_blocks(am, plates) -> tuple[dict, bool, str]:
    """The ``sag`` and ``stiffness`` blocks that ``statics --stiffness`` adds to its JSON
    (``stiffness``: the object of ``stiffness --json``; ``sag``: its sag block), whether there
    is a stiffness, and the text report."""
    from ..ee_stiffness import stiffness

    result = stiffness(am, plates)
    doc = result.to_dict()
    return {"sag": doc["sag"], "stiffness": doc}, result.success, format_stiffness(result, am)


def _vec(v) -> str:
    return "(" + ", ".join(f"{round(float(x), 4) + 0.0:.4f}" for x in v) + ")"


def format_stiffness(result: StiffnessResult, am) -> str:
    """A compact text report (lines ≤ 100 characters)."""
    import numpy as np

    from ..labels import platform_label

    cfg = am.config
    lines = [
        f"EE stiffness of {am.n} platforms at the loaded pose (legs {result.leg_stiffness:g} N/m, "
        f"payload {cfg.payload.mass:g} kg at {cfg.payload.offset:g} m)"
    ]
    if not result.success:
        return "\n".join([*lines, f"no stiffness: {result.message}"])
    lines += [
        f"sag: translation {_vec(1e3 * result.sag_translation)} mm, rotation {_vec(1e3 * result.sag_rotation)} mrad",
        f"under a pure force [N/m]:      {'  '.join(f'{x:10.4g}' for x in result.translational_stiffness)}",
        f"under a pure moment [N·m/rad]: {'  '.join(f'{x:10.4g}' for x in result.rotational_stiffness)}",
        f"weakest: {result.weakest_stiffness:.4g} N/m, {result.weakest_name}, along {_vec(result.weakest_direction)}",
        "stiffness [v, ω] at the EE origin, world axes (N/m, N/rad; N·m/m, N·m/rad):",
    ]
    lines += ["  " + " ".join(f"{x:11.4g}" for x in row) for row in result.stiffness]
    scale = np.r_[np.ones(3), np.full(3, 1.0 / cfg.plate.node_radius)]
    part = np.linalg.norm(scale[:, None] * result.geometric * scale) / np.linalg.norm(
        scale[:, None] * result.stiffness * scale
    )
    lines.append(f"load-dependent part: {100 * part:.3g}% of the stiffness (the rest: the legs' springs)")
    shares = [f"{platform_label(j)} {100 * s:.1f}%" for j, s in enumerate(result.platform_share)]
    head = "weakest-direction compliance by platform:"
    row = head
    for cell in shares:
        if len(row) + len(cell) + 2 > 100:
            lines.append(row)
            row = " " * 2
        row += "  " + cell
    lines.append(row)
    return "\n".join(lines)
