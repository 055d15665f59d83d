"""The documentation's statements about behaviour are those of the code: the configuration
keys and defaults, the trajectory format's version and fields, the time laws and the planner's
steps, the colours named in the guides, the install line and the extras, the README's word on
the paper's numbers, and no machine timings quoted in the guides."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"


def _read(rel: str) -> str:
    return (ROOT / rel).read_text(encoding="utf-8")


def test_configuration_page_shows_every_key_with_its_default():
    from assembler_pin.config import AssemblerConfig
    from assembler_pin.config.schema import StrictLoader

    (block,) = re.findall(r"```yaml\n(.*?)```", _read("docs/configuration.md"), flags=re.S)
    assert yaml.load(block, Loader=StrictLoader) == AssemblerConfig().to_dict()


def test_formats_page_documents_the_trajectory_version_the_code_writes():
    from assembler_pin.motion import trajfile

    page = _read("docs/formats.md")
    section = page[page.index("## Trajectory files") : page.index("## Waypoint files")]
    assert f"format v{trajfile.VERSION})" in section.splitlines()[0]
    assert f'"version": {trajfile.VERSION}' in section
    assert f"# assembler-pin trajectory v{trajfile.VERSION}`" in section
    for key in sorted(trajfile._META_KEYS):
        assert f"`{key}`" in section, f"meta key {key} not on the formats page"
    for kind in trajfile.MARGIN_KINDS:
        assert f"`margin_{kind}`" in section, f"column margin_{kind} not on the formats page"
    for law in trajfile.TIME_LAW_NAMES:
        assert f"`{law}`" in section
    assert "refused" in section and f"v{trajfile.VERSION - 1}" in section


def _plan_option(flag: str):
    from assembler_pin.cli.app import build_parser

    plan = build_parser("plan")._subparsers._group_actions[0].choices["plan"]  # type: ignore[union-attr]
    (action,) = [a for a in plan._actions if flag in a.option_strings]
    return action


def test_motion_guide_names_the_time_laws_and_the_default():
    page = _read("docs/guides/motion.md")
    law = _plan_option("--time-law")
    assert f"`plan --time-law {'|'.join(law.choices)}` (default `{law.default}`)" in page
    for gone in ("not time-optimal", "Not yet", "not built"):
        assert gone not in page, f"the motion guide still says {gone!r}"
    assert "`assembler-pin walk`" in page  # the inchworm step exists


def test_motion_guide_states_the_planner_defaults():
    import math

    from assembler_pin.motion.planner import PlanOptions

    d = PlanOptions()
    page = _read("docs/guides/motion.md")
    mm, deg = f"{1e3 * d.position_step:g} mm", f"{math.degrees(d.rotation_step):g}°"
    assert f"Every sample ({mm} / {deg} apart by default)" in page
    assert f"no leg moves more than {1e3 * d.max_leg_step:g} mm from the previous sample" in page


def test_viewer_guide_names_the_palette_colours_of_the_pose_views():
    from assembler_pin.common import palette

    table = palette.__doc__ or ""
    colour = {
        "initial": re.search(r"^initial condition / ghost\s+(\w+)", table, flags=re.M),
        "optimized": re.search(r"^optimized pose\s+(\w+)", table, flags=re.M),
        "the helper arm": re.search(r"^helper arm\s+(\w+)", table, flags=re.M),
    }
    page = " ".join(_read("docs/guides/viewer.md").split())
    for what, found in colour.items():
        assert found, what
        assert f"{what} {found.group(1)}" in page, f"the viewer guide does not draw {what} {found.group(1)}"


@pytest.mark.parametrize("page", sorted((DOCS / "guides").glob("*.md")), ids=lambda p: p.name)
def test_guides_quote_no_machine_timings(page):
    """Timings depend on the machine and go stale: the guides point at the Benchmarks page."""
    text = " ".join(page.read_text(encoding="utf-8").split())
    for phrase in (r"wall time", r"\b\d+-core\b", r"\bminutes? to\b", r"takes (about )?[\d.–]+ ?(s|ms|min)\b"):
        assert not re.search(phrase, text), f"{page.name} quotes a timing ({phrase})"


def test_readme_install_line_lists_the_dependencies_and_every_extra():
    project = _read("pyproject.toml")
    deps = re.search(r"^dependencies = \[(.*?)^\]", project, flags=re.S | re.M)
    assert deps
    names = [re.match(r"[A-Za-z0-9_.-]+", d).group(0) for d in re.findall(r'"([^"]+)"', deps.group(1))]  # type: ignore[union-attr]
    extras = re.search(r"^\[project.optional-dependencies\]\n(.*?)^\[", project, flags=re.S | re.M)
    assert extras
    readme = _read("README.md")
    install = " ".join(readme[readme.index("## Install") : readme.index("## In Python")].split())
    named = {"pin": "Pinocchio (`pin`)", "pyyaml": "PyYAML"}
    for name in names:
        assert named.get(name, name) in install, f"the README's install line omits {name}"
    for extra in re.findall(r"^(\w+) = \[", extras.group(1), flags=re.M):
        assert f"`.[{extra}]`" in install, f"the README's install line omits the extra [{extra}]"


def test_readme_says_how_far_our_optima_are_from_the_papers():
    """The ratio range in the README is the one of the generated Results table."""
    row = r"^\| \w+ \| [^|]+ \| ([\d.]+) \(SP[^|]+\| \d+% \| [\d.]+ → ([\d.]+) \("
    rows = re.findall(row, _read("docs/results.md"), flags=re.M)
    assert len(rows) == 5
    ratios = [float(ours) / float(paper) for ours, paper in rows]
    said = f"{min(ratios):.2f}–{max(ratios):.1f}×"
    readme = _read("README.md")
    assert said in readme, f"the README should say our optima are {said} the paper's"
    assert readme.index(said) < readme.index("## Install"), "said near the top"


def test_the_home_page_lists_every_guide_and_every_extra():
    index = _read("docs/index.md")
    for guide in sorted((DOCS / "guides").glob("*.md")):
        assert f"(guides/{guide.name})" in index, f"docs/index.md does not list guides/{guide.name}"
    extras = re.search(r"^\[project.optional-dependencies\]\n(.*?)^\[", _read("pyproject.toml"), flags=re.S | re.M)
    assert extras
    for extra in re.findall(r"^(\w+) = \[", extras.group(1), flags=re.M):
        assert f"`.[{extra}]`" in index, f"docs/index.md omits the extra [{extra}]"


def test_the_map_picture_is_drawn_as_map_png_draws_today():
    """docs/map.png is the output of the command in the comment above it: its size is the
    figure's of :func:`~assembler_pin.maps.pictures.map_heatmaps` at 150 dpi, and its caption
    names the five panels."""
    import struct

    page = _read("docs/guides/maps.md")
    command = re.search(r"<!-- generated by: (assembler-pin map [^>]*--png docs/map.png) -->\n!\[([^\]]*)\]", page)
    assert command, "docs/guides/maps.md: the map picture's generating command is missing"
    for panel in ("clearance", "max|F|", "capacity", "sag", "stiffness", "reachability"):
        assert panel in command.group(2)
    with (DOCS / "map.png").open("rb") as png:
        width, height = struct.unpack(">II", png.read(24)[16:24])
    from assembler_pin.maps.pictures import MAP_FIGSIZE

    assert (width, height) == (round(150 * MAP_FIGSIZE[0]), round(150 * MAP_FIGSIZE[1])), (width, height)


def test_solve_says_what_it_returns():
    """``ap.solve``'s docstring has a Returns section, and every attribute it names is one of
    the result's (or of the states it holds)."""
    import dataclasses
    import inspect

    import assembler_pin as ap
    from assembler_pin.solver.pipeline import SolveResult
    from assembler_pin.state import StackState

    doc = inspect.getdoc(ap.solve) or ""
    assert "\nReturns:\n" in doc
    returns = doc.split("\nReturns:\n")[1].split("\n\n")[0]
    named = set(re.findall(r"``\.?(\w+)``", returns)) - {"False", "True"}
    assert {"success", "message", "optimized", "initial", "best", "optimal"} <= named
    for kind in (SolveResult, StackState):
        fields = {f.name for f in dataclasses.fields(kind)} | set(dir(kind))
        named -= fields
    assert not named, f"ap.solve's Returns names {sorted(named)}, which its result does not have"


