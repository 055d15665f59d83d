"""Trajectory files: one format in CSV or JSON, written atomically, read strictly.

A file holds valid rows only (every constraint holds at every row) and says what a reader
needs to refuse a truncated or edited one: its row count and the SHA-256 of its rows.

* JSON: ``{"format": "assembler-pin trajectory", "version": 3, "meta": {...},
  "columns": [...], "rows": [[...], ...]}``.
* CSV: ``# assembler-pin trajectory v3``, then ``# meta: {...}`` (the same meta as one JSON
  line), the column header, one line per row, and a last line ``# end: N rows``.

``meta`` holds ``platforms``, ``rows``, ``sha256`` (of the rows as little-endian float64,
row-major), ``complete`` (false: the plan did not reach the end of the path and the file
holds the valid prefix), ``reason``, ``rate_hz``, ``max_speed`` [m/s], ``max_acceleration``
[m/s²], ``path_kind``, ``base`` (world pose of plate 0, 4×4) and ``waypoint_times`` [s]
(null unless the path's waypoint times were honoured) and ``time_law`` (``quintic`` or
``optimal``, :mod:`.laws`). Columns: ``t`` [s], the 6n leg lengths ``L_sp{j}_leg{i}`` [m],
the EE pose as TAA ``ee_x … ee_rz`` [m, rad], ``max_abs_force`` [N] (statics), the 6n leg
forces with the motion's own part ``F_sp{j}_leg{i}`` [N, tension positive], the smallest
margin of each constraint kind ``margin_*`` (``force`` of the statics, ``force_dynamic`` with
the motion's part) and ``feasible`` (1). Version 3 added ``time_law``, the ``F_*`` columns and
``margin_force_dynamic``; older files are refused with a request to plan again.

:func:`read_trajectory` checks the format (types, names, counts, checksum, finite numbers,
times increasing from 0); :func:`~assembler_pin.motion.rows.check_trajectory` then holds
every row to the model (stroke, speeds, and the EE against stack FK of its lengths).
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..common.files import read_text_bounded, strict_json, write_atomic
from ..common.naming import names
from ..config.bounds import check_bound
from ..config.choices import PATH_KINDS
from ..config.numbers import finite_float
from ..exceptions import AssemblerError, TrajectoryError, short_repr
from ..kinematics import checked_rotations

__all__ = [
    "FORMAT",
    "MARGIN_KINDS",
    "TIME_LAW_NAMES",
    "VERSION",
    "Trajectory",
    "read_trajectory",
    "trajectory_columns",
]

FORMAT = "assembler-pin trajectory"
VERSION = 3
MARGIN_KINDS = ("stroke", "deflection", "rise", "force", "force_dynamic", "path_position", "path_rotation")
TIME_LAW_NAMES = ("quintic", "optimal")
_META_KEYS = {
    "platforms",
    "rows",
    "sha256",
    "complete",
    "reason",
    "rate_hz",
    "max_speed",
    "max_acceleration",
    "path_kind",
    "base",
    "waypoint_times",
    "time_law",
}
_REPLAN = "plan it again with this version ('assembler-pin plan ... --out FILE')"


def trajectory_columns(platforms: int) -> list[str]:
    """Column names of a trajectory file for ``platforms`` Stewart platforms."""
    legs = [names.length_column(j, i) for j in range(platforms) for i in range(6)]
    ee = ["ee_x", "ee_y", "ee_z", "ee_rx", "ee_ry", "ee_rz"]
    forces = [names.force_column(j, i) for j in range(platforms) for i in range(6)]
    return ["t", *legs, *ee, "max_abs_force", *forces, *[f"margin_{k}" for k in MARGIN_KINDS], "feasible"]


@dataclass
class Trajectory:
    """Leg-length commands over time, with what they do.

    Attributes:
        times: (T,) [s], from 0.
        lengths: (T, n, 6) leg lengths [m].
        ee: (T, 6) EE pose as TAA (position [m], rotation vector [rad]), from stack FK.
        max_abs_force: (T,) max|F| of the statics [N].
        margins: per constraint kind (:data:`MARGIN_KINDS`), (T,) the smallest margin over
            the legs: ``stroke`` [m], ``deflection`` [rad], ``rise`` [m], ``force`` [N]
            (limit − |F|, statics), ``force_dynamic`` [N] (the same with the motion's own
            part), ``path_position`` [m] and ``path_rotation`` [rad] (tolerance −
            distance from the planned path); negative means violated.
        feasible: (T,) every constraint holds.
        platforms: n.
        meta: what the file's ``meta`` holds (see the module docstring).
        dynamic_forces: (T, n, 6) leg forces with the motion's own part (static + inertial)
            [N], tension positive (:func:`~assembler_pin.dynamics.inverse_dynamics_from_lengths`);
            None: not computed (such a trajectory cannot be written).
    """

    times: np.ndarray
    lengths: np.ndarray
    ee: np.ndarray
    max_abs_force: np.ndarray
    margins: dict[str, np.ndarray]
    feasible: np.ndarray
    platforms: int
    meta: dict = field(default_factory=dict)
    dynamic_forces: np.ndarray | None = None

    @property
    def max_abs_dynamic_force(self) -> np.ndarray:
        """(T,) max|F| with the motion's own part [N] (NaN when not computed)."""
        if self.dynamic_forces is None:
            return np.full(len(self.times), np.nan)
        return np.abs(self.dynamic_forces).reshape(len(self.times), -1).max(axis=1)

    @property
    def duration(self) -> float:
        return float(self.times[-1])

    @property
    def complete(self) -> bool:
        """The trajectory reaches the end of its path (False: the valid prefix of a failed plan)."""
        return bool(self.meta.get("complete", True))

    def speeds(self) -> np.ndarray:
        """(T-1, n, 6) leg speeds by finite differences [m/s]."""
        return np.diff(self.lengths, axis=0) / np.diff(self.times)[:, None, None]

    def accelerations(self) -> np.ndarray:
        """(T-2, n, 6) leg accelerations by finite differences [m/s²]."""
        v = self.speeds()
        mid = 0.5 * (self.times[1:] + self.times[:-1])
        return np.diff(v, axis=0) / np.diff(mid)[:, None, None]

    def __repr__(self) -> str:
        return (
            f"Trajectory({len(self.times)} samples, {self.duration:.2f} s, peak max|F| "
            f"{self.max_abs_force.max():.2f} N, all feasible: {bool(self.feasible.all())}, "
            f"complete: {self.complete})"
        )

    # ------------------------------------------------------------------ files
    def columns(self) -> list[str]:
        return trajectory_columns(self.platforms)

    def rows(self) -> np.ndarray:
        """(T, columns) the file's rows, in :meth:`columns` order."""
        T = len(self.times)
        margins = np.stack([self.margins[k] for k in MARGIN_KINDS], axis=1)
        dynamic = np.full((T, 6 * self.platforms), np.nan) if self.dynamic_forces is None else self.dynamic_forces
        return np.hstack(
            [
                self.times[:, None],
                self.lengths.reshape(T, -1),
                self.ee,
                self.max_abs_force[:, None],
                dynamic.reshape(T, -1),
                margins,
                self.feasible[:, None].astype(float),
            ]
        )

    def write(self, path: str | os.PathLike[str]) -> Path:
        """Write atomically as CSV (``.csv``) or JSON (any other suffix); units SI, forces in N.

        Raises:
            TrajectoryError: a row is not valid or not finite (files hold valid rows only).
        """
        rows = self.rows()
        if not np.isfinite(rows).all() or not self.feasible.all():
            bad = int(np.argmax(~(np.isfinite(rows).all(axis=1) & self.feasible)))
            raise TrajectoryError(
                f"row {bad} (t = {self.times[bad]:.3f} s) is not valid: a trajectory file holds valid rows only"
            )
        meta = {"complete": True, "reason": "", "waypoint_times": None, **self.meta}
        meta.update(platforms=self.platforms, rows=len(rows), sha256=rows_digest(rows))
        try:  # never write what read_trajectory would refuse
            _check_meta(meta)
        except AssemblerError as exc:
            raise TrajectoryError(f"cannot write this trajectory: {exc}") from None
        path = Path(path)
        if path.suffix.lower() == ".csv":
            buf = io.StringIO()
            buf.write(f"# {FORMAT} v{VERSION}\n# meta: {json.dumps(meta, allow_nan=False)}\n")
            w = csv.writer(buf, lineterminator="\n")
            w.writerow(self.columns())
            w.writerows([repr(float(x)) for x in row] for row in rows)
            buf.write(f"# end: {len(rows)} rows\n")
            return write_atomic(path, buf.getvalue())
        doc = {"format": FORMAT, "version": VERSION, "meta": meta, "columns": self.columns(), "rows": rows.tolist()}
        return write_atomic(path, json.dumps(doc, allow_nan=False))


