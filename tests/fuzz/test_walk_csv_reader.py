"""Hostile walk samples files (``walk --out DIR``'s walk.csv): each refused in one line with a
``WalkError``, or read into exactly the phases, supports and lengths it writes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import assembler_pin as ap
from assembler_pin.supports.two_point import SUPPORTS
from assembler_pin.walk import WalkPhase, WalkResult
from assembler_pin.walk.samples import parse_walk_csv, read_walk_csv, walk_csv

from .harness import call_api, fail
from .test_readers import FEW

#: (kind, support, foothold, samples) of a walk of two steps cut in its second transfer.
PHASES = (("reach", "base", 1, 3), ("transfer", "both", 1, 2), ("swing", "ee", 2, 2), ("transfer", "both", 2, 1))


@pytest.fixture(scope="module")
def good(am) -> tuple[str, WalkResult]:
    """A walk's samples text and the walk: lengths 0.2..0.3 m, forces up to 50 N."""
    rng = np.random.default_rng(3)
    home = ap.kinematics.plate_arrays(am, am.home)
    phases = []
    for kind, support, step, m in PHASES:
        L = rng.uniform(0.2, 0.3, (m, am.n, 6))
        F = rng.uniform(-50.0, 50.0, (m, am.n, 6))
        phases.append(WalkPhase(kind, support, step, [home] * m, L, L + 1e-4, F, True))
    walk = WalkResult(False, "step 2: the load cannot move to foothold 2", (), phases)
    return walk_csv(am, walk), walk


def _edit(text: str, row: int, column: int, value: str) -> str:
    lines = text.split("\n")
    fields = lines[row + 1].split(",")
    fields[column] = value
    lines[row + 1] = ",".join(fields)
    return "\n".join(lines)


def test_a_walks_samples_read_back_as_written(am, good, tmp_path):
    text, walk = good
    path = tmp_path / "walk.csv"
    path.write_text(text)
    got = read_walk_csv(path, n=am.n)
    want = [(k, p.kind, p.support, p.step) for k, p in enumerate(walk.phases) for _ in p.plates]
    assert list(zip(got.phase, got.kind, got.support, got.foothold, strict=True)) == want
    commanded = np.concatenate([p.commanded for p in walk.phases])
    assert np.abs(got.commanded - commanded).max() <= 5e-10  # written with 9 decimals
    peaks = np.concatenate([np.abs(p.forces).reshape(len(p.plates), -1).max(axis=1) for p in walk.phases])
    assert np.abs(got.max_abs_force - peaks).max() <= 5e-7
    with pytest.raises(ap.exceptions.WalkError, match="4 platforms, the model has 8"):
        read_walk_csv(path, n=8)


