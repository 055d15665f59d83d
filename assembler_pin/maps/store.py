"""A map directory on disk: its manifest, its Parquet parts, and the strict reader of both.

A map directory holds one map: ``map.json`` (the manifest: the grid's, every configuration's
and the solver settings' hashes) and one ``part-*.parquet`` file per finished batch, each row
carrying the ``key`` of what it was computed from (:func:`~.cells.cell_key`). Every file is
written atomically (:func:`~assembler_pin.common.files.atomic_path`): a part is whole or absent.
A directory that holds another map, a part that cannot be read, has another schema, repeats
a cell or holds a row computed from anything else is refused with one line
(:class:`~assembler_pin.exceptions.MapError`); its rows are never mixed into an answer.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
from pathlib import Path

from ..common.files import atomic_path, write_atomic
from ..exceptions import AssemblerError, MapError
from .cells import COLUMNS
from .grid import Grid

__all__ = ["MANIFEST", "check_manifest", "grid_hash", "manifest_for", "read_parts", "write_part"]

MANIFEST = "map.json"
"""The manifest's file name in a map directory."""
FORMAT = "assembler_pin map"
VERSION = 3  # 3: the sag and weakest-stiffness columns
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
    return pa.schema([(c, types.get(c, pa.float64())) for c in COLUMNS])


def grid_hash(grid: Grid) -> str:
    """A stable hash of a grid's axis values [m] and orientations [rad], exactly."""
    doc = [[v.hex() for v in getattr(grid, a)] for a in ("x", "y", "z")]
    doc.append([[v.hex() for v in r] for r in grid.orientations])
    return hashlib.sha256(json.dumps(doc).encode()).hexdigest()


def manifest_for(grid: Grid, configs: dict[str, str], solver: str) -> dict:
    """The manifest of a map: ``configs`` maps each configuration's name to its hash."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "shape": list(grid.shape),
        "grid": grid_hash(grid),
        "configs": dict(sorted(configs.items())),
        "solver": solver,
    }


def _read_manifest(path: Path) -> dict:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError):
        raise MapError(f"the map manifest {path} cannot be read as JSON: {_HOW}") from None
    keys = {"format", "version", "shape", "grid", "configs", "solver"}
    if not isinstance(doc, dict) or doc.get("format") != FORMAT or set(doc) != keys:
        raise MapError(f"{path} is not an assembler_pin map manifest: {_HOW}")
    return doc


def check_manifest(out: Path, wanted: dict) -> None:
    """Write ``wanted`` as the manifest of a new map directory, or check that ``out`` holds this
    same map; a directory holding another map, or parts without a manifest, is refused."""
    path = out / MANIFEST
    if not path.exists():
        if any(out.glob("part-*.parquet")):
            raise MapError(f"the map directory {out} holds parts without a manifest ({MANIFEST}): {_HOW}")
        write_atomic(path, json.dumps(wanted, indent=1) + "\n")
        return
    have = _read_manifest(path)
    if have == wanted:
        return
    named = (("version", "version"), ("grid", "grid"), ("solver settings", "solver"))
    differs = [what for what, key in named if have.get(key) != wanted[key]]
    old, new = have.get("configs"), wanted["configs"]
    if not isinstance(old, dict) or set(old) != set(new):
        differs.append("configuration names")
    else:
        differs += [f"configuration {name!r} content" for name in new if old[name] != new[name]]
    raise MapError(f"the map directory {out} holds another map (its {', '.join(differs) or 'manifest'} differ): {_HOW}")


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
    if table.column("config").null_count or table.column("cell").null_count or table.column("key").null_count:
        raise _bad_part(path, "holds rows without config, cell or key")
    return table


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
    path = out / f"part-{tag}-{rows[0]['cell']:09d}.parquet"
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp)
    return path


def remove_stale_temporaries(out: Path) -> None:
    """Remove the temporary files of parts whose writer was killed (never complete parts)."""
    for tmp in out.glob(".part-*.parquet.*.tmp"):
        with contextlib.suppress(OSError):
            tmp.unlink()