def rows_digest(rows: np.ndarray) -> str:
    """SHA-256 (hex) of rows as little-endian float64, row-major: the file's checksum."""
    return hashlib.sha256(np.ascontiguousarray(rows, dtype="<f8").tobytes()).hexdigest()


# ---------------------------------------------------------------------- reading
def read_trajectory(path: str | os.PathLike[str]) -> Trajectory:
    """A trajectory file written by :meth:`Trajectory.write` (CSV or JSON by suffix), checked
    as a format: names, types, row count, checksum, finite values, times increasing from 0,
    every row valid. Hold it to a model with :func:`~assembler_pin.motion.rows.check_trajectory`.

    Raises:
        TrajectoryError: one line naming the file and what is wrong with it.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TrajectoryError(f"a trajectory path must be a str or path, got {type(path).__name__}")
    path = Path(path)
    text = read_text_bounded(path, "trajectory.bytes", "trajectory", TrajectoryError)
    try:
        meta, columns, rows = _parse_csv(text) if path.suffix.lower() == ".csv" else _parse_json(text)
        return _trajectory(meta, columns, rows)
    except AssemblerError as exc:
        raise TrajectoryError(f"trajectory '{path}': {exc}") from None


def _parse_json(text: str) -> tuple[dict, list, list]:
    doc = strict_json(text)
    if isinstance(doc, dict) and "format" not in doc and {"columns", "rows"} <= set(doc):
        raise TrajectoryError(f"written by an older version (no row count or checksum): {_REPLAN}")
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise TrajectoryError(f'not a trajectory file (expected a JSON object with "format": "{FORMAT}")')
    if set(doc) != {"format", "version", "meta", "columns", "rows"}:
        raise TrajectoryError("expected exactly the keys format, version, meta, columns, rows")
    if type(doc["version"]) is not int or doc["version"] != VERSION:  # 3.0 is not the integer 3
        raise TrajectoryError(f"format version {short_repr(doc['version'], 30)} is not {VERSION}: {_REPLAN}")
    meta = _check_meta(doc["meta"])
    rows = doc["rows"]
    if not isinstance(rows, list):
        raise TrajectoryError('"rows" must be a list of rows')
    _check_count(len(rows), meta)
    if not all(type(r) is list for r in rows) or not {type(x) for r in rows for x in r} <= {int, float}:
        raise TrajectoryError("every row must be a list of numbers (no strings, booleans or null)")
    return meta, doc["columns"], rows


def _parse_csv(text: str) -> tuple[dict, list, list]:
    lines = text.splitlines()
    if lines and lines[0].startswith(f"# {FORMAT} v") and lines[0] != f"# {FORMAT} v{VERSION}":
        raise TrajectoryError(f"format {short_repr(lines[0][2:], 60)} is not v{VERSION}: {_REPLAN}")
    if lines and lines[0].startswith("t,L_sp"):
        raise TrajectoryError(f"written by an older version (no row count or checksum): {_REPLAN}")
    if not lines or lines[0] != f"# {FORMAT} v{VERSION}":
        raise TrajectoryError(f"not a trajectory file (the first line must be '# {FORMAT} v{VERSION}')")
    if len(lines) < 3 or not lines[1].startswith("# meta: "):
        raise TrajectoryError("truncated: no '# meta:' line and column header")
    meta = _check_meta(strict_json(lines[1][len("# meta: ") :]))
    if not lines[-1].startswith("# end: "):
        raise TrajectoryError("truncated: the last line is not '# end: N rows'")
    if lines[-1] != f"# end: {meta['rows']} rows":
        raise TrajectoryError(f"the end line {short_repr(lines[-1], 60)} does not match the meta's {meta['rows']} rows")
    body = lines[3:-1]
    _check_count(len(body), meta)
    columns = lines[2].split(",")
    try:
        rows = [[float(x) for x in line.split(",")] for line in body]
    except ValueError as exc:
        raise TrajectoryError(f"every row must be numbers: {str(exc)[:80]}") from None
    return meta, columns, rows


def _check_count(count: int, meta: dict) -> None:
    if count != meta["rows"]:
        raise TrajectoryError(f"holds {count} rows, its meta says {meta['rows']}: truncated or edited")


def _is_num(x: object) -> bool:
    """A JSON number a float holds finitely (an integer of 400 digits is not)."""
    return type(x) in (int, float) and finite_float(x) is not None


def _check_meta(meta: object) -> dict:
    """The file's meta with every key of the right type and range, or a TrajectoryError."""
    if not isinstance(meta, dict):
        raise TrajectoryError("meta must be a JSON object")
    if set(meta) != _META_KEYS:
        missing, extra = sorted(_META_KEYS - set(meta)), sorted(set(meta) - _META_KEYS)
        raise TrajectoryError(f"meta keys: missing {missing}, unknown {extra}")
    for key, bound in (("platforms", "config.platforms"), ("rows", "trajectory.rows")):
        check_bound(bound, meta[key], f"meta.{key}", TrajectoryError)
    for key, bound in (
        ("rate_hz", "plan.rate"),
        ("max_speed", "leg.max_speed"),
        ("max_acceleration", "leg.max_acceleration"),
    ):
        check_bound(bound, meta[key], f"meta.{key}", TrajectoryError)
    sha = meta["sha256"]
    if not (isinstance(sha, str) and len(sha) == 64 and all(c in "0123456789abcdef" for c in sha)):
        raise TrajectoryError("meta.sha256 must be 64 lowercase hex digits")
    if type(meta["complete"]) is not bool or not isinstance(meta["reason"], str) or len(meta["reason"]) > 2000:
        raise TrajectoryError("meta.complete must be true or false and meta.reason a string (≤ 2000 characters)")
    if meta["path_kind"] not in PATH_KINDS:
        raise TrajectoryError(f"meta.path_kind must be one of {', '.join(PATH_KINDS)}")
    base = meta["base"]
    if not (
        isinstance(base, list)
        and len(base) == 4
        and all(isinstance(r, list) and len(r) == 4 and all(map(_is_num, r)) for r in base)
    ):
        raise TrajectoryError("meta.base must be a 4x4 matrix of finite numbers (the world pose of plate 0)")
    checked_rotations(np.array([base], dtype=float), "meta.base")
    wt = meta["waypoint_times"]
    if wt is not None and not (isinstance(wt, list) and all(map(_is_num, wt)) and np.isfinite(wt).all()):
        raise TrajectoryError("meta.waypoint_times must be null or a list of finite numbers [s]")
    if meta["time_law"] not in TIME_LAW_NAMES:
        raise TrajectoryError(f"meta.time_law must be one of {', '.join(TIME_LAW_NAMES)}")
    return meta


