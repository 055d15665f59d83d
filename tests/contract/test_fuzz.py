"""Property tests of the refusal contract: malformed configs, plate files, goals and options.

Through the CLI every bad input ends with exit status 2 and exactly one line on stderr (no
traceback); through the API it raises an :class:`AssemblerError` subclass or answers with
success false — never another exception, never a NaN marked feasible.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import assembler_pin as ap
from assembler_pin.cli import main

FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
TMP = Path(tempfile.mkdtemp(prefix="assembler_pin_fuzz_"))

bad_scalars = st.one_of(
    st.booleans(),
    st.text(max_size=5),
    st.just(None),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([1e308, -1e308, 1e200, -1.0, 0.0, 1e-300, "2e-1", "nan", "inf"]),
    st.lists(st.integers(), max_size=3),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)
sections = {
    "plate": ["node_radius", "node_spacing_deg", "mass", "radius", "thickness"],
    "leg": [
        "min_length",
        "max_length",
        "motor_mass",
        "shaft_mass",
        "motor_com",
        "shaft_com",
        "max_deflection_deg",
        "max_tension",
        "max_compression",
        "motor_radius",
        "shaft_radius",
        "motor_length",
        "node_zone",
    ],
    "payload": ["mass", "offset", "radius"],
}


@st.composite
def configs(draw) -> dict:
    """A config mapping with at least one entry drawn from the bad values (or unknown keys)."""
    doc: dict = {}
    if draw(st.booleans()):
        doc["platforms"] = draw(st.one_of(st.integers(1, 4), bad_scalars, st.integers(65, 10**6)))
    if draw(st.booleans()):
        doc["gravity"] = draw(st.one_of(st.floats(0, 20), bad_scalars))
    if draw(st.booleans()):
        doc["clearance"] = draw(st.one_of(st.floats(0, 0.05), bad_scalars, st.floats(1.0, 1e300)))
    for name, keys in sections.items():
        if draw(st.booleans()):
            doc[name] = draw(
                st.one_of(
                    bad_scalars,
                    st.dictionaries(
                        st.sampled_from([*keys, "bogus"]), st.one_of(bad_scalars, st.floats(0, 1)), max_size=3
                    ),
                )
            )
    if draw(st.booleans()):
        doc[draw(st.text(min_size=1, max_size=6))] = draw(bad_scalars)
    return doc


def run_cli(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def assert_one_line_refusal(code: int, err: str) -> None:
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err


def assert_strict_json_answer(out: str) -> dict:
    doc = json.loads(out, parse_constant=lambda c: pytest.fail(f"non-strict JSON token {c}"))
    return doc


@FUZZ
@given(doc=configs())
def test_config_files_are_accepted_or_refused_in_one_line(doc):
    path = TMP / "config.yaml"
    path.write_text(yaml.safe_dump(doc, allow_unicode=True))
    code, out, err = run_cli(["statics", "--home", "--json", "--config", str(path)])
    if code == 0:
        state = assert_strict_json_answer(out)
        cfg = ap.load_config(path)  # the CLI accepted it: so does the API, with finite forces
        assert state["feasible"] is False or all(math.isfinite(f) for row in state["forces"] for f in row)
        assert cfg.platforms == len(state["forces"])
    else:
        assert_one_line_refusal(code, err)


@FUZZ
@given(doc=configs())
def test_config_mappings_raise_only_config_errors(doc):
    try:
        ap.load_config(doc)
    except ap.AssemblerError as exc:
        assert isinstance(exc, ap.exceptions.ConfigError) and str(exc)


matrix_entries = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.text(max_size=3),
    st.just(None),
    st.sampled_from([1e308, -1e308]),
)
plate_docs = st.one_of(
    bad_scalars,
    st.fixed_dictionaries({"plates": bad_scalars}),
    st.fixed_dictionaries(
        {"plates": st.lists(st.lists(st.lists(matrix_entries, min_size=0, max_size=5), max_size=5), max_size=6)}
    ),
    st.recursive(st.integers(), lambda inner: st.lists(inner, max_size=2), max_leaves=40),
)


@FUZZ
@given(doc=plate_docs)
def test_plate_files_are_answered_or_refused_in_one_line(doc):
    path = TMP / "plates.json"
    path.write_text(json.dumps(doc))
    code, out, err = run_cli(["statics", "--plates", str(path), "--json"])
    if code in (0, 1):  # a valid pose, or the answer for one that is not
        assert (code == 0) is assert_strict_json_answer(out)["feasible"]
    else:
        assert_one_line_refusal(code, err)


def test_pathological_plate_files_are_refused_in_one_line():
    cases = {
        "deep.json": "[" * 50_000 + "]" * 50_000,
        "bools.json": json.dumps({"plates": [[[True] * 4] * 4] * 5}),
        "latin1.json": b"\xff\xfe{}".decode("latin-1"),
    }
    for name, text in cases.items():
        path = TMP / name
        path.write_bytes(text.encode("latin-1") if name == "latin1.json" else text.encode())
        code, _, err = run_cli(["statics", "--plates", str(path)])
        assert_one_line_refusal(code, err)


goal_words = st.one_of(
    st.sampled_from(["nan", "inf", "-inf", "1e400", "-1e-3", "abc", "", "--", "1e200", "-1e308", "0x10", "1_0"]),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
)


@FUZZ
@given(words=st.lists(goal_words, min_size=0, max_size=8))
def test_goals_are_answered_or_refused_in_one_line(words):
    if len(words) == 6 and all(_finite(w) for w in words) and max(abs(float(w)) for w in words[:3]) < 5:
        words[0] = "10"  # keep in-range goals out of reach: the helper arm's full scan is not the point here
    code, out, err = run_cli(["solve", "--no-optimize", "--json", "--goal", *words])
    if code == 1:  # answered: not possible
        doc = assert_strict_json_answer(out)
        assert doc["success"] is False and "out of reach" in doc["message"]
    else:
        assert_one_line_refusal(code, err)


def _finite(word: str) -> bool:
    try:
        return math.isfinite(float(word))
    except ValueError:
        return False


@FUZZ
@given(
    option=st.sampled_from(["--w1", "--w2", "--ftol", "--max-iterations", "--d-step", "--max-attempts"]),
    value=st.sampled_from(["nan", "inf", "-1", "0", "-1e-3", "abc", "1.5", "1e400"]),
)
def test_solver_options_are_checked(option, value):
    code, _, err = run_cli(["solve", "--goal", "10", "0", "0.9", "0", "0", "0", "--json", option, value])
    if code != 1:  # 1: accepted, and the goal answered out of reach
        assert_one_line_refusal(code, err)


@pytest.fixture(scope="module")
def am():
    return ap.AssemblerModel.from_config()


api_inputs = st.one_of(
    bad_scalars,
    st.lists(st.one_of(bad_scalars, st.lists(matrix_entries, max_size=4)), max_size=6),
    st.just(np.full((5, 4, 4), np.nan)),
    st.just(np.zeros((5, 4, 4))),
    st.just(np.array([[[True] * 4] * 4] * 5)),
)


@FUZZ
@given(value=api_inputs)
def test_api_entry_points_raise_only_assembler_errors(am, value):
    calls = [
        lambda: ap.evaluate_state(am, value),
        lambda: ap.solve_statics(am, value),
        lambda: ap.kinematics.taa_to_se3(value),
        lambda: ap.kinematics.to_se3(value),
        lambda: ap.stack_forward_kinematics(am, value),
        lambda: ap.kinematics.leg_state(am, value),
    ]
    for call in calls:
        try:
            result = call()
        except ap.AssemblerError:
            continue
        if isinstance(result, ap.StackState):
            assert not result.feasible or np.all(np.isfinite(result.forces))
