"""``assembler-pin reproduce``: the paper's scenarios."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from ..exceptions import CLIError

if TYPE_CHECKING:
    from collections.abc import Sequence

    from ..model import AssemblerModel
    from ..reproduce import ScenarioOutcome
from .common import add_optimize_arguments, config_from_args, optimize_options, progress_for
from .paths import path_argument, writable_directory


def add_parser(add) -> None:
    """Register the ``reproduce`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("reproduce", "the paper's scenarios: initial vs optimized forces, tables, report with figures")
    p.add_argument("--out", type=path_argument, metavar="DIR", help="write report.md and PNG figures into DIR")
    p.add_argument("--scenario", action="append", metavar="NAME", help="only this scenario (repeatable)")
    p.add_argument(
        "--no-sag",
        action="store_true",
        help="skip the sag-optimal solve of each scenario (its table beside the force-optimal pose)",
    )
    p.add_argument(
        "--markdown",
        action="store_true",
        help="print only the tables and ranges of docs/results.md, in markdown and without the "
        "times (python docs/gen_results.py puts them there); not with --out",
    )
    add_optimize_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """The paper's scenarios, initial vs optimized, with a markdown report and figures.

    Exit 0 when every scenario is solved, 1 when one is not (its row says why); progress
    per scenario on a terminal. The report is written only once every scenario is done.
    """
    from ..config.bounds import check_bound
    from ..model.assembler import AssemblerModel
    from ..reproduce import results_markdown, run_scenarios
    from ..scenarios import SCENARIOS

    names = args.scenario or list(SCENARIOS)
    unknown = [n for n in names if n not in SCENARIOS]
    if unknown:
        raise CLIError(f"unknown scenario {', '.join(unknown)}; valid: {', '.join(SCENARIOS)}")
    if args.max_iterations is not None:
        check_bound("optimize.max_iterations", args.max_iterations, "--max-iterations", CLIError)
    if args.markdown and args.out:
        raise CLIError("--markdown prints the docs' tables, --out writes the report: use one of them")
    if args.out:
        writable_directory(args.out, "--out directory")
    options = optimize_options(args)
    am = AssemblerModel.from_config(config_from_args(args))
    with progress_for(args, "reproduce") as prog:
        outcomes = run_scenarios(am, names, options, progress=prog, sag=not args.no_sag)
    if args.markdown:
        print(results_markdown(am, outcomes))
    else:
        print_tables(am, outcomes, args)
    solved = all(o.result.success and (o.sag_result is None or o.sag_result.success) for o in outcomes)
    return 0 if solved else 1


def print_tables(am: AssemblerModel, outcomes: Sequence[ScenarioOutcome], args: argparse.Namespace) -> None:
    """The text tables of ``reproduce`` (summary, sag, forces) and, with ``--out``, the report."""
    from ..reproduce import force_tables, sag_table, summary_table, write_report

    print(
        f"The paper's scenarios on {am.n} platforms, payload {am.config.payload.mass:g} kg "
        f"at {am.config.payload.offset:g} m (forces in N, tension positive)\n"
    )
    print(summary_table(outcomes))
    if not args.no_sag:
        print(
            "\nForce-optimal and sag-optimal poses: max|F| [N], EE sag under its own load [mm] "
            f"(legs {am.config.leg.stiffness:g} N/m)\n"
        )
        print(sag_table(am, outcomes))
    for outcome in outcomes:
        print()
        print(force_tables(outcome))
    if args.out:
        path = write_report(am, outcomes, args.out)
        print(f"\nwrote report: {path}")
