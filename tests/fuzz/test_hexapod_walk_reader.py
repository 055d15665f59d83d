"""The walk file's strict reader: hostile edits of a real file are refused in one line with a
``HexapodError``, or read into exactly what the file says; the writer's file reads back
bit for bit."""

from __future__ import annotations

import copy
import functools
import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

import assembler_pin as ap
from assembler_pin.exceptions import HexapodError
from assembler_pin.hexapod import read_walk, walk, write_walk
from assembler_pin.hexapod.walkfile import walk_to_dict


@functools.cache
def _result():
    am = ap.AssemblerModel.from_config({"platforms": 1, "hexapod": {"stacks": 6}})
    return walk(am, (0.04, 0.0, 0.0), step=0.05, samples=1)


def test_the_written_file_reads_back_bit_for_bit(tmp_path):
    got = _result()
    path = write_walk(tmp_path / "w.json", got)
    assert [p.name for p in tmp_path.iterdir()] == ["w.json"]  # no temporary file left
    back = read_walk(path)
    assert (back.stacks, back.platforms, back.gait, back.feet) == (6, 1, "tripod", "resting")
    assert back.success == got.success and back.reason == got.reason
    for j, s in enumerate(got.samples):
        assert back.t[j] == s.t and back.step[j] == s.step and back.phase[j] == s.phase
        assert np.array_equal(back.body_pose[j], s.body_pose) and np.array_equal(back.feet_poses[j], s.feet)
        assert np.array_equal(back.stance[j], s.stance) and np.array_equal(back.lengths[j], s.lengths)
        assert np.array_equal(back.forces[j], s.forces) and back.max_abs_force[j] == s.max_abs_force
        assert back.stability_margin_m[j] == s.stability_margin_m and back.violations[j] == s.violations


def _edits():
    def at(path, value):
        def edit(doc):
            obj = doc
            for key in path[:-1]:
                obj = obj[key]
            if value is KeyError:
                del obj[path[-1]]
            else:
                obj[path[-1]] = value
            return doc

        return edit

    return {
        "version_2": at(["version"], 2),
        "version_true": at(["version"], True),
        "format_other": at(["format"], "assembler-pin trajectory"),
        "unknown_key": lambda d: {**d, "extra": 1},
        "missing_samples": at(["samples"], KeyError),
        "no_samples": at(["samples"], []),
        "stacks_zero": at(["stacks"], 0),
        "stacks_float": at(["stacks"], 6.0),
        "stacks_other": at(["stacks"], 5),
        "platforms_huge": at(["platforms"], 10**9),
        "gait_unknown": at(["gait"], "gallop"),
        "feet_unknown": at(["feet"], "glued"),
        "success_int": at(["success"], 1),
        "success_with_reason": at(["reason"], "why"),
        "t_string": at(["samples", 0, "t"], "0"),
        "t_back": at(["samples", 2, "t"], -1.0),
        "step_zero": at(["samples", 0, "step"], 0),
        "step_bool": at(["samples", 0, "step"], True),
        "phase_unknown": at(["samples", 0, "phase"], "jump"),
        "pose_short": at(["samples", 0, "body_pose"], [0.0] * 5),
        "pose_bool": at(["samples", 0, "body_pose", 0], False),
        "pose_long_integer": at(["samples", 0, "body_pose", 0], 10**40 + 1),
        "pose_huge_integer": at(["samples", 0, "body_pose", 0], 10**400),
        "feet_not_rigid": at(["samples", 0, "feet", 0, 0, 0], 2.0),
        "feet_last_row": at(["samples", 0, "feet", 0, 3, 0], 1.0),
        "stance_int": at(["samples", 0, "stance", 0], 1),
        "stance_short": at(["samples", 0, "stance"], [True] * 5),
        "lengths_null": at(["samples", 0, "lengths"], None),
        "forces_ragged": at(["samples", 0, "forces", 0], [[1.0]]),
        "margin_string": at(["samples", 0, "stability_margin_m"], "1"),
        "violations_number": at(["samples", 0, "violations"], [1]),
        "sample_extra_key": lambda d: d["samples"][0].update(x=1) or d,
    }


@pytest.mark.parametrize(("name", "edit"), list(_edits().items()))
def test_hostile_edits_are_refused_in_one_line(tmp_path, name, edit):
    doc = edit(copy.deepcopy(walk_to_dict(_result())))
    path = tmp_path / "w.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(HexapodError) as info:
        read_walk(path)
    assert "\n" not in str(info.value) and str(info.value).startswith("walk file")


TEXTS = ["", "{", "[]", '{"version": NaN}', '{"a": 1, "a": 2}', "null", '"walk"', "\x00\x01", "[" * 100000]


@pytest.mark.parametrize("text", TEXTS, ids=[f"text{j}" for j in range(len(TEXTS))])
def test_malformed_text_is_refused(tmp_path, text):
    path = tmp_path / "w.json"
    path.write_text(text)
    with pytest.raises(HexapodError):
        read_walk(path)


def test_missing_file_and_directory_are_refused(tmp_path):
    for path in (tmp_path / "missing.json", tmp_path):
        with pytest.raises(HexapodError):
            read_walk(path)


def _leaves(obj, path=()):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(obj, list) and obj:
        for j in {0, len(obj) - 1}:
            yield from _leaves(obj[j], (*path, j))
    else:
        yield path


_DOC = None


def _doc():
    global _DOC
    if _DOC is None:
        _DOC = walk_to_dict(_result())
    return _DOC


hostile = st.one_of(
    st.sampled_from([1e300, -1e300, 0, -1, 10**40, 10**400, True, False, None, "", "x", [], {}]),
    st.floats(allow_nan=False, allow_infinity=False),
)


@settings(
    max_examples=60,
    deadline=None,
    database=None,
    suppress_health_check=list(HealthCheck),
    phases=(Phase.explicit, Phase.generate),
)
@given(st.data())
def test_any_leaf_replaced_is_refused_or_read_as_written(tmp_path_factory, data):
    doc = copy.deepcopy(_doc())
    leaves = sorted(_leaves(doc), key=str)
    path = data.draw(st.sampled_from(leaves))
    value = data.draw(hostile)
    obj = doc
    for key in path[:-1]:
        obj = obj[key]
    obj[path[-1]] = value
    file = tmp_path_factory.mktemp("w") / "w.json"
    file.write_text(json.dumps(doc))
    try:
        back = read_walk(file)
    except HexapodError as exc:
        assert "\n" not in str(exc)
        return
    got = _read_at(back, path)
    assert got == value or (value is None and _isnan(got))


def _isnan(x):
    return isinstance(x, float) and math.isnan(x)


def _read_at(back, path):
    """What the reader made of the leaf at ``path`` of the file."""
    if path[0] != "samples":
        return getattr(back, path[0])
    key, j, rest = path[2], path[1], path[3:]
    if key in ("phase", "violations"):
        got = getattr(back, key)[j]
        return got[rest[0]] if rest else (list(got) if key == "violations" else got)
    arrays = {"feet": back.feet_poses, "step": back.step, "stance": back.stance}
    value = (arrays[key] if key in arrays else getattr(back, key))[j][tuple(rest)]
    return value.item() if hasattr(value, "item") else value