def _trajectory(meta: dict, columns: object, rows: list) -> Trajectory:
    """The Trajectory of checked meta and rows; names, checksum and values checked here."""
    n = meta["platforms"]
    if columns != trajectory_columns(n):
        raise TrajectoryError(f"the columns are not those of a {n}-platform trajectory (t, L_sp0_leg0, …, feasible)")
    width = len(columns)
    if any(len(r) != width for r in rows):
        k = next(k for k, r in enumerate(rows) if len(r) != width)
        raise TrajectoryError(f"row {k} has {len(rows[k])} values, expected {width}")
    try:
        arr = np.array(rows, dtype=float).reshape(len(rows), width)
    except OverflowError:
        raise TrajectoryError("a number is too large for a float") from None
    if rows_digest(arr) != meta["sha256"]:
        raise TrajectoryError("its rows do not match meta.sha256: the file was edited or damaged")
    if not np.isfinite(arr).all():
        raise TrajectoryError(f"row {int(np.argmax(~np.isfinite(arr).all(axis=1)))} has a NaN or infinite value")
    t = arr[:, 0]
    if t[0] != 0 or not (np.diff(t) > 0).all():
        raise TrajectoryError("times must start at 0 and increase strictly")
    check_bound("trajectory.duration", float(t[-1]), "its duration", TrajectoryError)
    if not (arr[:, -1] == 1.0).all():
        raise TrajectoryError(
            f"row {int(np.argmax(arr[:, -1] != 1.0))} is not marked feasible (1): files hold valid rows only"
        )
    legs = arr[:, 1 : 1 + 6 * n]
    if not (legs > 0).all() or not (arr[:, 7 + 6 * n] >= 0).all():
        raise TrajectoryError("leg lengths must be > 0 and max_abs_force >= 0")
    dynamic = arr[:, 8 + 6 * n : 8 + 12 * n]
    margins = {k: arr[:, 8 + 12 * n + i] for i, k in enumerate(MARGIN_KINDS)}
    negative = np.stack([margins[kind] < 0 for kind in MARGIN_KINDS], axis=1)
    if negative.any():  # a file holds valid rows only: every margin of every row is >= 0
        k, kind = (int(i) for i in np.argwhere(negative)[0])
        raise TrajectoryError(f"row {k} has a negative {MARGIN_KINDS[kind]} margin yet is marked feasible")
    return Trajectory(
        times=t.copy(),
        lengths=legs.reshape(-1, n, 6).copy(),
        ee=arr[:, 1 + 6 * n : 7 + 6 * n].copy(),
        max_abs_force=arr[:, 7 + 6 * n].copy(),
        margins=margins,
        feasible=np.ones(len(t), dtype=bool),
        platforms=n,
        meta=meta,
        dynamic_forces=dynamic.reshape(-1, n, 6).copy(),
    )
