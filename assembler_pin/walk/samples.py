"""The walk's samples file ``walk.csv`` (``walk --out DIR``): written here, read back strictly.

One header line, then one row per sample of every phase in order::

    sample,phase,kind,support,foothold,max_abs_force,L_sp0_leg0,...,L_sp{n-1}_leg5

``sample`` counts the rows from 0; ``phase`` the phases from 0 (consecutive rows of a phase
share it, and it grows by one from phase to phase); ``kind`` is ``reach``, ``transfer`` or
``swing`` in the walk's order (reach, transfer, swing, transfer, reach ...); ``support`` the
plates held in that kind (``base``, ``both``, ``ee``: names of
:data:`~assembler_pin.supports.two_point.SUPPORTS`); ``foothold`` the foothold the phase goes to
(phase p: p // 2 + 1); ``max_abs_force`` the sample's max|F| [N] with that support; then the
commanded lengths [m] of the legs (columns of :meth:`~assembler_pin.common.naming.names.length_column`).
The file ends with a newline. The reader refuses anything else in one line
(:class:`~assembler_pin.exceptions.WalkError`): a truncated file, an unknown phase kind, a
support not in ``SUPPORTS`` or not the one of its kind, a NaN or non-positive length, ...
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..common.files import read_text_bounded
from ..common.naming import names
from ..config.bounds import check_bound
from ..exceptions import WalkError
from ..supports.two_point import SUPPORTS

__all__ = ["PHASE_SUPPORT", "SAMPLE_COLUMNS", "WalkSamples", "parse_walk_csv", "read_walk_csv", "walk_csv", "walk_rows"]

#: The support held in each kind of phase.
PHASE_SUPPORT = {"reach": "base", "transfer": "both", "swing": "ee"}
#: The columns before the commanded lengths.
SAMPLE_COLUMNS = ("sample", "phase", "kind", "support", "foothold", "max_abs_force")
#: Longest commanded length accepted [m] (the stroke of any real leg is far below it).
MAX_LENGTH = 100.0

_INT = re.compile(r"\d{1,9}", re.ASCII)  # ASCII digits only: float() reads '١٢' as 12
_REAL = re.compile(r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d{1,3})?", re.ASCII)


@dataclass(frozen=True)
class WalkSamples:
    """The rows of a walk's samples file, in order.

    Attributes:
        phase, foothold: (m,) phase index and foothold of each sample.
        kind, support: each sample's phase kind and support.
        max_abs_force: (m,) max|F| [N]; commanded: (m, n, 6) commanded lengths [m].
    """

    phase: np.ndarray
    kind: tuple[str, ...]
    support: tuple[str, ...]
    foothold: np.ndarray
    max_abs_force: np.ndarray
    commanded: np.ndarray

    def __len__(self) -> int:
        return len(self.kind)

    def __repr__(self) -> str:
        kinds = [k for i, k in enumerate(self.kind) if i == 0 or self.phase[i] != self.phase[i - 1]]
        peak = f"{float(self.max_abs_force.max()):.2f} N" if len(self) else "-"
        return (
            f"WalkSamples({len(self)} samples, {len(kinds)} phases ({', '.join(kinds)}), "
            f"peak max|F| {peak}, {self.commanded.shape[1]} platforms)"
        )


def walk_rows(am, walk) -> tuple[list[str], list[list[object]]]:
    """The CSV header and rows of a :class:`~assembler_pin.walk.WalkResult`: one row per sample,
    its phase, support, max|F| [N] and the commanded lengths [m] (module doc)."""
    header = [*SAMPLE_COLUMNS] + [names.length_column(j, i) for j in range(am.n) for i in range(6)]
    rows, count = [], 0
    for k, phase in enumerate(walk.phases):
        for i in range(len(phase.plates)):
            peak = float(abs(phase.forces[i]).max())
            rows.append([count, k, phase.kind, phase.support, phase.step, f"{peak:.6f}"])
            rows[-1] += [f"{x:.9f}" for x in phase.commanded[i].ravel()]
            count += 1
    return header, rows


def walk_csv(am, walk) -> str:
    """The text of a walk's samples file (module doc)."""
    header, rows = walk_rows(am, walk)
    return "\n".join([",".join(header)] + [",".join(str(x) for x in r) for r in rows]) + "\n"


def _header(line: str, n: int | None) -> int:
    """The number of platforms the header names (checked against ``n`` when given)."""
    cols = line.split(",")
    if tuple(cols[:6]) != SAMPLE_COLUMNS:
        raise WalkError(f"not a walk samples file: the header must start {','.join(SAMPLE_COLUMNS)}")
    count = len(cols) - 6
    if count < 6 or count % 6:
        raise WalkError(f"the header has {count} length columns; a stack of n platforms has 6 n")
    platforms = count // 6
    check_bound("config.platforms", platforms, "the platforms of the header", error=WalkError)
    want = [names.length_column(j, i) for j in range(platforms) for i in range(6)]
    if cols[6:] != want:
        bad = next(c for c, w in zip(cols[6:], want, strict=True) if c != w)
        raise WalkError(f"header column {bad[:30]!r} is not the length column expected there")
    if n is not None and platforms != n:
        raise WalkError(f"the file holds a stack of {platforms} platforms, the model has {n}")
    return platforms


