"""``assembler-pin support``: the stack held at both ends (plate 0 and the EE plate): the
elastic distribution of leg forces for the pose's own lengths and the chosen one (min max|F|)."""

from __future__ import annotations

import argparse

from .common import config_from_args, dumps, plates_from_args
from .paths import path_argument


def add_parser(add) -> None:
    """Register the ``support`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("support", "leg forces with both ends held: the elastic distribution and the chosen (min max|F|) one")
    src = p.add_mutually_exclusive_group()
    src.add_argument(
        "--plates", type=path_argument, metavar="FILE", help='JSON {"plates": [n+1 4x4]} file, or - for stdin'
    )
    src.add_argument("--home", action="store_true", help="use the home pose")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def support_document(am, plates) -> dict:
    """The JSON answer: ``forces`` the elastic distribution of the pose's own lengths, ``chosen``
    the distribution minimizing max|F| with its ``length_offsets``; success when both are."""
    from ..supports.choice import chosen_distribution
    from ..supports.two_point import two_point_statics

    elastic = two_point_statics(am, plates)
    chosen = chosen_distribution(am, plates)
    message = elastic.message if not elastic.success else chosen.message if not chosen.success else "ok"
    return {
        "success": elastic.success and chosen.success,
        "message": message,
        "support": "both",
        "forces": elastic.forces.tolist(),
        "max_abs_force": elastic.max_abs_force,
        "elastic": elastic.to_dict(),
        "chosen": chosen.to_dict(),
    }


def run(args: argparse.Namespace) -> int:
    """Exit 0 with both distributions; 1 when there is none (singular pose, no convergence)."""
    from ..model.assembler import AssemblerModel

    am = AssemblerModel.from_config(config_from_args(args))
    plates = plates_from_args(args, am, "give --plates FILE (or - for stdin) or --home")
    doc = support_document(am, plates)
    print(dumps(doc) if args.json else format_support(doc))
    return 0 if doc["success"] else 1


def held_statics(am, plates, support: str, as_json: bool) -> int:
    """``statics --support ee|both``: print the forces of that support; exit 0 when they are
    feasible (``ee``: every limit; ``both``: both distributions found), else 1."""
    if support == "both":
        doc = support_document(am, plates)
        print(dumps(doc) if as_json else format_support(doc))
        return 0 if doc["success"] else 1
    from ..supports.two_point import ee_held_statics

    held = ee_held_statics(am, plates)
    doc = held.to_dict()
    print(dumps(doc) if as_json else format_ee(held))
    return 0 if held.feasible else 1


def format_ee(held) -> str:
    """The EE-held statics as text (lines ≤ 100 characters)."""
    import numpy as np

    from ..common.labels import platform_label

    verdict = "feasible" if held.feasible else f"{len(held.violations)} violations: {held.violations[0]}"
    lines = [
        "held at the EE plate alone (plate 0 free): leg forces [N], tension positive",
        f"max|F| {held.max_abs_force:.3f} N, {verdict}"[:100],
        f"  EE support force {np.round(held.ee_wrench[:3], 3).tolist()} N",
    ]
    for j, row in enumerate(held.forces):
        lines.append(f"  {platform_label(j)} " + " ".join(f"{x:8.2f}" for x in row))
    return "\n".join(lines)


def format_support(doc: dict) -> str:
    """A compact text report (lines ≤ 100 characters)."""
    import numpy as np

    from ..common.labels import platform_label

    if not doc["success"]:
        return f"support both: {doc['message']}"
    el, ch = doc["elastic"], doc["chosen"]
    lines = [
        "held at plate 0 and at the EE plate (welded): leg forces [N], tension positive",
        f"elastic (the pose's own lengths): max|F| {el['max_abs_force']:.3f} N, residual {el['residual']:.2g} N",
        f"chosen (min max|F|):              max|F| {ch['max_abs_force']:.3f} N, "
        f"largest offset {1e6 * np.abs(ch['length_offsets']).max():.2f} µm",
    ]
    for name, wrench in el["support_wrenches"].items():
        lines.append(f"  {name} support force (elastic) {np.round(wrench[:3], 3).tolist()} N")
    for j, (fe, fc, off) in enumerate(zip(el["forces"], ch["forces"], ch["length_offsets"], strict=True)):
        lines.append(f"  {platform_label(j)} elastic " + " ".join(f"{x:7.2f}" for x in fe))
        lines.append(f"  {platform_label(j)} chosen  " + " ".join(f"{x:7.2f}" for x in fc))
        lines.append(f"  {platform_label(j)} offset  " + " ".join(f"{1e6 * x:7.2f}" for x in off) + " µm")
    return "\n".join(lines)
