"""Output files written atomically: a temporary file beside the target, then ``os.replace``.

A reader never sees a half-written file: a kill, Ctrl-C or a full disk mid-write leaves
either the previous file or none, and never a 0-byte or truncated one. Every file the
package writes goes through :func:`write_atomic` or :func:`atomic_path`.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ..config.bounds import BOUNDS
from ..config.inputs import read_input_text
from ..exceptions import AssemblerError, TrajectoryError

__all__ = ["atomic_path", "read_text_bounded", "strict_json", "write_atomic"]


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path in ``path``'s directory, moved onto ``path`` when the block succeeds.

    For writers that take a file name (``savefig``, ``pyarrow.parquet.write_table``): write to
    the yielded path; on any exception (``KeyboardInterrupt`` included) the temporary file is
    removed and ``path`` is left as it was. An ``OSError`` about the temporary file names
    ``path`` instead.
    """
    target = Path(path)
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as exc:  # named as the caller gave it, never as the temporary file
        raise OSError(exc.errno, exc.strerror, str(target)) from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        os.chmod(tmp, 0o644)
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(exc, OSError) and exc.filename in (tmp_name, tmp):
            raise OSError(exc.errno, exc.strerror, str(target)) from None
        raise


def write_atomic(path: str | os.PathLike[str], data: str | bytes, encoding: str = "utf-8") -> Path:
    """Write ``data`` (text in ``encoding``, or bytes) to ``path`` atomically; returns the path."""
    target = Path(path)
    payload = data.encode(encoding) if isinstance(data, str) else data
    with atomic_path(target) as tmp:
        with tmp.open("wb") as fh:
            fh.write(payload)
            fh.flush()
            os.fsync(fh.fileno())
    return target


def read_text_bounded(path: object, bound_key: str, what: str, error: type[Exception]) -> str:
    """The UTF-8 text of the input file ``path``, read through the one checked door of input
    files (:func:`~assembler_pin.config.inputs.read_input_text`): refused in one line
    (``error``) when ``path`` is not a non-empty str or path, the file is missing or
    unreadable, not a regular file (a FIFO, a directory or a device is refused before it is
    opened), empty, larger than its row ``bound_key`` of the limits table [bytes], or not
    UTF-8. ``what`` names the file in the message (``"trajectory"``, ``"waypoint file"``)."""
    return read_input_text(path, what, error, int(BOUNDS[bound_key].high), allow_empty=False, bound=bound_key)


def strict_json(text: str, error: type[AssemblerError] = TrajectoryError) -> object:
    """JSON without NaN/Infinity constants or duplicate keys; ``error`` (one line) when not."""

    def pairs(items: list[tuple[str, object]]) -> dict:
        keys = [k for k, _ in items]
        if len(set(keys)) != len(keys):
            raise error(f"duplicate key {next(k for k in keys if keys.count(k) > 1)!r}"[:120])
        return dict(items)

    def constant(name: str) -> object:
        raise error(f"{name} is not a number a file may hold")

    try:
        return json.loads(text, object_pairs_hook=pairs, parse_constant=constant)
    except AssemblerError:
        raise
    except json.JSONDecodeError as exc:
        raise error(f"not valid JSON ({exc.msg} at line {exc.lineno} column {exc.colno}): truncated?") from None
    except (RecursionError, ValueError) as exc:  # deep nesting, an integer of thousands of digits
        raise error(f"not a valid file ({type(exc).__name__}: nested too deeply or a number too long)") from None
