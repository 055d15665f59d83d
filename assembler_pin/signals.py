"""Stop signals turned into ``KeyboardInterrupt``: one way to unwind for Ctrl-C, ``kill`` and
a closed terminal.

Light on purpose (standard library only): the command line installs it around every
subcommand, and the viewer around its server, without importing anything numerical.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["StopRequested", "forget_interrupt", "interrupt_on_signals"]


class StopRequested(KeyboardInterrupt):
    """A stop signal turned into an interrupt by :func:`interrupt_on_signals`.

    Attributes:
        signum: the signal received (``128 + signum`` is the shell's exit status for it).
    """

    def __init__(self, signum: int) -> None:
        super().__init__(f"stopped by {signal.Signals(signum).name}")
        self.signum = signum


def interrupt_on_signals(names: Sequence[str] = ("SIGTERM", "SIGHUP")) -> Callable[[], None]:
    """Make the named signals raise :class:`StopRequested` (a ``KeyboardInterrupt``), as Ctrl-C does.

    A program then unwinds the same way for ``kill``, a closed terminal and Ctrl-C, running
    its ``finally`` blocks (which stop servers and remove temporary files). Signals this
    platform lacks are skipped; outside the main thread nothing is installed.

    Returns:
        A function restoring the previous handlers.
    """

    def interrupt(signum: int, frame: object) -> None:
        raise StopRequested(signum)

    previous: dict[int, Any] = {}
    if threading.current_thread() is threading.main_thread():
        for name in names:
            sig = getattr(signal, name, None)
            if sig is not None:
                previous[sig] = signal.signal(sig, interrupt)

    def restore() -> None:
        for sig, handler in previous.items():
            signal.signal(sig, handler)

    return restore


def forget_interrupt() -> None:
    """Call after handling a ``KeyboardInterrupt``: keep it from killing the process at exit.

    CPython marks a ``KeyboardInterrupt`` that leaves code run from a string (``exec`` of a
    string, as numpy and scipy do while importing) as unhandled, even when a caller catches
    it; the interpreter then ends by killing itself with SIGINT instead of exiting with the
    status the program chose. Running a string that succeeds clears the mark.
    """
    exec("pass", {})
