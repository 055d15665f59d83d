"""One numbering: the same leg read through every surface a user reads has the same label.

The pose is built with one leg too long — leg 2 of platform 1, ``lengths[1, 2]`` — so the
leg each surface must name is known from how the pose was made, not from the labels.
"""

from __future__ import annotations

import json
import re
from types import SimpleNamespace

import numpy as np
import pytest

from assembler_pin import evaluate_state, plots, stack_forward_kinematics
from assembler_pin.cli import format_state_table
from assembler_pin.common.labels import leg_label, platform_label
from assembler_pin.reproduce import ScenarioOutcome, force_tables, summary_table
from assembler_pin.scenarios import SCENARIOS

J, I = 1, 2  # the leg made too long: platform 1, leg 2 (0-based, as the arrays)


@pytest.fixture(scope="module")
def state(am):
    lengths = np.full((am.n, 6), 0.275)
    lengths[J, I] = am.config.leg.max_length + 0.01
    lengths[3, 4] = 0.25  # some asymmetry elsewhere, within the stroke
    return evaluate_state(am, stack_forward_kinematics(am, lengths).raise_if_failed())


@pytest.fixture(scope="module")
def heaviest(state):
    """(platform, leg) of the largest |F|, from the force array."""
    j, i = np.unravel_index(np.abs(state.forces).argmax(), state.forces.shape)
    return int(j), int(i)


def test_labels():
    assert platform_label(0) == "SP0" and leg_label(1, 2) == "SP1 leg 2"
    assert leg_label(np.int64(3), np.int64(5)) == "SP3 leg 5"  # numpy indices read as plain numbers


def test_json_and_violation_text(state):
    doc = json.loads(json.dumps(state.to_dict()))
    too_long = [v for v in doc["violations"] if v["kind"] == "max_length"]
    assert [(v["platform"], v["leg"]) for v in too_long] == [(J, I)]
    assert doc["leg_lengths"][J][I] == pytest.approx(state.leg_lengths[J, I])
    (violation,) = [v for v in state.violations if v.kind == "max_length"]
    assert (violation.platform, violation.leg) == (J, I)
    assert str(violation).startswith(f"max_length at {leg_label(J, I)}: ")


def _cell(table: str, row: str, column: str, header_prefix: str = "leg") -> str:
    """The cell of a ``|``-separated text table at a row label and a column header."""
    lines = table.splitlines()
    header = next(line for line in lines if line.startswith(header_prefix))
    columns = [c.strip() for c in header.split("|")]
    col = next(k for k, c in enumerate(columns) if c.split()[0] == column)
    line = next(line for line in lines if line.split("|")[0].strip() == row)
    return line.split("|")[col]


def test_state_table(state, heaviest):
    table = format_state_table(state)
    force, length_mm = (float(x) for x in _cell(table, str(I), platform_label(J)).split())
    assert force == pytest.approx(state.forces[J, I], abs=5e-4)
    assert length_mm == pytest.approx(1e3 * state.leg_lengths[J, I], abs=5e-3)
    assert f"  - max_length at {leg_label(J, I)}: " in table
    assert f"N ({leg_label(*heaviest)})," in table


def test_reproduce_tables(state, heaviest, am):
    other = evaluate_state(am, am.home)
    result = SimpleNamespace(initial=state, optimized=other, message="test", timing_s={"initial": 0.0})
    outcome = ScenarioOutcome(SCENARIOS["translation"], result, (am.config.leg.min_length, am.config.leg.max_length))

    text = force_tables(outcome).splitlines()
    header, rows = text[1], {line.split()[0]: line for line in text[2:]}
    initial_half = [c.split() for c in (header.split("|")[0], rows[str(I)].split("|")[0])]
    column = initial_half[0].index(platform_label(J))  # "leg SP0 SP1 ...": the row label comes first
    assert float(initial_half[1][column]) == pytest.approx(state.forces[J, I], abs=5e-3)

    md = force_tables(outcome, markdown=True).splitlines()
    cells = [c.strip() for c in md[0].strip("|").split("|")]
    row = next(line for line in md[2:] if line.strip("|").split("|")[0].strip() == str(I))
    value = row.strip("|").split("|")[cells.index(f"initial {platform_label(J)}")]
    assert float(value) == pytest.approx(state.forces[J, I], abs=5e-3)

    assert f"({leg_label(*heaviest)})" in summary_table([outcome])
    assert f"({leg_label(*heaviest)})" in summary_table([outcome], markdown=True)


def test_figure_labels(state):
    fig = plots.force_heatmaps(state)
    ax = next(ax for ax in fig.axes if ax.images)
    xticks = [t.get_text() for t in ax.get_xticklabels()]
    yticks = [t.get_text() for t in ax.get_yticklabels()]
    (cell,) = [t for t in ax.texts if t.get_position() == (xticks.index(platform_label(J)), yticks.index(f"leg {I}"))]
    assert float(cell.get_text()) == pytest.approx(state.forces[J, I], abs=0.051)

    ax = plots.force_bars(state).axes[0]
    labels = [t.get_text() for t in ax.get_xticklabels()]
    heights = [p.get_height() for p in ax.patches]
    assert heights[labels.index(leg_label(J, I))] == pytest.approx(state.forces[J, I])


def test_viewer_marks_the_leg_by_the_same_numbers(am, state):
    from assembler_pin.viz import StackViewer

    assert StackViewer.violating_legs(state) == [(J, I)]
    with StackViewer(am) as v:
        v.display(state)
        html = v.static_html(frame=False)
    marker_paths = set(re.findall(r"/meshcat/assembler_violations/[A-Za-z0-9_]+", _decoded_paths(html)))
    assert marker_paths == {f"/meshcat/assembler_violations/sp{J}_leg{I}"}  # as the URDF's sp1_leg2_* names


def _decoded_paths(html: str) -> str:
    import base64

    import umsgpack

    blobs = re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html)
    return "\n".join(str(umsgpack.unpackb(base64.b64decode(b)).get("path", "")) for b in blobs)
