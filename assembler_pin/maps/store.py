"""A map directory on disk: its manifest, its Parquet parts, and the strict reader of both.

A map directory holds one map: ``map.json`` (the manifest: the grid's, every configuration's,
the solver settings' and the scene's hashes) and one ``part-*.parquet`` file per finished batch, each row
carrying the ``key`` of what it was computed from (:func:`~.cells.cell_key`). Every file is
written atomically (:func:`~assembler_pin.common.files.atomic_path`): a part is whole or absent.
A directory that holds another map, a part that cannot be read, has another schema, repeats
a cell or holds a row computed from anything else is refused with one line
(:class:`~assembler_pin.exceptions.MapError`); its rows are never mixed into an answer.

Each part carries the SHA-256 of its rows in its Parquet metadata (:data:`CHECKSUM_KEY`),
verified whenever it is read: a part edited after it was written is refused, and so is a row
whose clearance or pose columns hold what a cell never records (NaN, a clearance below
:data:`MIN_CLEARANCE`, other than two body names, a pose of another length). The manifest is
read only when it is a regular file of at most ``map.manifest_bytes`` (never a pipe or a
device read whole).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
from pathlib import Path

from ..common.files import atomic_path, write_atomic
from ..config.bounds import BOUNDS
from ..config.inputs import read_input_bytes
from ..exceptions import AssemblerError, MapError
from .cells import COLUMNS
from .grid import Grid

__all__ = [
    "MANIFEST",
    "check_manifest",
    "grid_hash",
    "manifest_for",
    "read_manifest",
    "read_parts",
    "rows_checksum",
    "write_part",
]

MANIFEST = "map.json"
"""The manifest's file name in a map directory."""
FORMAT = "assembler_pin map"
VERSION = 5  # 3: sag and weakest stiffness; 4: parts carry a checksum; 5: clearance, pose, scene
MIN_CLEARANCE = -1.0
"""The smallest clearance a row may hold [m]: bodies overlapping by more are not a pose."""
MAX_BODY_NAME = 80
"""The longest body name a row's ``clearance_between`` may hold [characters]."""
CHECKSUM_KEY = b"assembler_pin.sha256"
"""The key of a part's checksum in its Parquet schema metadata."""
_HOW = "use another --out directory, or delete this one to start afresh"


def need_pyarrow():
    """(pyarrow, pyarrow.parquet), or an AssemblerError saying how to install them."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise AssemblerError("maps need pyarrow: pip install 'assembler_pin[maps]'") from None
    return pa, pq


def schema():
    """The Arrow schema of a map part (the columns of :data:`~.cells.COLUMNS`)."""
    pa, _ = need_pyarrow()
    types = {c: pa.string() for c in ("config", "reason", "capacity_binding", "binding", "key")}
    types |= {c: pa.int64() for c in ("cell", "ix", "iy", "iz", "io")}
    types["reachable"] = pa.bool_()
    types["clearance_between"] = pa.list_(pa.string())
    types["plates_xyzquat"] = pa.list_(pa.float64())
    return pa.schema([(c, types.get(c, pa.float64())) for c in COLUMNS])


def grid_hash(grid: Grid) -> str:
    """A stable hash of a grid's axis values [m] and orientations [rad], exactly."""
    doc = [[v.hex() for v in getattr(grid, a)] for a in ("x", "y", "z")]
    doc.append([[v.hex() for v in r] for r in grid.orientations])
    return hashlib.sha256(json.dumps(doc).encode()).hexdigest()


