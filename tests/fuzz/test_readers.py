"""Property tests of the file readers and SPEC parsers (hypothesis): each input is refused
with an ``AssemblerError`` subclass, or read into exactly what it says — never a silently
different value, never another exception.

Complements ``tests/contract/test_fuzz.py`` (configs as YAML mappings, plate files, goals, solver
options): here trajectory files, waypoint files, grid and orientation SPECs, YAML number
spellings and forward-kinematics inputs.
"""

from __future__ import annotations

import itertools
import json
import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

import assembler_pin as ap
from assembler_pin.maps import parse_grid
from assembler_pin.motion import read_waypoints

from . import answers
from .corpus import _csv_text, _parse_csv
from .harness import call_api, fail

#: No example database and no shrinking or patch files: a run leaves nothing behind, and a
#: known failure costs no more than finding it.
_QUIET = dict(
    deadline=None, suppress_health_check=list(HealthCheck), database=None, phases=(Phase.explicit, Phase.generate)
)
FEW = settings(max_examples=25, **_QUIET)
SOME = settings(max_examples=80, **_QUIET)

hostile_floats = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, 1e300, -1e300, 1e-300, -0.0]),
    st.floats(allow_nan=True, allow_infinity=True),
)
hostile_scalars = st.one_of(
    hostile_floats,
    st.booleans(),
    st.none(),
    st.text(max_size=4),
    st.integers(min_value=-(10**30), max_value=10**30),
    st.lists(st.integers(), max_size=2),
)


# ---------------------------------------------------------------------- trajectory files
@st.composite
def trajectory_edits(draw):
    """(column kind, row fraction, new value or relative shift)."""
    kind = draw(st.sampled_from(["t", "L", "ee", "max_abs_force"]))
    row = draw(st.floats(0.05, 0.95))
    if kind == "t" or draw(st.booleans()):
        value = draw(st.sampled_from([math.nan, math.inf, -math.inf, -1.0, 1e9, 1e300]))
        return kind, row, ("set", value)
    shift = draw(st.floats(1e-5, 1e-1)) * draw(st.sampled_from([-1.0, 1.0]))
    return kind, row, ("add", shift)


def _edit_rows(header: list[str], rows: list[list], kind: str, frac: float, edit, rng_index: int) -> None:
    k = min(len(rows) - 1, max(1, int(frac * len(rows))))
    cols = {
        "t": [0],
        "L": [i for i, c in enumerate(header) if c.startswith("L_sp")],
        "ee": [i for i, c in enumerate(header) if c.startswith("ee_")],
        "max_abs_force": [header.index("max_abs_force")],
    }[kind]
    c = cols[rng_index % len(cols)]
    old = float(rows[k][c])
    new = edit[1] if edit[0] == "set" else old + edit[1] * (1.0 if kind != "max_abs_force" else 100.0)
    rows[k][c] = repr(new) if isinstance(rows[k][c], str) else new


@FEW
@given(edit=trajectory_edits(), fmt=st.sampled_from(["csv", "json"]), which=st.integers(0, 100))
def test_edited_trajectory_rows_are_refused(ws, tmp_path_factory, edit, fmt, which):
    """A row whose time, lengths, EE or max|F| was edited no longer agrees with itself (or is
    not finite): a strict reader refuses the file."""
    kind, frac, change = edit
    path = tmp_path_factory.mktemp("traj") / f"edited.{fmt}"
    if fmt == "json":
        doc = json.loads(ws.traj_json)
        _edit_rows(doc["columns"], doc["rows"], kind, frac, change, which)
        path.write_text(json.dumps(doc))
    else:
        pre, table, post = _parse_csv(ws.traj_csv)  # the v2 comment lines kept as written
        _edit_rows(table[0], table[1:], kind, frac, change, which)
        path.write_text(_csv_text(pre, table, post))
    call_api(lambda: ap.read_trajectory(path), "refuse", f"read_trajectory({fmt}, {kind} {change})")


def test_planned_trajectory_rows_agree_with_their_lengths(am, ws, tmp_path):
    """The planner's own file: every row's EE and max|F| are FK and statics of its lengths."""
    for fmt, text in (("csv", ws.traj_csv), ("json", ws.traj_json)):
        path = tmp_path / f"planned.{fmt}"
        path.write_text(text)
        answers.check_trajectory_file(am, path, f"planned trajectory ({fmt})", claimed_valid=True)


