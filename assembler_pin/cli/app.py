"""The ``assembler-pin`` command: the parser, and errors turned into exit statuses.

Each subcommand lives in its own module of this package (``add_parser`` + ``run``), whose
heavy imports happen inside ``run``: building the parser imports no numerical library.
"""

from __future__ import annotations

import argparse
import logging
import os
import re
import shutil
import signal
import sys
import traceback
import warnings
from collections.abc import Sequence
from typing import Any, NoReturn

from ..exceptions import AssemblerError, CLIError
from . import bench, export, hexapod, plan, reproduce, simulate, solve, statics, stiffness, support, view, walk
from . import map as map_command  # the module of `assembler-pin map`; the builtin map stays map
from .paths import check_paths_first, path_argument

logger = logging.getLogger("assembler_pin")

#: The subcommands in the order ``--help`` lists them.
SUBCOMMANDS = (
    export,
    statics,
    stiffness,
    support,
    solve,
    reproduce,
    bench,
    plan,
    walk,
    hexapod,
    map_command,
    simulate,
    view,
)


class _Parser(argparse.ArgumentParser):
    """argparse with one-line refusals (a :class:`CLIError`, not a usage dump and exit) and
    negative numbers in scientific notation read as numbers (``--goal -1e-3 ...``)."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?$|^-(?:inf|nan)$", re.I)

    def error(self, message: str) -> NoReturn:
        raise CLIError(f"{message} (see '{self.prog} --help')")

    def format_usage(self) -> str:
        return wrap_usage(super().format_usage())

    def format_help(self) -> str:
        return wrap_usage(super().format_help())


def wrap_usage(text: str, width: int | None = None) -> str:
    """``text`` (a help or usage text) with every usage line longer than ``width`` (argparse's
    own: the terminal's columns - 2) broken before a ``|`` of the group it is in, the rest
    indented under the group's opening bracket: argparse keeps a group of alternatives on one
    line however long it is."""
    width = width or max(shutil.get_terminal_size().columns - 2, 40)
    head, sep, rest = text.partition("\n\n")
    lines: list[str] = []
    for line in head.splitlines():
        while len(line) > width and " | " in line[:width]:
            cut = line.rindex(" | ", 0, width)
            opened: list[int] = []
            for k, c in enumerate(line[:cut]):
                if c in "([":
                    opened.append(k)
                elif c in ")]" and opened:
                    opened.pop()
            indent = opened[0] + 1 if opened else 0
            lines.append(line[:cut])
            line = " " * indent + line[cut + 1 :]
        lines.append(line)
    return "\n".join(lines) + sep + rest


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The ``assembler-pin`` argument parser (one-line refusals, see :class:`_Parser`).

    Args:
        only: build the arguments of this subcommand alone; every other one is listed by
            its name and help (what ``assembler-pin --help`` prints) without its arguments,
            which is most of the parser's cost. None (default): every subcommand complete
            (the CLI reference, the tests).
    """
    parser = _Parser(
        prog="assembler-pin",
        description="Serialized Stewart platforms (the Assembler) on Pinocchio: model, statics, solve.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress to stderr")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress line on a terminal")
    sub = parser.add_subparsers(dest="command", required=True)

    def add(name: str, help_: str) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=help_, description=help_)
        if only is not None and name != only:
            return _UNBUILT  # listed by name and help; its arguments are not built
        p.add_argument("--config", type=path_argument, metavar="FILE", help="YAML configuration (default: built-in)")
        return p

    for module in SUBCOMMANDS:
        module.add_parser(add)
    return parser


class _Unbuilt:
    """What ``add`` gives for a subcommand this run does not use: every parser method a
    subcommand's ``add_parser`` calls (``add_argument``, ``add_argument_group``,
    ``set_defaults``, ...) does nothing and returns it again."""

    def __getattr__(self, name: str) -> Any:
        return self._nothing

    def _nothing(self, *args: object, **kwargs: object) -> _Unbuilt:
        return self


_UNBUILT: Any = _Unbuilt()


def _command_of(argv: Sequence[str]) -> str:
    """The subcommand ``argv`` names (its first word that is not an option; the top-level
    options take no value), or "" when it names none."""
    return next((word for word in argv if not word.startswith("-")), "")


