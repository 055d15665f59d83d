"""The README and the documentation pages say what the code does.

- the README's Python example and the pages' Python blocks run as written;
- the commands the pages show run (the cheap ones in the fast tier, the ones of a few
  seconds marked slow), and every other command is listed here with the reason it is not;
- the generated pages (CLI reference, limits) are those the code generates today;
- the README keeps its shape: the picture, the two commands, at most 10 KB, the Python
  version and the licence of pyproject.toml; its links point at files that exist.
"""

from __future__ import annotations

import importlib.util
import io
import json
import re
import shlex
import subprocess
import sys
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
PAGES = [README, *sorted(DOCS.rglob("*.md"))]
_PROJECT = (ROOT / "pyproject.toml").read_text(encoding="utf-8")


def _project(key: str) -> str:
    """A string value of pyproject.toml's [project] table (tomllib is Python 3.11+ only)."""
    found = re.search(rf'^{re.escape(key)} = (?:{{ text = )?"([^"]+)"', _PROJECT, flags=re.M)
    assert found, f"pyproject.toml has no {key}"
    return found.group(1)


def _blocks(path: Path, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", path.read_text(encoding="utf-8"), flags=re.S)


def _page_id(path: Path) -> str:
    return str(path.relative_to(ROOT))


# --- the README -------------------------------------------------------------------------


def test_readme_python_example_runs_and_its_numbers_hold():
    (code,) = _blocks(README, "python")
    assert len(code.strip().splitlines()) <= 15, "the README's example stays within 15 lines"
    ns: dict = {}
    exec(compile(code, str(README), "exec"), ns)
    am, state, statics, result = ns["am"], ns["state"], ns["statics"], ns["result"]
    cfg = am.config
    # the home pose is symmetric: every leg of a platform carries the same force, in compression
    assert state.forces.shape == (4, 6)
    assert np.allclose(state.forces, state.forces[:, :1], atol=1e-9) and np.all(state.forces < 0)
    # the base mount carries the whole weight, counted from the configuration alone
    legs = cfg.platforms * 6 * (cfg.leg.motor_mass + cfg.leg.shaft_mass)
    weight = cfg.gravity * ((cfg.platforms + 1) * cfg.plate.mass + legs + cfg.payload.mass)
    assert statics.base_wrench[2] == pytest.approx(weight, rel=1e-9)
    # the goal is solved, and optimizing never raises the largest force
    assert result.success
    assert result.optimized.max_abs_force <= result.initial.max_abs_force + 1e-9
    np.testing.assert_allclose(result.optimized.plates.as_se3()[-1].translation, [0.3, 0.0, 0.75], atol=1e-9)


def test_readme_opens_with_the_two_setup_commands():
    first_blocks = _blocks(README, "bash")[:2]
    assert first_blocks[0].strip() == "pip install -e . && assembler-pin reproduce --out reproduce"
    assert first_blocks[1].strip() == 'pip install -e ".[test]" && python -m pytest'


def test_readme_picture_is_the_reproduce_figure():
    text = README.read_text(encoding="utf-8")
    pictures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert pictures and pictures[0] == "docs/vertical_lift_views.png"
    assert (README.parent / pictures[0]).stat().st_size > 50_000
    assert "reproduce/vertical_lift_views.png" in text  # the command that makes it
    assert text.index("![") < text.index("```bash")  # the picture comes first


def test_readme_is_short_and_states_python_and_licence():
    text = README.read_text(encoding="utf-8")
    assert len(text.encode("utf-8")) <= 10_000
    low = _project("requires-python").removeprefix(">=")
    assert f"Python ≥ {low}" in text and "tested on 3.11" in text
    assert _project("license") in text


def test_readme_and_pages_link_to_files_that_exist():
    """The README's relative links (GitHub renders them; mkdocs checks only the pages)."""
    text = README.read_text(encoding="utf-8")
    targets = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", text)
    local = [t for t in targets if not re.match(r"[a-z]+://", t)]
    assert local, "the README links to its documentation"
    missing = [t for t in local if not (ROOT / t).exists()]
    assert not missing, f"README links to missing files: {missing}"


def test_citation_matches_the_package():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert cff["version"] == _project("version")
    assert cff["license"] == _project("license")
    paper = cff["preferred-citation"]
    assert paper["title"].startswith("Metrics and Optimization of Internal Poses")
    assert [a["family-names"] for a in paper["authors"]] == ["Chapin", "Komendera"]


# --- generated pages --------------------------------------------------------------------


def _generator(name: str):
    spec = importlib.util.spec_from_file_location(name, DOCS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.skipif(sys.version_info[:2] != (3, 11), reason="argparse's help layout differs between Python versions")
def test_cli_page_is_generated_from_the_parser():
    gen = _generator("gen_cli")
    stale = "docs/cli.md is stale: run python docs/gen_cli.py"
    assert gen.PAGE.read_text(encoding="utf-8") == gen.render(), stale
    from assembler_pin.cli import build_parser

    for name in gen.subcommand_parsers(build_parser()):
        assert f"## `assembler-pin {name}`" in gen.PAGE.read_text(encoding="utf-8")


def test_limits_page_is_generated_from_the_bounds_table():
    gen = _generator("gen_limits")
    stale = "docs/limits.md is stale: run python docs/gen_limits.py"
    assert gen.PAGE.read_text(encoding="utf-8") == gen.render(), stale
    from assembler_pin.config.bounds import BOUNDS

    assert all(f"`{key}`" in gen.PAGE.read_text(encoding="utf-8") for key in BOUNDS)


# --- the pages' Python blocks -----------------------------------------------------------

SLOW_PYTHON = {"docs/results.md": "optimizes the five scenarios twice (several seconds)"}


def _python_cases():
    for page in PAGES[1:]:
        for k, code in enumerate(_blocks(page, "python")):
            marks = [pytest.mark.slow] if _page_id(page) in SLOW_PYTHON else []
            yield pytest.param(page, code, id=f"{_page_id(page)}[{k}]", marks=marks)


@pytest.mark.parametrize(("page", "code"), list(_python_cases()))
def test_page_python_block_runs(page, code, monkeypatch):
    monkeypatch.chdir(ROOT)  # the measuring snippet reads the package's files
    ns: dict = {}
    with redirect_stdout(io.StringIO()) as out:
        exec(compile(code, str(page), "exec"), ns)
    assert out.getvalue().strip(), f"a Python block of {_page_id(page)} prints its result"
    if "relaxed" in ns:  # optimizing on with relaxed limits never raises max|F|
        assert ns["more"].max_abs_force <= ns["ours"].max_abs_force + 1e-9


# --- the pages' commands ----------------------------------------------------------------

RUN, SLOW = "run", "slow"
#: (pattern matched against the start of a command line, what to do, why when not run)
COMMANDS: list[tuple[str, str, str]] = [
    (r"assembler-pin statics --home( --json > home\.json)?$", RUN, ""),
    (r"assembler-pin solve --goal [-\d. ]+( --no-optimize --json)?$", RUN, ""),
    (r"assembler-pin export --mjcf --out urdf$", RUN, ""),
    (r"wc -c README\.md$", RUN, ""),
    (r"assembler-pin stiffness --home( --compensated --json)?$", RUN, ""),
    (r"assembler-pin support --home( --json)?$", RUN, ""),
    (r"assembler-pin statics --home --support (ee|both) --json$", RUN, ""),
    (r"assembler-pin view --home (--loaded( --exaggerate [\d.]+)?|--ellipsoid) --html \S+$", SLOW, ""),
    (r"assembler-pin view --scenario \w+ --loaded --ellipsoid --ellipsoid-force [\d.]+ --html \S+$", SLOW, ""),
    (r"assembler-pin solve --goal [-\d. ]+ --objective sag$", SLOW, ""),
    (r"grep -rc # fmt: skip assembler_pin", RUN, ""),
    (r"assembler-pin view (--home|--scenario \w+|--goal [-\d. ]+)( --force-scale \w+)? --html \S+$", SLOW, ""),
    (r"assembler-pin solve --goal [-\d. ]+ --capacity$", SLOW, ""),
    (r"assembler-pin statics --home --carrier \w+( --mount [-\d. ]+)?$", SLOW, ""),
    (r"assembler-pin solve --goal [-\d. ]+ --carrier ur10 --fixed-carrier", SLOW, ""),
    (r"assembler-pin view --home --carrier", SLOW, ""),
    (r"assembler-pin simulate --home$", SLOW, ""),
    (r"assembler-pin statics --home --json > home\.json && assembler-pin simulate --plates", SLOW, ""),
    (r"assembler-pin reproduce --scenario", SLOW, ""),
    (r"assembler-pin bench --quick$", SLOW, ""),
    (r"assembler-pin plan --from", SLOW, ""),
    (
        r"printf platforms: 16\\n > p16\.yaml && assembler-pin solve --config p16\.yaml --goal [-\d. ]+ --method auto",
        SLOW,
        "",
    ),
    (r"assembler-pin hexapod (stand|capacity)( --\S+ \S+)*( --json)?$", RUN, ""),
    (r"assembler-pin hexapod walk --to [-\d.]+ [-\d.]+ [-\d.]+( --\S+ \S+)*( --json)?$", RUN, ""),
    (r"pip install", "", "installs packages"),
    (r"python -c from assembler_pin .*benchmark_wide_search", "", "300 starts a goal, ~10 s each (test_bench runs 3)"),
    (r"assembler-pin bench --(truss|speed|platforms-sweep)$", "", "minutes of timings"),
    (r"assembler-pin bench --targets( --json| --map-cells (0|200))?$", "", "minutes of timings (test_bench runs rows)"),
    (r"python -m pytest", "", "the test suite itself"),
    (r"mkdocs build", "", "builds this site (CI runs it)"),
    (r"mypy ", "", "a type check of the whole package (CI runs it)"),
    (r"python -m mujoco\.viewer", "", "needs a display"),
    (r"assembler-pin view --home( --host \S+)?$", "", "serves a live page until Ctrl-C (test_viewer.py runs one)"),
    (r"assembler-pin view --plates examples/poses\.json --html \S+$", SLOW, ""),
    (
        r"assembler-pin view --(home|scenario translation) --scene examples/truss_bay\.yaml --html \S+$",
        "",
        "a page with the scene and its closest pair (viz/test_scene_view.py draws both and checks them)",
    ),
    (
        r"assembler-pin reproduce --out",
        "",
        "every scenario with its random-pose references (core/test_reproduce.py)",
    ),
    (
        r"assembler-pin reproduce( --markdown)?$",
        "",
        "every scenario with its random-pose references (core/test_results_page.py, in-process)",
    ),
    (r"python docs/gen_results\.py( --check)?$", "", "rewrites docs pages (core/test_results_page.py checks them)"),
    (r"assembler-pin bench( --json --repeat \d+)?$", "", "the full benchmark takes minutes"),
    (r"assembler-pin map ", "", "a Dask map of many cells takes minutes (tests/maps/test_maps.py runs small ones)"),
    (r"assembler-pin solve --goal [-\d. ]+ --carrier ur10$", "", "searches the carrier's joints (test_carrier.py)"),
    (r"assembler-pin plan --to", "", "plans a motion of 50-130 samples (tests/motion/test_motion.py)"),
    (r"assembler-pin plan --waypoints examples/waypoints\.json", "", "plans three waypoints"),
    (r"assembler-pin walk ", "", "plans a walk of several steps, minutes (tests/walk/test_walk.py runs one)"),
    (r"assembler-pin simulate --trajectory", "", "needs a planned trajectory (tests/simulate/test_mujoco.py runs one)"),
]


def _command_lines():
    """(page, the command as words, the line as written) for each command line of a page."""
    seen: set[str] = set()
    for page in PAGES:
        for block in _blocks(page, "bash"):
            for line in block.splitlines():
                words = " ".join(shlex.split(line, comments=True))
                if words and words not in seen:
                    seen.add(words)
                    yield page, words, line


def _rule(cmd: str) -> tuple[str, str] | None:
    for pattern, action, why in COMMANDS:
        if re.match(pattern, cmd):
            return action, why
    return None


def test_every_command_of_the_pages_is_run_or_has_a_reason():
    unclassified = [f"{_page_id(p)}: {c}" for p, c, _ in _command_lines() if _rule(c) is None]
    assert not unclassified, "classify these commands in tests/test_readme.py COMMANDS:\n" + "\n".join(unclassified)


def _run_line(line: str, cwd: Path) -> None:
    """One command line of a page, the ``assembler-pin`` parts in this process."""
    from assembler_pin.cli import main

    for part in line.split(" && "):
        tokens = shlex.split(part, comments=True)
        target = None
        if ">" in tokens:
            target, tokens = tokens[tokens.index(">") + 1], tokens[: tokens.index(">")]
        if tokens[0] != "assembler-pin":
            subprocess.run(part, shell=True, check=True, cwd=cwd, capture_output=True, timeout=60)
            continue
        with redirect_stdout(io.StringIO()) as out:
            status = main(tokens[1:])
        assert status == 0, f"{part!r} exited with {status}"
        assert out.getvalue().strip() or "--out" in tokens or "--html" in tokens, f"{part!r} printed nothing"
        if target:
            (cwd / target).write_text(out.getvalue(), encoding="utf-8")
            if "--json" in tokens:
                json.loads(out.getvalue())


def _runnable():
    for page, words, line in _command_lines():
        rule = _rule(words)
        if rule and rule[0] in (RUN, SLOW):
            marks = [pytest.mark.slow] if rule[0] == SLOW else []
            yield pytest.param(line, id=f"{_page_id(page)}: {words}", marks=marks)


@pytest.mark.parametrize("line", list(_runnable()))
def test_page_command_runs(line, tmp_path, monkeypatch):
    for name in ("README.md", "assembler_pin", "examples"):  # what the commands read
        (tmp_path / name).symlink_to(ROOT / name)
    monkeypatch.chdir(tmp_path)
    _run_line(line, tmp_path)


def test_ratios_table_is_generated_from_the_bench():
    """The ratios table of docs/benchmarks.md is the bench's own rendering of the figures it
    stored (docs/ratios.json, written by ``python docs/gen_ratios.py``), with every row."""
    import json

    gen = _generator("gen_ratios")
    page = gen.PAGE.read_text(encoding="utf-8")
    doc = json.loads(gen.FIGURES.read_text(encoding="utf-8"))
    assert gen.render(page, doc) == page, "docs/benchmarks.md is stale: run python docs/gen_ratios.py"
    from assembler_pin.bench.ratios import RATIO_TARGETS

    assert all(what in page for _, what, *_ in RATIO_TARGETS)
