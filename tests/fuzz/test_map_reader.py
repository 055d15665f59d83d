"""The map directory reader held to the rule of every reader: ``read_map`` and a rerun of
``run_map`` refuse in one line what ``map`` would never write — a part edited after it was
written (its checksum), a part without a checksum, a truncated part, parts without a manifest,
a manifest of another version, a part holding a configuration or a cell the manifest does not
have, a ``map.json`` that is a named pipe or a device (refused without reading it), and a part
whose checksum matches but whose clearance or pose columns hold what a cell never records (a
NaN or infinite clearance, one below -1 m, other than two body names, a name that is not text,
a pose of the wrong length or not finite, a pose without being reachable)."""

from __future__ import annotations

import json
import math
import os
import threading
from pathlib import Path

import pyarrow.parquet as pq
import pytest

import assembler_pin as ap
from assembler_pin.exceptions import MapError
from assembler_pin.maps import parse_grid, read_map, run_map
from assembler_pin.maps.store import CHECKSUM_KEY, rows_checksum

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


POSE = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.24, 0.0, 0.0, 0.0, 1.0]  # two plates, x y z qx qy qz qw
GOOD = {"reachable": True, "clearance_m": 0.02, "clearance_between": ["SP0 leg 0", "floor"], "plates_xyzquat": POSE}
"""A reachable row's clearance and pose columns as a cell records them."""

#: hostile clearance and pose columns, each written with a checksum that matches: (columns, refusal)
HOSTILE = {
    "clearance_nan": ({"clearance_m": math.nan}, "clearance_m nan"),
    "clearance_inf": ({"clearance_m": math.inf}, "clearance_m inf"),
    "clearance_below_minus_1m": ({"clearance_m": -1.5}, "below -1 m"),
    "clearance_without_bodies": ({"clearance_between": []}, "0 clearance_between names, not 2"),
    "clearance_one_body": ({"clearance_between": ["floor"]}, "1 clearance_between names, not 2"),
    "clearance_three_bodies": ({"clearance_between": ["a", "b", "c"]}, "3 clearance_between names, not 2"),
    "clearance_body_empty": ({"clearance_between": ["", "floor"]}, "clearance_between name ''"),
    "clearance_body_control": ({"clearance_between": ["SP0 leg 0", "a\nb"]}, "clearance_between name"),
    "clearance_body_null": ({"clearance_between": [None, "floor"]}, "clearance_between name None"),
    "clearance_body_numbers": ({"clearance_between": [1, 2]}, "clearance_between' of type list<"),  # int64 items
    "clearance_bodies_without_distance": ({"clearance_m": None}, "2 clearance_between names, not 0"),
    "pose_short": ({"plates_xyzquat": POSE[:13]}, "13 plates_xyzquat numbers"),
    "pose_one_plate": ({"plates_xyzquat": POSE[:7]}, "7 plates_xyzquat numbers"),
    "pose_missing": ({"plates_xyzquat": []}, "0 plates_xyzquat numbers"),
    "pose_nan": ({"plates_xyzquat": [math.nan, *POSE[1:]]}, "not finite"),
    "pose_not_a_rotation": ({"plates_xyzquat": [*POSE[:13], 2.0]}, "unit norm"),
    "pose_unreachable": ({"reachable": False}, "not being reachable"),
}


def _rewrite(part: Path, columns: dict) -> None:
    """Set the first row's ``columns`` (a value each) and sign the part with a matching checksum."""
    import pyarrow as pa

    table = pq.read_table(part)
    for name, value in columns.items():
        i = table.schema.names.index(name)
        array = pa.array([value] * table.num_rows)  # the value's own type: a hostile one is kept
        if not (pa.types.is_list(array.type) and pa.types.is_int64(array.type.value_type)):
            array = pa.array([value] * table.num_rows, table.schema.field(i).type)
        table = table.set_column(i, pa.field(name, array.type), array)
    table = table.replace_schema_metadata({CHECKSUM_KEY: rows_checksum(table).encode("ascii")})
    pq.write_table(table, part)


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
    elif how in HOSTILE:
        _rewrite(part, GOOD | HOSTILE[how][0])
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
    *HOSTILE,
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
        if how in HOSTILE:
            assert HOSTILE[how][1] in text, text


def test_an_untouched_map_is_read_back_and_reused(tmp_path):
    out = tmp_path / "m"
    _run(out)
    assert CHECKSUM_KEY in pq.read_table(_first_part(out)).schema.metadata
    assert read_map(out).num_rows == 2 and _run(out).skipped == 2
    rows = read_map(out).to_pylist()
    assert all(r["clearance_m"] is None and r["clearance_between"] == r["plates_xyzquat"] == [] for r in rows)


def test_a_row_as_a_cell_records_it_passes_the_checks(tmp_path):
    """The hostile cases are refused for their values, not for being edited: the same edit
    with the values a reachable cell records is read back."""
    out = tmp_path / "m"
    _run(out)
    _rewrite(_first_part(out), GOOD)
    first = read_map(out).to_pylist()[0]
    assert {k: first[k] for k in GOOD} == GOOD and _run(out).skipped == 2