HOSTILE = {
    "empty": lambda t: "",
    "header-only-no-newline": lambda t: t.split("\n")[0],
    "truncated-mid-row": lambda t: t[: len(t) // 2],
    "truncated-at-a-line-end": lambda t: t[: t.index("\n", len(t) // 2) + 1].rsplit(",", 3)[0] + "\n",
    "unknown-phase": lambda t: _edit(t, 3, 2, "hop"),
    "phase-kind-out-of-order": lambda t: _edit(_edit(t, 5, 2, "reach"), 5, 3, "base"),
    "support-not-in-SUPPORTS": lambda t: _edit(t, 0, 3, "left_foot"),
    "support-not-its-kinds": lambda t: _edit(t, 0, 3, "ee"),
    "support-none": lambda t: _edit(t, 3, 3, "none"),
    "nan-length": lambda t: _edit(t, 1, 9, "nan"),
    "NaN-length": lambda t: _edit(t, 1, 6, "NaN"),
    "inf-length": lambda t: _edit(t, 2, 7, "inf"),
    "huge-length": lambda t: _edit(t, 2, 7, "1e400"),
    "negative-length": lambda t: _edit(t, 2, 7, "-0.25"),
    "zero-length": lambda t: _edit(t, 2, 7, "0"),
    "underscore-number": lambda t: _edit(t, 2, 7, "0_25"),
    "nan-force": lambda t: _edit(t, 0, 5, "nan"),
    "negative-force": lambda t: _edit(t, 0, 5, "-1"),
    "sample-gap": lambda t: _edit(t, 2, 0, "3"),
    "phase-skips": lambda t: _edit(t, 3, 1, "2"),
    "phase-back": lambda t: _edit(t, 4, 1, "0"),
    "foothold-wrong": lambda t: _edit(t, 0, 4, "2"),
    "negative-phase": lambda t: _edit(t, 0, 1, "-1"),
    "extra-field": lambda t: _edit(t, 0, 5, "1.0,2.0"),
    "blank-line": lambda t: t + "\n",
    "header-renamed": lambda t: t.replace("L_sp0_leg3", "L_sp0_leg9", 1),
    "header-short": lambda t: t.replace(",L_sp3_leg5", "", 1),
    "not-csv": lambda t: '{"footholds": []}\n',
    "arabic-indic-length": lambda t: _edit(t, 2, 7, "\u0660.\u0662\u0665"),
    "arabic-indic-sample": lambda t: _edit(t, 1, 0, "\u0661"),
    "fullwidth-force": lambda t: _edit(t, 0, 5, "\uff11\uff10"),
}


@pytest.mark.parametrize("case", list(HOSTILE))
def test_hostile_walk_samples_are_refused_in_one_line(good, tmp_path, case):
    path = tmp_path / "walk.csv"
    path.write_text(HOSTILE[case](good[0]))
    with pytest.raises(ap.exceptions.WalkError) as err:
        read_walk_csv(path)
    assert "\n" not in str(err.value) and len(str(err.value)) < 300


@pytest.mark.parametrize("path", [None, b"walk.csv", 5, "", ["walk.csv"]])
def test_walk_file_readers_refuse_what_is_not_a_path(path):
    """The readers' argument: a str or path, else one WalkError (never a TypeError)."""
    for read in (read_walk_csv, ap.walk.footholds.read_footholds):
        with pytest.raises(ap.exceptions.WalkError, match="path"):
            read(path)


@pytest.mark.parametrize("text", [None, b"sample\n", 5])
def test_parse_walk_csv_refuses_what_is_not_text(text):
    with pytest.raises(ap.exceptions.WalkError, match="str"):
        parse_walk_csv(text)


def test_walk_file_readers_refuse_pipes_and_devices(tmp_path):
    """Only regular files are read: a named pipe would block, /dev/zero never ends."""
    import os

    fifo = tmp_path / "walk.csv"
    os.mkfifo(fifo)
    for path in (fifo, "/dev/zero"):
        for read in (read_walk_csv, ap.walk.footholds.read_footholds, ap.read_trajectory):
            with pytest.raises(ap.AssemblerError, match="not a regular file"):
                read(path)


TOKENS = st.one_of(
    st.sampled_from(["nan", "inf", "-inf", "", " ", "1e999", "0x10", "1_0", "reach", "swing", *SUPPORTS]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-5, 5).map(str),
    st.text(max_size=5),
)


@FEW
@given(row=st.integers(0, 7), column=st.integers(0, 29), token=TOKENS)
def test_an_edited_field_is_refused_or_read_as_written(good, row, column, token):
    text = _edit(good[0], row, column, token)
    called = call_api(lambda: parse_walk_csv(text), "any", f"walk.csv row {row} column {column} = {token!r}")
    if called.error is not None:
        return
    got = called.result
    j, i = divmod(column - 6, 6)
    read = {
        0: row,
        1: got.phase[row],
        2: got.kind[row],
        3: got.support[row],
        4: got.foothold[row],
        5: got.max_abs_force[row],
    }.get(column, got.commanded[row, j, i] if column >= 6 else None)
    expected = token if column in (2, 3) else float(token)
    if read != expected:
        fail("accepted", f"walk.csv row {row} column {column} = {token!r} read as {read!r}")