def manifest_for(grid: Grid, configs: dict[str, str], solver: str, scene: str | None = None) -> dict:
    """The manifest of a map: ``configs`` maps each configuration's name to its hash;
    ``scene`` is the scene's hash (:func:`~.cells.scene_hash`), None for a map without one."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "shape": list(grid.shape),
        "grid": grid_hash(grid),
        "configs": dict(sorted(configs.items())),
        "solver": solver,
        "scene": scene,
    }


def _read_manifest(path: Path) -> dict:
    """The manifest at ``path``, read only when it is a regular file of bounded size.

    Raises:
        MapError: not a regular file, too large, not JSON, or not a map manifest.
    """
    limit = int(BOUNDS["map.manifest_bytes"].high)
    try:  # the one door of input files: a FIFO or a device is refused before it is opened
        data = read_input_bytes(path, "the map manifest", MapError, limit, str(path), bound="map.manifest_bytes")
    except MapError as exc:
        raise MapError(f"{exc}: {_HOW}") from None
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise MapError(f"the map manifest {path} cannot be read as JSON: {_HOW}") from None
    keys = {"format", "version", "shape", "grid", "configs", "solver", "scene"}
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise MapError(f"{path} is not an assembler_pin map manifest: {_HOW}")
    if doc.get("version") != VERSION and isinstance(doc.get("version"), int):
        return doc  # another version: named by the caller, whatever its keys
    if set(doc) != keys:
        raise MapError(f"{path} is not an assembler_pin map manifest: {_HOW}")
    return doc


def read_manifest(out: Path) -> dict:
    """The manifest of the map directory ``out``, checked as a reader sees it: present,
    of this :data:`VERSION`, its configuration names texts.

    Raises:
        MapError: naming what is wrong.
    """
    path = out / MANIFEST
    if not os.path.lexists(path):
        raise MapError(f"the map directory {out} holds parts without a manifest ({MANIFEST}): {_HOW}")
    doc = _read_manifest(path)
    if doc["version"] != VERSION:
        raise MapError(
            f"{path} is a map of version {doc['version']!r:.20}, this package reads version {VERSION}: {_HOW}"
        )
    configs, shape = doc["configs"], doc["shape"]
    if not (isinstance(configs, dict) and configs and all(isinstance(v, str) for v in configs.values())):
        raise MapError(f"{path} is not an assembler_pin map manifest (configs): {_HOW}")
    if not (isinstance(shape, list) and shape and all(type(v) is int and v > 0 for v in shape)):
        raise MapError(f"{path} is not an assembler_pin map manifest (shape): {_HOW}")
    scene = doc["scene"]
    if not (scene is None or (isinstance(scene, str) and len(scene) == 64 and scene.isalnum())):
        raise MapError(f"{path} is not an assembler_pin map manifest (scene): {_HOW}")
    return doc


def check_manifest(out: Path, wanted: dict) -> None:
    """Write ``wanted`` as the manifest of a new map directory, or check that ``out`` holds this
    same map; a directory holding another map, or parts without a manifest, is refused."""
    path = out / MANIFEST
    if not os.path.lexists(path):
        if any(out.glob("part-*.parquet")):
            raise MapError(f"the map directory {out} holds parts without a manifest ({MANIFEST}): {_HOW}")
        write_atomic(path, json.dumps(wanted, indent=1) + "\n")
        return
    have = _read_manifest(path)
    if have == wanted:
        return
    named = (("version", "version"), ("grid", "grid"), ("solver settings", "solver"), ("scene", "scene"))
    differs = [what for what, key in named if have.get(key) != wanted[key]]
    old, new = have.get("configs"), wanted["configs"]
    if not isinstance(old, dict) or set(old) != set(new):
        differs.append("configuration names")
    else:
        differs += [f"configuration {name!r} content" for name in new if old[name] != new[name]]
    raise MapError(f"the map directory {out} holds another map (its {', '.join(differs) or 'manifest'} differ): {_HOW}")


def rows_checksum(table) -> str:
    """The SHA-256 of a part's rows: every column's values in order, floats exactly (their
    ``repr``), whatever the Parquet encoding."""
    h = hashlib.sha256()
    for name in table.schema.names:
        h.update(name.encode())
        h.update(json.dumps(table.column(name).to_pylist(), allow_nan=True).encode())
    return h.hexdigest()


def _bad_part(path: Path, why: str) -> MapError:
    return MapError(f"map part {path} {why}: delete it (its cells are recomputed on the next run)")


def _read_part(path: Path, pa, pq):
    try:
        table = pq.read_table(path)
    except (OSError, pa.ArrowException, ValueError) as exc:
        text = " ".join(str(exc).split())
        raise _bad_part(path, f"is not a readable Parquet file ({text[:80] or type(exc).__name__})") from None
    want = schema()
    if table.schema.names != want.names:
        missing = [c for c in want.names if c not in table.schema.names]
        extra = [c for c in table.schema.names if c not in want.names]
        why = f"missing {missing[:3]}" if missing else f"extra {extra[:3]}" if extra else "in another order"
        raise _bad_part(path, f"has other columns than a map part ({why})")
    for field in want:
        if table.schema.field(field.name).type != field.type:
            got = table.schema.field(field.name).type
            raise _bad_part(path, f"has column {field.name!r} of type {got}, not {field.type}")
    if table.num_rows == 0:
        raise _bad_part(path, "holds no rows")
    stored = (table.schema.metadata or {}).get(CHECKSUM_KEY)
    if stored is None:
        raise _bad_part(path, "carries no checksum of its rows")
    if stored.decode("ascii", "replace") != rows_checksum(table):
        raise _bad_part(path, "does not match its checksum (its rows were changed after it was written)")
    if table.column("config").null_count or table.column("cell").null_count or table.column("key").null_count:
        raise _bad_part(path, "holds rows without config, cell or key")
    _check_pose_columns(path, table)
    return table


def _pose_problem(reachable: object, distance: object, between: object, plates: object) -> str:
    """What is wrong with a row's reachability, clearance and pose columns ("" when nothing)."""
    if not isinstance(reachable, bool):
        return "no reachable value"
    if distance is not None and not (isinstance(distance, float) and math.isfinite(distance)):
        return f"clearance_m {distance!r:.20} (a finite number, or null without a pose)"
    if distance is not None and distance < MIN_CLEARANCE:
        return f"clearance_m {distance:.6g} m, below {MIN_CLEARANCE:g} m"
    if not isinstance(between, list):
        return "no clearance_between list"
    want = 0 if distance is None else 2
    if len(between) != want:
        return f"{len(between)} clearance_between names, not {want} (two bodies with a clearance, none without)"
    for name in between:
        if not (isinstance(name, str) and name.strip() and len(name) <= MAX_BODY_NAME and name.isprintable()):
            return f"clearance_between name {name!r:.40} (1 to {MAX_BODY_NAME} printable characters)"
    if not isinstance(plates, list):
        return "no plates_xyzquat list"
    if not reachable:
        return "" if not plates and distance is None else "a pose or a clearance, not being reachable"
    if len(plates) < 14 or len(plates) % 7:
        return f"{len(plates)} plates_xyzquat numbers, not 7 per plate of two or more plates"
    if not all(isinstance(v, float) and math.isfinite(v) for v in plates):
        return "plates_xyzquat numbers that are not finite"
    quats = (plates[k + 3 : k + 7] for k in range(0, len(plates), 7))
    if any(abs(math.sqrt(sum(q * q for q in quat)) - 1.0) > 1e-6 for quat in quats):
        return "plates_xyzquat quaternions that are not of unit norm"
    return ""


