"""Progress of long work, shown on a terminal only.

Library functions that run for seconds take ``progress: ProgressCallback | None``, a
callable ``(done, total, note)`` they call as work completes; they never print. The CLI
passes a :class:`TerminalProgress`, which writes one self-overwriting line to stderr
when stderr is a terminal and ``--quiet`` was not given, and nothing otherwise (so pipes,
logs and tests see no progress text).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

from ..exceptions import ArgumentError

__all__ = ["ProgressCallback", "TerminalProgress", "checked_progress"]

#: ``(done, total, note)``: ``done`` of ``total`` units finished (``total`` 0 when unknown).
ProgressCallback = Callable[[int, int, str], None]


def checked_progress(progress: ProgressCallback | None) -> ProgressCallback | None:
    """``progress`` when it is None or callable, else :class:`ArgumentError` (a public
    function checks it before any work, not at its first call deep inside)."""
    if progress is not None and not callable(progress):
        raise ArgumentError(f"progress must be a callable (done, total, note) or None, got {type(progress).__name__}")
    return progress


class TerminalProgress:
    """A one-line progress display on stderr: ``label: done/total note [elapsed]``.

    Args:
        label: what is running (``"plan"``).
        enabled: show anything at all; default: only when ``stream`` is a terminal.
        stream: where to write (default ``sys.stderr``).
        min_interval: seconds between redraws.
    """

    def __init__(
        self, label: str, enabled: bool | None = None, stream: TextIO | None = None, min_interval: float = 0.2
    ) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.label = label
        self.enabled = bool(self.stream.isatty()) if enabled is None else enabled
        self.min_interval = min_interval
        self._start = time.perf_counter()
        self._last = -1.0
        self._shown = False

    def __call__(self, done: int, total: int = 0, note: str = "") -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last < self.min_interval and not (total and done >= total):
            return
        self._last = now
        count = f"{done}/{total}" if total else f"{done}"
        line = f"{self.label}: {count} {note}".rstrip() + f" [{now - self._start:.0f} s]"
        self.stream.write("\r" + line[:99].ljust(99))
        self.stream.flush()
        self._shown = True

    def close(self) -> None:
        """End the line (call before printing results)."""
        if self._shown:
            self.stream.write("\r" + " " * 99 + "\r")
            self.stream.flush()
            self._shown = False

    def __enter__(self) -> TerminalProgress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
