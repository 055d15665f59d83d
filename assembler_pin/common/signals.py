"""Stop signals turned into ``KeyboardInterrupt``: one way to unwind for Ctrl-C, ``kill`` and
a closed terminal.

Light on purpose (standard library only): the command line installs it around every
subcommand, and the viewer around its server, without importing anything numerical.
"""

from __future__ import annotations

import _thread
import signal
import sys
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

    An interrupt that lands while a finalizer runs (a ``__del__`` or a weakref callback, run
    by the garbage collector at any point) cannot leave it: Python would print it as an
    ignored exception, with a traceback, and go on working. The hook installed here
    (:class:`_Redelivery`) raises the same signal again instead, :data:`REDELIVERY_DELAY`
    later, so the program's own code is interrupted and unwinds as for any Ctrl-C.

    Returns:
        A function restoring the previous handlers (and the previous unraisable hook).
    """

    def interrupt(signum: int, frame: object) -> None:
        raise StopRequested(signum)

    previous: dict[int, Any] = {}
    previous_hook = sys.unraisablehook
    hook: _Redelivery | None = None
    if threading.current_thread() is threading.main_thread():
        for name in names:
            sig = getattr(signal, name, None)
            if sig is not None:
                previous[sig] = signal.signal(sig, interrupt)
        sys.unraisablehook = hook = _Redelivery(previous_hook)

    def restore() -> None:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if hook is not None:
            sys.unraisablehook = previous_hook
            hook.active = False  # a redelivery still pending is dropped: the program has unwound

    return restore


#: How long after a finalizer's interrupt it is raised again in the main thread [s].
REDELIVERY_DELAY = 0.01


class _Redelivery:
    """An unraisable hook that raises an interrupt caught in a finalizer again as its signal
    (SIGINT for Ctrl-C, the :class:`StopRequested`'s own otherwise), while ``active``; every
    other unraisable exception goes to ``fallback``."""

    def __init__(self, fallback: Callable[[Any], object]) -> None:
        self.fallback, self.active = fallback, True

    def __call__(self, unraisable: Any) -> None:
        exc = unraisable.exc_value
        if not isinstance(exc, KeyboardInterrupt):
            self.fallback(unraisable)
            return
        # from a thread, after the hook has returned: raised in the hook, it would be ignored again
        later = threading.Timer(REDELIVERY_DELAY, self._interrupt, (getattr(exc, "signum", signal.SIGINT),))
        later.daemon = True
        later.start()

    def _interrupt(self, signum: int) -> None:
        if self.active:
            _thread.interrupt_main(signal.Signals(signum))


def forget_interrupt() -> None:
    """Call after handling a ``KeyboardInterrupt``: keep it from killing the process at exit.

    CPython marks a ``KeyboardInterrupt`` that leaves code run from a string (``exec`` of a
    string, as numpy and scipy do while importing) as unhandled, even when a caller catches
    it; the interpreter then ends by killing itself with SIGINT instead of exiting with the
    status the program chose. Running a string that succeeds clears the mark.
    """
    exec("pass", {})
