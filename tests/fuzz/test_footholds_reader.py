"""Hostile footholds files (``walk --footholds``): each refused in one line with a
``WalkError``, or read into exactly the poses it writes — never another exception, never a
silently different foothold."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import assembler_pin as ap
from assembler_pin.walk.footholds import read_footholds

from .harness import call_api, fail
from .test_readers import SOME, hostile_scalars

GOOD = [[0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0, 0.0, 0.0, 0.0]]


@st.composite
def foothold_docs(draw):
    rows = draw(
        st.one_of(
            st.just(GOOD),
            st.lists(st.lists(st.one_of(hostile_scalars, st.floats(-2, 2)), min_size=5, max_size=7), max_size=4),
            st.lists(hostile_scalars, max_size=3),
        )
    )
    doc: dict = {"footholds": rows}
    if draw(st.booleans()):
        doc["degrees"] = draw(st.one_of(st.booleans(), hostile_scalars))
    if draw(st.booleans()):
        doc["floor_z"] = draw(st.one_of(st.just(0.0), hostile_scalars))
    if draw(st.booleans()):
        doc[draw(st.sampled_from(["surface", "Footholds", ""]))] = 1
    return doc


def _is_real(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _well_formed(doc: dict) -> bool:
    rows, degrees, floor_z = doc["footholds"], doc.get("degrees", False), doc.get("floor_z")
    return (
        set(doc) <= {"footholds", "degrees", "floor_z"}
        and isinstance(rows, list)
        and 2 <= len(rows) <= 100
        and all(isinstance(r, list) and len(r) == 6 and all(_is_real(v) for v in r) for r in rows)
        and isinstance(degrees, bool)
        and (floor_z is None or (_is_real(floor_z) and abs(floor_z) <= 1e3))
    )


@SOME
@given(doc=foothold_docs())
def test_footholds_files_are_read_as_written(tmp_path_factory, doc):
    path = tmp_path_factory.mktemp("fh") / "footholds.json"
    path.write_text(json.dumps(doc))
    well_formed = _well_formed(doc)
    called = call_api(lambda: read_footholds(path), "any" if well_formed else "refuse", f"read_footholds({doc})")
    if called.error is not None:
        rows = doc["footholds"]
        if well_formed and max(abs(v) for r in rows for v in r) < 3:
            fail("valid-input-refused", f"read_footholds({doc}): {called.error}")
        return
    got = called.result
    for k, (pose, row) in enumerate(zip(got.footholds, doc["footholds"], strict=True)):
        want = ap.kinematics.taa_to_se3(row, degrees=doc.get("degrees", False))
        if not np.allclose(pose.homogeneous, want.homogeneous, atol=1e-12):
            fail("accepted", f"read_footholds({doc}): foothold {k} read as another pose")
    if got.floor_z != doc.get("floor_z"):
        fail("accepted", f"read_footholds({doc}): floor_z read as {got.floor_z}")


@pytest.mark.parametrize(
    "text",
    [
        "",
        "[]",
        "{}",
        '{"footholds": [[0,0,0,0,0,0],[0.5,0,0,0,0,0]], "footholds": []}',
        '{"footholds": [[0,0,0,0,0,NaN],[0.5,0,0,0,0,0]]}',
        '{"footholds": [[0,0,0,0,0,1e400],[0.5,0,0,0,0,0]]}',
        '{"footholds": [[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,2]], [0.5,0,0,0,0,0]]}',
        '{"footholds": [[[2,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], [0.5,0,0,0,0,0]]}',
        '{"footholds": [[true,0,0,0,0,0],[0.5,0,0,0,0,0]]}',
        '{"footholds": [[0,0,0,0,0,0]]}',
        '{"footholds": ' + json.dumps([[k, 0, 0, 0, 0, 0] for k in range(101)]) + "}",
        '{"footholds": [[0,0,0,0,0,0],[0.5,0,0,0,0,0]], "degrees": "yes"}',
        '{"footholds": [[0,0,0,0,0,0],[0.5,0,0,0,0,0]], "floor_z": 1e9}',
        '{"footholds": [[0,0,0,0,0,0],[0.5,0,0,0,0,0]], "floor_z": null, "x": 1}',
        '{"footholds": [[0,0,0,0,0,0],[0.5,0,0,0,0,0]]',
        "\udcff",
    ],
)
def test_malformed_footholds_files_are_refused_in_one_line(tmp_path, text):
    path = tmp_path / "footholds.json"
    path.write_bytes(text.encode("utf-8", "surrogateescape"))
    with pytest.raises(ap.exceptions.WalkError) as err:
        read_footholds(path)
    assert "\n" not in str(err.value) and len(str(err.value)) < 300


def test_a_4x4_foothold_file_reads_back_and_an_oversized_file_is_refused(tmp_path):
    path = tmp_path / "footholds.json"
    pose = ap.kinematics.taa_to_se3([0.5, 0.1, 0.0, 0.0, 0.0, 0.3])
    path.write_text(json.dumps({"footholds": [np.eye(4).tolist(), pose.homogeneous.tolist()], "floor_z": 0}))
    got = read_footholds(path)
    assert np.allclose(got.footholds[1].homogeneous, pose.homogeneous, atol=1e-15) and got.floor_z == 0.0
    path.write_text(" " * (1 << 20) + json.dumps({"footholds": GOOD}))
    with pytest.raises(ap.exceptions.WalkError, match=r"larger than 1048576 bytes \(walk.file_bytes\)"):
        read_footholds(path)
