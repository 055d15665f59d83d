"""The map directory reader held to the rule of every reader: ``read_map`` and a rerun of
``run_map`` refuse in one line what ``map`` would never write — a part edited after it was
written (its checksum), a part without a checksum, a truncated part, parts without a manifest,
a manifest of another version, a part holding a configuration or a cell the manifest does not
have, and a ``map.json`` that is a named pipe or a device (refused without reading it)."""

from __future__ import annotations

import json
import os
import threading
from pathlib import Path

import pyarrow.parquet as pq
import pytest

import assembler_pin as ap
from assembler_pin.exceptions import MapError
from assembler_pin.maps import parse_grid, read_map, run_map
from assembler_pin.maps.store import CHECKSUM_KEY

FAR = "x=3:3.2:2,y=0,z=0.8"  # two cells out of reach: answered at once


def _run(out: Path):
    return run_map(parse_grid(FAR), [("default", ap.load_config())], out, workers=0)


def _first_part(out: Path) -> Path:
    return sorted(out.glob("part-*.parquet"))[0]


def _set_column(part: Path, name: str, values: list, keep_checksum: bool) -> None:
    table = pq.read_table(part)
    import pyarrow as pa

    i = table.schema.names.index(name)
    edited = table.set_column(i, table.schema.field(i), pa.array(values, table.schema.field(i).type))
    edited = edited.replace_schema_metadata(table.schema.metadata if keep_checksum else None)
    pq.write_table(edited, part)


def _edit(out: Path, how: str) -> None:
    part = _first_part(out)
    manifest = out / "map.json"
    if how == "force_edited":  # the checksum kept: the rows no longer match it
        _set_column(part, "max_abs_force", [1e9], keep_checksum=True)
    elif how == "key_edited":
        _set_column(part, "key", ["0" * 32], keep_checksum=True)
    elif how == "no_checksum":
        _set_column(part, "max_abs_force", [1e9], keep_checksum=False)
    elif how == "truncated":
        part.write_bytes(part.read_bytes()[:60])
    elif how == "no_manifest":
        manifest.unlink()
    elif how == "older_version":
        doc = json.loads(manifest.read_text())
        manifest.write_text(json.dumps(doc | {"version": 2}))
    elif how == "other_config":
        doc = json.loads(manifest.read_text())
        manifest.write_text(json.dumps(doc | {"configs": {"other": doc["configs"]["default"]}}))
    elif how == "manifest_fifo":
        manifest.unlink()
        os.mkfifo(manifest)
    elif how == "manifest_dev_zero":
        manifest.unlink()
        manifest.symlink_to("/dev/zero")
    elif how == "manifest_huge":
        manifest.write_bytes(b" " * (2 << 20))
    else:  # pragma: no cover
        raise AssertionError(how)


CASES = [
    "force_edited",
    "key_edited",
    "no_checksum",
    "truncated",
    "no_manifest",
    "older_version",
    "other_config",
    "manifest_fifo",
    "manifest_dev_zero",
    "manifest_huge",
]


def _refused_in_time(call) -> MapError:
    """``call()`` raises MapError within 20 s (a pipe read whole would block forever)."""
    got: list = []
    worker = threading.Thread(target=lambda: got.append(_outcome(call)), daemon=True)
    worker.start()
    worker.join(20)
    assert got, "no answer within 20 s (the reader blocked)"
    assert isinstance(got[0], MapError), f"not a MapError: {got[0]!r}"
    return got[0]


def _outcome(call):
    try:
        return call()
    except Exception as exc:
        return exc


@pytest.mark.parametrize("how", CASES)
def test_map_readers_refuse_what_map_would_never_write(tmp_path, how):
    if how == "manifest_fifo" and not hasattr(os, "mkfifo"):
        pytest.skip("no named pipes here")
    out = tmp_path / "m"
    _run(out)
    _edit(out, how)
    for call in (lambda: read_map(out), lambda: _run(out)):
        text = str(_refused_in_time(call))
        assert "\n" not in text and len(text) < 400, text


def test_an_untouched_map_is_read_back_and_reused(tmp_path):
    out = tmp_path / "m"
    _run(out)
    assert CHECKSUM_KEY in pq.read_table(_first_part(out)).schema.metadata
    assert read_map(out).num_rows == 2 and _run(out).skipped == 2
