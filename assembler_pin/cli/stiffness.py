"""``assembler-pin stiffness``: the EE's stiffness and sag of a pose, the legs as springs."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from .common import add_goal_arguments, add_pose_source, config_from_args, dumps, goal_from_args, plates_from_args
from .paths import path_argument

if TYPE_CHECKING:
    from ..compliance.ee_stiffness import StiffnessResult
    from ..kinematics import PlateArrays


def add_parser(add) -> None:
    """Register the ``stiffness`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("stiffness", "EE stiffness, compliance and sag under gravity and payload (legs of leg.stiffness N/m)")
    src = add_pose_source(p)
    add_goal_arguments(src, " (the pose: solve's force optimum for it)")
    src.add_argument(
        "--scaling",
        action="store_true",
        help="stiffness and sag of the home pose against the number of platforms, n = 1..--max-platforms",
    )
    p.add_argument("--max-platforms", type=int, metavar="N", help="with --scaling: the largest n (64)")
    p.add_argument(
        "--out", type=path_argument, metavar="FILE.png", help="with --scaling: write the log-log figure there"
    )
    p.add_argument(
        "--compensated",
        action="store_true",
        help="command the compensated lengths (the loaded pose is then the given one: no sag)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Exit 0 with the stiffness; 1 when there is none (singular, unstable, no pose for the goal)."""
    from ..compliance.ee_stiffness import stiffness
    from ..exceptions import CLIError
    from ..model.assembler import AssemblerModel

    if args.scaling:
        if args.compensated:
            raise CLIError("--compensated has no effect with --scaling (the home poses are rigid): drop one of them")
        return _run_scaling(args)
    if args.out is not None:
        raise CLIError("--out writes the figure of --scaling: give --scaling too")
    if args.max_platforms is not None:
        raise CLIError("--max-platforms sets the largest n of --scaling: give --scaling too, or drop it")
    am = AssemblerModel.from_config(config_from_args(args))
    plates: PlateArrays | list
    if args.goal is not None or args.goal_deg is not None:
        from ..solver.pipeline import solve

        solved = solve(am, goal_from_args(args))
        if not solved.success:
            doc = {"success": False, "message": f"no pose for the goal: {solved.message}"}
            print(dumps(doc) if args.json else f"stiffness: {doc['message']}")
            return 1
        assert solved.optimized is not None  # a successful solve optimizes (the default)
        plates = solved.optimized.plates
    else:
        plates = plates_from_args(
            args, am, "give --plates FILE (or - for stdin), --home, --goal X Y Z RX RY RZ or --scaling"
        )
    lengths = None
    if args.compensated:
        from ..compliance.loaded import compensated_lengths

        lengths = compensated_lengths(am, plates).lengths
    result = stiffness(am, plates, lengths=lengths)
    if args.json:
        print(dumps(result.to_dict()))
    else:
        print(format_stiffness(result, am))
    return 0 if result.success else 1


def _run_scaling(args: argparse.Namespace) -> int:
    """``--scaling``: the table (text or JSON) and, with ``--out``, the figure; exit 0."""
    from ..compliance.scaling import scaling_figure, stiffness_scaling
    from ..config.bounds import check_bound
    from ..exceptions import CLIError
    from .common import progress_for

    top = 64 if args.max_platforms is None else args.max_platforms
    top = int(check_bound("config.platforms", top, "--max-platforms", CLIError))
    if args.out is not None and not str(args.out).lower().endswith(".png"):
        raise CLIError(f"--out must name a .png file, got {args.out!r}")
    if args.out is not None:
        from .paths import writable_parent

        writable_parent(args.out, "--out file")
    cfg = config_from_args(args)
    prog = progress_for(args, "scaling")
    table = stiffness_scaling(cfg, top, progress=prog)
    doc = table.to_dict()
    if args.out is not None:
        from ..common.files import atomic_path

        fig = scaling_figure(table)
        with atomic_path(args.out) as tmp:
            fig.savefig(tmp, dpi=150, format="png")
        doc["out"] = str(args.out)
    prog.close()
    print(dumps(doc) if args.json else format_scaling(table, doc.get("out")))
    return 0


def format_scaling(table, out: str | None) -> str:
    """The text table of ``--scaling``: n = 1, 2, 4, ... and the last n (lines ≤ 100 characters)."""
    ns = table.platforms
    show = sorted({int(n) for n in ns if n & (n - 1) == 0} | {int(ns[-1])})
    if table.first_unstable is not None:
        show = sorted(set(show) | {table.first_unstable - 1, table.first_unstable} - {0})
    lines = [
        f"EE stiffness and sag of the home pose against the platforms (legs {table.leg_stiffness:g} N/m)",
        f"{'n':>3} {'lateral N/m':>12} {'axial N/m':>12} {'torsion N·m/rad':>16} {'sag mm':>9}  springs alone: lateral",
    ]
    for n in show:
        i = n - 1
        if table.stable[i]:
            stiff = f"{table.lateral[i]:>12.4g} {table.axial[i]:>12.4g} {table.torsional[i]:>16.4g}"
            row = f"{stiff} {1e3 * table.sag[i]:>9.4g}"
        else:
            row = f"{'buckles':>12} {'—':>12} {'—':>16} {'—':>9}"
        lines.append(f"{n:>3} {row}  {table.elastic['lateral'][i]:.4g}")
    if table.first_unstable is not None:
        lines.append(f"the loaded stack buckles under its own weight from n = {table.first_unstable}")
    if out is not None:
        lines.append(f"figure: {out}")
    return "\n".join(lines)


def stiffness_blocks(am, plates) -> tuple[dict, bool, str]:
    """The ``sag`` and ``stiffness`` blocks that ``statics --stiffness`` adds to its JSON
    (``stiffness``: the object of ``stiffness --json``; ``sag``: its sag block), whether there
    is a stiffness, and the text report."""
    from ..compliance.ee_stiffness import stiffness

    result = stiffness(am, plates)
    doc = result.to_dict()
    return {"sag": doc["sag"], "stiffness": doc}, result.success, format_stiffness(result, am)


def _vec(v) -> str:
    return "(" + ", ".join(f"{round(float(x), 4) + 0.0:.4f}" for x in v) + ")"


def format_stiffness(result: StiffnessResult, am) -> str:
    """A compact text report (lines ≤ 100 characters)."""
    import numpy as np

    from ..common.labels import platform_label

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