def test_formats_page_lists_every_key_and_violation_kind_statics_prints(tmp_path, capsys):
    """``statics --json`` of a pose that meets an obstacle: every key it prints (the
    ``clearance`` object's too) and the ``collision`` violation, with its keys, are on the
    formats page."""
    import json

    from assembler_pin.cli import main

    scene = tmp_path / "post.yaml"
    scene.write_text(yaml.safe_dump({"obstacles": [{"sphere": {"radius": 0.05, "center": [0.0, 0.0, 0.5]}}]}))
    assert main(["statics", "--home", "--json", "--scene", str(scene)]) == 1
    doc = json.loads(capsys.readouterr().out)
    page = _read("docs/formats.md")
    section = page.split("## `statics --json`")[1].split("\n## ")[0]
    for key in [*doc, *doc["clearance"]]:
        assert f"`{key}`" in section, key
    (collision,) = [v for v in doc["violations"] if v["kind"] == "collision"]
    kinds = section.split("**Violation kinds**")[1]
    assert "`collision`" in kinds and all(f"`{key}`" in section for key in collision)


def test_collisions_guide_quotes_what_the_program_prints(tmp_path, capsys):
    """The collision lines the guide quotes are those ``statics --scene`` prints for its
    example, and the one-line message the solver gives for the same violation."""
    from assembler_pin import AssemblerModel, evaluate_state
    from assembler_pin.cli import main
    from assembler_pin.collision.scene import scene_from_dict
    from assembler_pin.common.messages import describe

    post = {"obstacles": [{"sphere": {"radius": 0.05, "center": [0, 0, 0.5]}}]}
    page = _read("docs/guides/collisions.md")
    assert "`obstacles: [{sphere: {radius: 0.05, center: [0, 0, 0.5]}}]`" in page
    scene = tmp_path / "post.yaml"
    scene.write_text(yaml.safe_dump(post))
    assert main(["statics", "--home", "--scene", str(scene)]) == 1
    printed = capsys.readouterr().out.rstrip("\n").splitlines()[-3:]
    assert "```text\n" + "\n".join(printed) + "\n```" in page
    am = AssemblerModel.from_config()
    (v,) = [v for v in evaluate_state(am, am.home, scene=scene_from_dict(post)).violations if v.kind == "collision"]
    assert f"`{describe(v)}`" in " ".join(page.split())


