"""The motion guide's comparison (docs/guides/motion.md): its block is the output of
``plan --compare`` and ``plan --compare --w3 10000`` as docs/gen_motion.py writes it, and every
sentence in it that states a figure is the one written from the tables printed above it (a
hand edit of a figure, or a table rerun without its sentences, fails here). The runs themselves
take minutes: ``python docs/gen_motion.py --check`` compares the block with a fresh run."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"


@pytest.fixture(scope="module")
def gen():
    spec = importlib.util.spec_from_file_location("gen_motion", DOCS / "gen_motion.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_comparisons_sentences_are_those_of_its_tables(gen):
    page = gen.PAGE.read_text(encoding="utf-8")
    default, stiff = gen.tables_on_page(page)
    assert page == gen.with_block(page, gen.block(default, stiff)), "run python docs/gen_motion.py"
    rows = gen.parse_table(default)
    assert len(rows) == 9 and {m for _, m in rows} == {"optimized", "helper_arm", "linear_lengths"}
    assert len(gen.parse_table(stiff)) == 9


def test_the_findings_follow_the_tables(gen):
    """The sentences change with the figures: a plan valid everywhere is named, a linear plan
    below ours is named, the helper arm's margin is the table's."""
    header = "path plan peak travel time valid limits off"
    rows = {
        ("a_path", "optimized"): (50.0, 2.0, 5.0, 100.0, 100.0, 1.0),
        ("a_path", "helper_arm"): (100.0, 1.0, 9.0, 90.0, 100.0, 3.0),
        ("a_path", "linear_lengths"): (60.0, 1.0, 2.0, 100.0, 100.0, 40.0),
    }
    table = "\n".join([header] + [f"{p} {m} " + " ".join(map(str, v)) for (p, m), v in rows.items()])
    stiff_rows = dict(rows) | {("a_path", "linear_lengths"): (40.0, 1.0, 2.0, 20.0, 100.0, 50.0)}
    stiff = "\n".join([header] + [f"{p} {m} " + " ".join(map(str, v)) for (p, m), v in stiff_rows.items()])
    text = " ".join(gen.findings(gen.parse_table(table), gen.parse_table(stiff)).split())
    assert "and so is the linear plan on the a path" in text
    assert "50 % under the helper arm's" in text and "up to 3.0 mm" in text and "2.0× their net change" in text
    assert "the linear plan's peak (40.0 N) is then below ours, while it leaves the path by 5 cm" in text