#: Exit statuses of every subcommand: answered and successful, answered "not
#: possible", refused input, a bug (``EX_SOFTWARE``), interrupted by Ctrl-C (128 + SIGINT).
EXIT_OK, EXIT_NOT_POSSIBLE, EXIT_REFUSED, EXIT_BUG, EXIT_INTERRUPTED = 0, 1, 2, 70, 130
#: The reader of the output went away (``… | head``): 128 + SIGPIPE, as a shell command
#: killed by the signal, without a word on stderr.
EXIT_PIPE = 141

#: The top-level options: with only these (or nothing), the command lists its subcommands.
_TOP_FLAGS = frozenset({"-v", "--verbose", "-q", "--quiet"})


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command and return its exit status.

    0: answered and successful; 1: answered, not possible (the answer is still printed);
    2: refused input (one line on stderr); 70: an unexpected error, a bug (one line, the
    traceback only with ``-v``); 130 / 143: interrupted by Ctrl-C / SIGTERM (one line).
    Warnings of the numerical libraries are logged at debug level, never printed.
    """
    from ..common.signals import forget_interrupt, interrupt_on_signals

    command = "assembler-pin"
    restore_signals = interrupt_on_signals(("SIGTERM",))
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _log_warning
            warnings.simplefilter("default")
            words = sys.argv[1:] if argv is None else list(argv)
            parser = build_parser(only=_command_of(words))
            if set(words) <= _TOP_FLAGS:  # no subcommand: what there is to run
                print(parser.format_help(), end="")
                return EXIT_OK
            try:
                args = parser.parse_args(words)
            except CLIError as exc:
                print(f"assembler-pin: error: {_one_line(exc)}", file=sys.stderr)
                return EXIT_REFUSED
            command = f"assembler-pin {args.command}"
            logging.basicConfig(
                level=logging.INFO if args.verbose else logging.WARNING,
                format="%(levelname)s %(name)s: %(message)s",
            )
            return _run(args, command)
    except KeyboardInterrupt as stop:  # Ctrl-C, or SIGTERM through interrupt_on_signals
        logger.debug("interrupted", exc_info=True)
        forget_interrupt()
        signum = getattr(stop, "signum", signal.SIGINT)
        how = "" if signum == signal.SIGINT else f" ({stop})"
        print(f"{command}: interrupted{how}", file=sys.stderr)
        return 128 + int(signum)
    finally:
        restore_signals()


def _run(args: argparse.Namespace, command: str) -> int:
    """``args.func(args)`` with every error but an interrupt turned into one line and a status."""
    try:
        check_paths_first(args)  # before the subcommand's heavy imports and any work
        status = int(args.func(args))
        sys.stdout.flush()  # a closed pipe shows here, not at the interpreter's exit
        return status
    except BrokenPipeError:
        _silence_stdout()
        return EXIT_PIPE
    except AssemblerError as exc:
        print(f"{command}: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_REFUSED
    except OSError as exc:  # an output path that cannot be written
        where = f" '{exc.filename}'" if exc.filename else ""
        print(f"{command}: error: cannot write{where}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_REFUSED
    except Exception as exc:  # anything else is a bug: one line, the traceback only with -v
        if args.verbose:
            traceback.print_exc(file=sys.stderr)
        hint = "" if args.verbose else "; run with -v for the traceback"
        what = f"{type(exc).__name__}: {_one_line(exc)[:300]}"
        print(f"{command}: internal error (a bug, please report it): {what}{hint}", file=sys.stderr)
        return EXIT_BUG


def _silence_stdout() -> None:
    """Point stdout at the null device, so that the interpreter's last flush of the output
    nobody reads any more is not an error printed on stderr."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # stdout is not a file (captured by a test)
        pass
    finally:
        os.close(devnull)


def _log_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: object = None,
    line: str | None = None,
) -> None:
    """``warnings.showwarning`` of the command: a warning is logged at debug level, not printed."""
    logger.debug("%s: %s (%s:%s)", category.__name__, message, filename, lineno)


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())