def test_the_api_index_breaks_module_paths_only_after_a_dot():
    """The API index's "defined in" links: a break opportunity after each dot and the site's
    stylesheet forbids any other (identifiers are never broken mid-word)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("hooks", DOCS / "hooks.py")
    hooks = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hooks)
    assert hooks.dotted_breaks("assembler_pin.solver.pipeline.solve") == (
        "assembler_pin.<wbr>solver.<wbr>pipeline.<wbr>solve"
    )
    assert "stylesheets/extra.css" in yaml.safe_load(_read("mkdocs.yml").split("\nplugins:")[0])["extra_css"]
    css = _read("docs/stylesheets/extra.css")
    assert ".md-typeset td a code" in css and "word-break: normal" in css and "overflow-wrap: normal" in css


def test_the_truss_guides_scaling_table_is_what_the_command_computes():
    """docs/guides/truss.md's table and sentence of ``stiffness --scaling``: every figure is
    the table's (4 significant digits), the first n that buckles and the n = 46 figures too."""
    from assembler_pin.compliance.scaling import stiffness_scaling

    def g(x: float) -> str:
        return re.sub(r"e\+?0*(\d)", r"e\1", f"{x:.4g}")

    table = stiffness_scaling(max_platforms=64)
    page = _read("docs/guides/truss.md").split("## How stiffness scales")[1].split("\n## ")[0]
    rows = re.findall(r"^\| (\d+) \| (.+) \|$", page, flags=re.M)
    assert [int(n) for n, _ in rows] == [1, 4, 8, 16, 64]
    for n, cells in rows:
        k = int(n) - 1
        shown = [c.strip() for c in cells.split("|")]
        if table.stable[k]:
            sag_mm = 1e3 * table.sag[k]
            want = [g(table.lateral[k]), g(table.axial[k]), g(table.torsional[k]), g(sag_mm)]
        else:
            want = ["buckles", "—", "—", "—"]
        assert shown == [*want, g(table.elastic["lateral"][k])], n
    first = table.first_unstable
    words = " ".join(page.split())
    assert f"buckles under its own weight from n = {first}" in words
    before = first - 2  # the index of n = first - 1
    assert f"at n = {first - 1} the lateral stiffness is {table.lateral[before]:.2g} N/m" in words
    assert f"the sag {1e3 * table.sag[before]:.2g} mm" in words


def test_formats_page_documents_the_walk_file_the_code_writes():
    from assembler_pin.hexapod import walkfile

    page = _read("docs/formats.md")
    section = page[page.index("## Walk files") : page.index("## Errors in the API")]
    assert f"format v{walkfile.VERSION})" in section.splitlines()[0]
    assert f'"format": "{walkfile.FORMAT}", "version": {walkfile.VERSION}' in section
    for key in (*walkfile._TOP, *walkfile._SAMPLE):
        assert f"`{key}`" in section or f'"{key}"' in section, f"walk file key {key} not on the formats page"
    for phase in walkfile.PHASES:
        assert f"`{phase}`" in section
    assert "more\nthan 1 + 100 × 49 × 50 samples" in section and walkfile.MAX_FILE_SAMPLES == 1 + 100 * 49 * 50
