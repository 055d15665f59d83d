"""The ``assembler-pin`` command: the parser, and errors turned into exit statuses.

Each subcommand lives in its own module of this package (``add_parser`` + ``run``), whose
heavy imports happen inside ``run``: building the parser imports no numerical library.
"""

from __future__ import annotations

import argparse
import logging
import re
import sys
from collections.abc import Sequence
from typing import NoReturn

from ..exceptions import AssemblerError, CLIError
from . import bench, export, map, plan, reproduce, simulate, solve, statics, stiffness, support, view

logger = logging.getLogger("assembler_pin")

#: The subcommands in the order ``--help`` lists them.
SUBCOMMANDS = (export, statics, stiffness, support, solve, reproduce, bench, plan, map, simulate, view)


class _Parser(argparse.ArgumentParser):
    """argparse with one-line refusals (a :class:`CLIError`, not a usage dump and exit) and
    negative numbers in scientific notation read as numbers (``--goal -1e-3 ...``)."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?$|^-(?:inf|nan)$", re.I)

    def error(self, message: str) -> NoReturn:
        raise CLIError(f"{message} (see '{self.prog} --help')")


def build_parser() -> argparse.ArgumentParser:
    """The ``assembler-pin`` argument parser (one-line refusals, see :class:`_Parser`)."""
    parser = _Parser(
        prog="assembler-pin",
        description="Serialized Stewart platforms (the Assembler) on Pinocchio: model, statics, solve.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress to stderr")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress line on a terminal")
    sub = parser.add_subparsers(dest="command", required=True)

    def add(name: str, help_: str) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=help_, description=help_)
        p.add_argument("--config", metavar="FILE", help="YAML configuration (default: built-in)")
        return p

    for module in SUBCOMMANDS:
        module.add_parser(add)
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
