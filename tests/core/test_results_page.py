"""docs/results.md holds what ``assembler-pin reproduce --markdown`` prints today.

The block between the page's markers is regenerated in-process from one run of the five
scenarios (docs/gen_results.py, the function the command prints) and compared with the page;
so are the vertical-lift forces of the picture's caption in README.md and docs/index.md.

The comparison is exact, with one exception: the figures of the reference columns (the
optimum against random valid poses) may differ by one in their last digit. Those poses are
random plates repaired onto the leg limits by a least-squares solve whose end point is any
zero of the violation, so it moves with the last bits of the arithmetic: between OpenBLAS's
Haswell and SkylakeX kernels the median of one scenario's poses moves by 0.1 % (47.56 % /
47.63 % against it), within 0.1 percentage point of the rounding edge. Every other figure
agrees to 1e-8 relative between kernels and is printed to 0.1 N or 1 %.
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
STALE = (
    "docs/results.md is stale: run python docs/gen_results.py (it writes the output of "
    "assembler-pin reproduce --markdown between the markers)"
)
#: Where a figure may move by one in its last digit: the reference column and its range.
LOOSE = ("vs median / worst random valid pose", "below the median random valid pose")
NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?%?")


def _generator():
    spec = importlib.util.spec_from_file_location("gen_results", ROOT / "docs" / "gen_results.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


gen = _generator()


@pytest.fixture(scope="module")
def run():
    """The default model and the five scenarios, solved once for every test here."""
    return gen.run()


def _block(text: str) -> str:
    return text[text.index(gen.BEGIN) + len(gen.BEGIN) : text.index(gen.END)].strip("\n")


def _loose_cells(lines: list[str]) -> set[tuple[int, int]]:
    """(line, cell) of the figures allowed to differ in their last digit."""
    loose: set[tuple[int, int]] = set()
    column = None
    for k, line in enumerate(lines):
        cells = line.split(" | ")
        if line.startswith("| scenario |"):
            column = next((c for c, cell in enumerate(cells) if cell == LOOSE[0]), None)
        elif not line.startswith("|"):
            column = None
        elif column is not None:
            loose.add((k, column))
        if LOOSE[1] in line:
            loose.update((k, c) for c in range(len(cells)))
    return loose


def differences(page: str, now: str) -> list[str]:
    """Lines of ``page`` that differ from ``now`` by more than the last digit of a loose figure."""
    a, b = page.splitlines(), now.splitlines()
    if len(a) != len(b):
        return [f"{len(a)} lines on the page, {len(b)} printed"]
    loose = _loose_cells(b)
    out = []
    for k, (x, y) in enumerate(zip(a, b, strict=True)):
        cx, cy = x.split(" | "), y.split(" | ")
        same = len(cx) == len(cy) and all(
            p == q or ((k, c) in loose and _within_last_digit(p, q))
            for c, (p, q) in enumerate(zip(cx, cy, strict=True))
        )
        if not same:
            out.append(f"page:    {x}\nprinted: {y}")
    return out


def _within_last_digit(p: str, q: str) -> bool:
    """The same text but for percentages each within one unit of its last digit (a count,
    such as the number of poses, is exact)."""
    if NUMBER.sub("#", p) != NUMBER.sub("#", q):
        return False
    for u, v in zip(NUMBER.findall(p), NUMBER.findall(q), strict=True):
        if u == v:
            continue
        if not (u.endswith("%") and v.endswith("%")):
            return False
        step = 10.0 ** -len(u.rstrip("%").partition(".")[2])
        if abs(float(u.rstrip("%")) - float(v.rstrip("%"))) > step * 1.001:
            return False
    return True


def test_results_page_is_what_reproduce_markdown_prints(run):
    am, outcomes = run
    from assembler_pin.reproduce import results_markdown

    now = results_markdown(am, outcomes)
    page = _block(gen.RESULTS.read_text(encoding="utf-8"))
    if page != now:
        problems = differences(page, now)
        assert not problems, STALE + "\n" + "\n".join(problems)


def test_picture_captions_quote_the_pictured_scenario(run):
    _, outcomes = run
    for path in gen.CAPTIONED:
        text = path.read_text(encoding="utf-8")
        assert text == gen.with_caption(text, outcomes), f"{path.name}: the caption's forces are stale: {STALE}"


def test_the_command_prints_the_block(run, monkeypatch, capsys):
    """``reproduce --markdown`` prints :func:`results_markdown` and nothing else."""
    import assembler_pin.reproduce as reproduce
    from assembler_pin.cli import main

    am, outcomes = run
    monkeypatch.setattr(reproduce, "run_scenarios", lambda *args, **kwargs: outcomes)
    assert main(["-q", "reproduce", "--markdown"]) == 0
    assert capsys.readouterr().out == reproduce.results_markdown(am, outcomes) + "\n"


def test_the_comparison_allows_only_the_reference_figures_to_move():
    page = "\n".join(
        [
            "| scenario | initial max\\|F\\| [N] | vs median / worst random valid pose | gap to multistart |",
            "|---|---|---|---|",
            "| a | 102.1 (SP0 leg 4) | 48% / 54% (n = 8) | +0.0% |",
            "",
            "- The optimum is below the median random valid pose for the goal by 26–48%, below the worst by 32–58%.",
        ]
    )
    assert differences(page, page) == []
    assert differences(page, page.replace("48% / 54%", "47% / 55%").replace("26–48%", "26–47%")) == []
    assert differences(page, page.replace("48% / 54%", "46% / 54%"))  # two points is stale
    assert differences(page, page.replace("102.1", "102.2"))  # any other figure exactly
    assert differences(page, page.replace("+0.0%", "+0.1%"))
    assert differences(page, page.replace("(n = 8)", "(n = 7)"))  # a count is exact
    assert differences(page, page.replace("SP0 leg 4", "SP0 leg 5"))