# ---------------------------------------------------------------------- waypoint files
@st.composite
def waypoint_docs(draw):
    good = [[0.0, 0.0, 0.95, 0.0, 0.0, 0.0], [0.01, 0.0, 0.95, 0.0, 0.0, 0.1]]
    rows = draw(
        st.one_of(
            st.just(good),
            st.lists(st.lists(st.one_of(hostile_scalars, st.floats(-1, 1)), min_size=5, max_size=7), max_size=4),
        )
    )
    doc: dict = {"waypoints": rows}
    if draw(st.booleans()):
        doc["times"] = draw(st.one_of(st.lists(hostile_scalars, max_size=3), hostile_scalars, st.just([0.0, 2.0])))
    if draw(st.booleans()):
        doc["degrees"] = draw(st.one_of(st.booleans(), hostile_scalars))
    return doc


def _is_real(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


@SOME
@given(doc=waypoint_docs())
def test_waypoint_files_are_read_as_written(tmp_path_factory, doc):
    path = tmp_path_factory.mktemp("wp") / "wp.json"
    path.write_text(json.dumps(doc))
    rows, times, degrees = doc["waypoints"], doc.get("times"), doc.get("degrees", False)
    well_formed = (
        len(rows) >= 2
        and all(isinstance(r, list) and len(r) == 6 and all(_is_real(v) for v in r) for r in rows)
        and isinstance(degrees, bool)
        and (
            times is None
            or (
                isinstance(times, list)
                and len(times) == len(rows)
                and all(_is_real(t) for t in times)
                and times[0] == 0
                and all(b > a for a, b in itertools.pairwise(times))
            )
        )
    )
    called = call_api(lambda: read_waypoints(path), "any" if well_formed else "refuse", f"read_waypoints({doc})")
    if called.error is not None:
        if well_formed and max(abs(v) for r in rows for v in r) < 1e3:
            fail("valid-input-refused", f"read_waypoints({doc}): {called.error}")
        return
    path_ = called.result
    for k, (pose, row) in enumerate(zip(path_.waypoints, rows, strict=True)):
        want = ap.kinematics.taa_to_se3(row, degrees=degrees)
        if not np.allclose(pose.homogeneous, want.homogeneous, atol=1e-12):
            fail("accepted", f"read_waypoints({doc}): waypoint {k} read as another pose")
    if times is not None and (path_.times is None or not np.allclose(path_.times, times)):
        fail("accepted", f"read_waypoints({doc}): times {times} read as {path_.times}")


# ---------------------------------------------------------------------- SPECs
axis_items = st.one_of(
    st.sampled_from(["0", "0.5", "-0.2", "nan", "inf", "1e400", "", "a", "1:2", "0:1:3:4", "0:1:2.5", "0:1:1e2"]),
    st.builds(
        lambda a, b, n: f"{a}:{b}:{n}",
        st.sampled_from(["0", "-1", "nan", "1e308", "0.2"]),
        st.sampled_from(["1", "inf", "-1e308", "0.7"]),
        st.sampled_from(["-1", "0", "1", "2", "3", "9", "10000000000000"]),
    ),
)
grid_specs = st.lists(
    st.tuples(st.sampled_from(["x", "y", "z", "X", "q", " x"]), axis_items).map(lambda t: f"{t[0]}={t[1]}"),
    max_size=4,
).map(",".join)
orientation_specs = st.one_of(
    st.none(),
    st.lists(
        st.lists(st.sampled_from(["0", "30", "-45", "nan", "inf", "1e400", "a", "1e7"]), min_size=2, max_size=4).map(
            " ".join
        ),
        max_size=3,
    ).map("; ".join),
)
_NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")
_YAML12_INT = re.compile(r"^(0o[0-7]+|0x[0-9a-fA-F]+)$")


@SOME
@given(spec=grid_specs, orientations=orientation_specs)
def test_grid_specs_are_refused_or_read_as_written(spec, orientations):
    called = call_api(lambda: parse_grid(spec, orientations), "any", f"parse_grid({spec!r}, {orientations!r})")
    if called.error is not None:
        return
    grid = called.result
    values = [*grid.x, *grid.y, *grid.z, *(v for o in grid.orientations for v in o)]
    if not all(math.isfinite(v) for v in values):
        fail("accepted", f"parse_grid({spec!r}, {orientations!r}): non-finite values in the grid")
    for item in filter(None, (p.strip() for p in spec.split(","))):
        axis, _, text = item.partition("=")
        axis = axis.strip().lower()
        if axis not in ("x", "y", "z"):
            fail("accepted", f"parse_grid({spec!r}): unknown axis '{axis}' accepted")
        parts = text.strip().split(":")
        if len(parts) == 3 and parts[2].lstrip("-").isdigit():
            count = int(parts[2])
            if len(getattr(grid, axis)) != count:
                fail("accepted", f"parse_grid({spec!r}): axis {axis} with COUNT {count} read with another count")
        elif len(parts) == 1 and not _NUMBER.match(parts[0]):
            fail("accepted", f"parse_grid({spec!r}): '{parts[0]}' accepted as a number")


yaml_numbers = st.sampled_from(
    [
        "9.81",
        "1.5",
        "2",
        "+1.5",
        "1e1",
        "1.0e1",
        "9_81",
        "1:30",
        "0x1F",
        "0o17",
        "017",
        ".nan",
        ".inf",
        "-.inf",
        "yes",
        "no",
        "on",
        "~",
        "'9.81'",
        "1e400",
        "0b101",
        "9.81.1",
        "1_000.5",
        "0.",
        ".5",
        "12e-1",
        "!!float 3",
        "!!int 3",
        "&a 3",
    ]
)
yaml_keys = st.sampled_from([("gravity",), ("payload", "mass"), ("plate", "mass"), ("leg", "max_tension")])


@SOME
@given(key=yaml_keys, text=yaml_numbers)
def test_yaml_numbers_are_refused_or_read_as_decimals(tmp_path_factory, key, text):
    """A YAML 1.1 spelling (``9_81``, ``1:30``, ``yes``, ``0b101``) is refused, never read as
    981, 90, 1 or 5; ``017`` is refused or read as 17 (never the YAML 1.1 octal 15); a plain
    decimal is read as itself. The YAML 1.2 core schema defines ``0o17`` (octal) and ``0x1F``
    (hexadecimal) as integers, so reading them as 15 and 31 is right, and an explicit tag
    (``!!float 3``) as the number it tags."""
    body = f"{key[0]}: {text}\n" if len(key) == 1 else f"{key[0]}:\n  {key[1]}: {text}\n"
    path = tmp_path_factory.mktemp("yaml") / "c.yaml"
    path.write_text(body)
    called = call_api(lambda: ap.load_config(path), "any", f"load_config({body!r})")
    if called.error is not None:
        return
    cfg = called.result
    value = getattr(cfg, key[0]) if len(key) == 1 else getattr(getattr(cfg, key[0]), key[1])
    if text.startswith(("!!float ", "!!int ")):  # an explicit YAML tag: the tagged number
        text = text.split(" ", 1)[1]
    if _YAML12_INT.match(text):  # YAML 1.2 core schema octal and hexadecimal integers
        if value != int(text, 0):
            fail("accepted", f"load_config({body.strip()!r}): read as {value!r}, not {int(text, 0)!r}")
        return
    if not _NUMBER.match(text):
        fail("accepted", f"load_config({body.strip()!r}): read as {value!r}")
    if value != float(text):
        fail("accepted", f"load_config({body.strip()!r}): read as {value!r}, not {float(text)!r}")


# ---------------------------------------------------------------------- forward kinematics
@FEW
@given(data=st.data())
def test_fk_of_hostile_lengths(am, data):
    lengths = np.array(
        data.draw(st.lists(st.one_of(hostile_floats, st.floats(0.2, 0.35)), min_size=am.n * 6, max_size=am.n * 6)),
        dtype=float,
    ).reshape(am.n, 6)
    expect = "any" if np.all(np.isfinite(lengths)) else "refuse"
    called = call_api(lambda: ap.stack_forward_kinematics(am, lengths), expect, f"FK of {lengths.tolist()}")
    if called.error is None and called.result.success:
        answers.check_fk_result(am, called.result, "FK of hostile lengths")
        uniform = float(lengths.flat[0])
        if np.all(lengths == uniform):
            answers.check_fk_result(am, called.result, "FK of hostile lengths", uniform)


@FEW
@given(p=st.tuples(hostile_floats, hostile_floats, hostile_floats).filter(lambda t: not all(map(math.isfinite, t))))
def test_non_finite_goals_never_succeed(am, p):
    import pinocchio as pin

    from assembler_pin.solver import solve

    goal = pin.SE3(np.eye(3), np.array(p, dtype=float))
    for name, fn in (
        ("initial_condition", lambda: ap.initial_condition(am, goal)),
        ("solve", lambda: solve(am, goal, optimize=False)),
    ):
        called = call_api(fn, "any", f"{name}(goal p={p})")
        if called.error is None and getattr(called.result, "success", False):
            fail("wrong-answer", f"{name}(goal p={p}): success for a goal that is not finite")


@pytest.mark.parametrize("platforms", [1, 2])
def test_small_stacks_answer_the_corpus_basics(platforms, tmp_path):
    """A 1- and 2-platform stack: the home pose is feasible by the independent check."""
    am = ap.AssemblerModel.from_config({"platforms": platforms})
    state = ap.evaluate_state(am, am.home)
    answers.check_state_doc(am, state.to_dict(), f"home of {platforms} platforms")
    assert state.feasible