def _number(text: str, what: str, pattern: re.Pattern) -> float:
    if not pattern.fullmatch(text):
        kind = "a non-negative integer" if pattern is _INT else "a finite decimal number"
        raise WalkError(f"{what} must be {kind}, got {text[:30]!r}")
    value = float(text)
    if not math.isfinite(value):
        raise WalkError(f"{what} must be finite, got {text[:30]!r}")
    return value


def _phase_fields(where: str, fields: list[str], previous: tuple | None) -> tuple[int, str, str, int]:
    """(phase, kind, support, foothold) of a row, each checked against the walk's order."""
    phase = int(_number(fields[1], f"{where} phase", _INT))
    kind, support = fields[2], fields[3]
    if kind not in PHASE_SUPPORT:
        raise WalkError(f"{where}: unknown phase {kind[:30]!r} (allowed: {', '.join(PHASE_SUPPORT)})")
    if support not in SUPPORTS:
        raise WalkError(f"{where}: support {support[:30]!r} is not one of {', '.join(SUPPORTS)}")
    if support != PHASE_SUPPORT[kind]:
        raise WalkError(f"{where}: a {kind} is held at {PHASE_SUPPORT[kind]!r}, not {support!r}")
    foothold = int(_number(fields[4], f"{where} foothold", _INT))
    first = 0 if previous is None else previous[0]
    if phase not in (first, first + 1) or (previous is None and phase != 0):
        raise WalkError(f"{where}: phase {phase} after phase {'none' if previous is None else first}")
    want = "transfer" if phase % 2 else ("reach" if phase % 4 == 0 else "swing")
    if kind != want or foothold != phase // 2 + 1:
        raise WalkError(
            f"{where}: phase {phase} is the {want} to foothold {phase // 2 + 1}, not a {kind} to {foothold}"
        )
    return phase, kind, support, foothold


def parse_walk_csv(text: str, n: int | None = None) -> WalkSamples:
    """The :class:`WalkSamples` of a samples file's text (module doc); ``n``: the platforms the
    file must hold (default: as its header says).

    Raises:
        WalkError: anything but the format, in one line naming the row and the column.
    """
    if not isinstance(text, str):
        raise WalkError(f"the samples file's text must be a str, got {type(text).__name__}")
    if not text.endswith("\n"):
        raise WalkError("the samples file is truncated: its last line has no end")
    lines = text[:-1].split("\n")
    platforms = _header(lines[0], n)
    width = 6 + 6 * platforms
    rows: list[tuple[int, str, str, int]] = []
    peaks, lengths = np.zeros(len(lines) - 1), np.zeros((len(lines) - 1, 6 * platforms))
    for k, line in enumerate(lines[1:]):
        where = f"row {k} (line {k + 2})"
        fields = line.split(",")
        if len(fields) != width:
            raise WalkError(f"{where} has {len(fields)} fields, the header {width}: truncated or malformed")
        if int(_number(fields[0], f"{where} sample", _INT)) != k:
            raise WalkError(f"{where}: sample {fields[0][:12]!r}, expected {k} (rows count from 0)")
        rows.append(_phase_fields(where, fields, rows[-1] if rows else None))
        peaks[k] = _number(fields[5], f"{where} max_abs_force", _REAL)
        if peaks[k] < 0:
            raise WalkError(f"{where}: max_abs_force {fields[5][:20]} is negative")
        for c, field in enumerate(fields[6:]):
            value = _number(field, f"{where} {names.length_column(c // 6, c % 6)}", _REAL)
            if not 0.0 < value <= MAX_LENGTH:
                raise WalkError(
                    f"{where}: length {field[:20]} m of {names.length_column(c // 6, c % 6)} is not in (0, 100]"
                )
            lengths[k, c] = value
    return WalkSamples(
        np.array([r[0] for r in rows], dtype=int),
        tuple(r[1] for r in rows),
        tuple(r[2] for r in rows),
        np.array([r[3] for r in rows], dtype=int),
        peaks,
        lengths.reshape(-1, platforms, 6),
    )


def read_walk_csv(path: str | Path, n: int | None = None) -> WalkSamples:
    """Read a walk's samples file (:func:`parse_walk_csv`), at most the ``trajectory.bytes``
    row of the limits table.

    Raises:
        WalkError: unreadable, empty, too large, not UTF-8, or not the format (one line).
    """
    return parse_walk_csv(read_text_bounded(path, "trajectory.bytes", "walk samples file", WalkError), n)
