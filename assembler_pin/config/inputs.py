"""The one door of every input file the package reads: a configuration, a scene, a model file,
a plate file, footholds, waypoints, a trajectory, a walk's samples, a map's manifest.

A path is checked *before* it is opened: it must be a non-empty str or path naming a regular
file (a directory, a FIFO, a socket or a device such as ``/dev/zero`` is refused, never opened,
so a pipe nobody writes cannot block the read), no larger than the reader's bound. The file is
then opened without blocking and checked again on its descriptor (a file swapped for a pipe in
between is refused too), and at most ``max_bytes + 1`` bytes are read. Every refusal is one
line naming the file as the user gave it.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ..exceptions import short_repr

__all__ = ["checked_input_path", "read_input_bytes", "read_input_text"]

#: Open flags of an input file: read only, never blocking on a FIFO, never a controlling terminal.
_OPEN_FLAGS = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)


def _kind(mode: int) -> str:
    """What a file that is not a regular file is, for the message."""
    for test, name in (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISCHR, "a device"),
        (stat.S_ISBLK, "a device"),
    ):
        if test(mode):
            return name
    return "not a regular file"


def _name(path: object) -> str:
    """A path as a message shows it: printable, at most 160 characters."""
    text = os.fspath(path) if isinstance(path, (str, os.PathLike)) else str(path)
    text = text if isinstance(text, str) and text.isprintable() else repr(text)[1:-1]
    return text if len(text) <= 160 else text[:159] + "…"


def _refuse_kind(mode: int, what: str, shown: str, error: type[Exception]) -> None:
    if not stat.S_ISREG(mode):
        raise error(f"{what} '{shown}' is {_kind(mode)}, not a regular file")


def checked_input_path(path: object, what: str, error: type[Exception], shown: str | None = None) -> Path:
    """``path`` as a :class:`~pathlib.Path` when it names an existing regular file; else
    ``error`` in one line: not a str or path, empty, missing or unreadable, a NUL in it, or not
    a regular file (a directory, a FIFO, a socket, a device). Nothing is opened."""
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)):
        raise error(f"a {what} path must be a str or path, got {short_repr(path, 40)}")
    text = os.fspath(path)
    if not isinstance(text, str):  # a path-like object of bytes
        raise error(f"a {what} path must be a str or path, got {type(path).__name__} of bytes")
    if not text:
        raise error(f"a {what} path must not be empty")
    name = shown if shown is not None else _name(text)
    try:
        info = os.stat(text)
    except (OSError, ValueError) as exc:  # ValueError: a NUL in the path
        raise error(f"cannot read {what} '{name}': {getattr(exc, 'strerror', None) or exc}") from None
    _refuse_kind(info.st_mode, what, name, error)
    return Path(text)


def read_input_bytes(
    path: object,
    what: str,
    error: type[Exception],
    max_bytes: int,
    shown: str | None = None,
    allow_empty: bool = True,
    bound: str = "",
) -> bytes:
    """The bytes of the input file ``path``, through :func:`checked_input_path` first.

    Args:
        what: the kind of file, for the message (``"scene file"``).
        max_bytes: the largest file read (its documented bound) [bytes].
        shown: how the message names the file (default: the path as given).
        allow_empty: whether an empty file is an answer (an empty configuration is the default).
        bound: the row of the limits table that sets ``max_bytes``, named in the message.

    Raises:
        ``error``: one line: see :func:`checked_input_path`; larger than ``max_bytes``; empty
        when not ``allow_empty``.
    """
    target = checked_input_path(path, what, error, shown)
    name = shown if shown is not None else _name(path)
    larger = f"{what} '{name}' is larger than {max_bytes} bytes" + (f" ({bound})" if bound else "")
    try:
        fd = os.open(target, _OPEN_FLAGS)
    except OSError as exc:
        raise error(f"cannot read {what} '{name}': {exc.strerror or exc}") from None
    try:
        info = os.fstat(fd)
        _refuse_kind(info.st_mode, what, name, error)  # swapped for a pipe since the check
        if info.st_size > max_bytes:
            raise error(larger)
        with os.fdopen(fd, "rb", closefd=False) as fh:
            data = fh.read(max_bytes + 1)
    except OSError as exc:
        raise error(f"cannot read {what} '{name}': {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    if len(data) > max_bytes:
        raise error(larger)
    if not data and not allow_empty:
        raise error(f"{what} '{name}' is empty")
    return data


def read_input_text(
    path: object,
    what: str,
    error: type[Exception],
    max_bytes: int,
    shown: str | None = None,
    allow_empty: bool = True,
    bound: str = "",
) -> str:
    """The UTF-8 text of the input file ``path`` (:func:`read_input_bytes`); ``error`` also when
    it is not UTF-8 text."""
    data = read_input_bytes(path, what, error, max_bytes, shown, allow_empty, bound)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        name = shown if shown is not None else _name(path)
        raise error(f"{what} '{name}' is not UTF-8 text") from None