def _check_pose_columns(path: Path, table) -> None:
    """Refuse a row whose clearance or pose columns hold what a cell never records."""
    names = ("cell", "reachable", "clearance_m", "clearance_between", "plates_xyzquat")
    for cell, *values in zip(*(table.column(c).to_pylist() for c in names), strict=True):
        why = _pose_problem(*values)
        if why:
            raise _bad_part(path, f"holds cell {cell} with {why}")


def read_parts(out: Path) -> list:
    """Every part of ``out`` read strictly: (path, ``pyarrow.Table``) pairs in name order.

    Raises:
        MapError: naming the first part that cannot be read, has another schema, holds no
            rows, or repeats a (config, cell) of another part.
    """
    pa, pq = need_pyarrow()
    tables: list = []
    seen: dict[tuple[str, int], Path] = {}  # (config, cell) -> the part holding it
    for path in sorted(out.glob("part-*.parquet")):
        table = _read_part(path, pa, pq)
        for name, cell in zip(table.column("config").to_pylist(), table.column("cell").to_pylist(), strict=True):
            if (name, cell) in seen:
                raise _bad_part(path, f"repeats cell {cell} of config {name!r} (also in {seen[name, cell].name})")
            seen[name, cell] = path
        tables.append((path, table))
    return tables


def write_part(out: Path, rows: list[dict], tag: str) -> Path:
    """Write a batch's rows as one part, atomically (a part is whole or absent)."""
    pa, pq = need_pyarrow()
    table = pa.Table.from_pylist(rows, schema=schema())
    table = table.replace_schema_metadata({CHECKSUM_KEY: rows_checksum(table).encode("ascii")})
    path = out / f"part-{tag}-{rows[0]['cell']:09d}.parquet"
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp)
    return path


def remove_stale_temporaries(out: Path) -> None:
    """Remove the temporary files of parts whose writer was killed (never complete parts)."""
    for tmp in out.glob(".part-*.parquet.*.tmp"):
        with contextlib.suppress(OSError):
            tmp.unlink()
