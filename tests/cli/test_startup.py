"""Start-up of the command: ``--help`` builds its parser without numerical libraries, and
``statics --home --json`` answers without numpy or Pinocchio (assembler_pin.statics.home),
with the same document as the Pinocchio statics of the home pose.

No timing is asserted here: ``assembler-pin bench --speed`` measures the start-up
(:func:`assembler_pin.bench.speed.benchmark_startup`).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import subprocess
import sys

import numpy as np
import pytest
import yaml

from assembler_pin.cli.app import main
from assembler_pin.cli.statics import _fast_home
from assembler_pin.collision.home import home_clearance
from assembler_pin.config import PayloadConfig, PlateConfig, load_config
from assembler_pin.model import AssemblerModel
from assembler_pin.model.geometry import leg_geometry
from assembler_pin.state import evaluate_state
from assembler_pin.statics import CONDITION_LIMIT
from assembler_pin.statics.home import SCREEN_CONDITION, home_anchors, home_state_document

HEAVY = ("numpy", "pinocchio", "scipy", "numba", "coal")

#: Configurations of the comparisons: the default, short and long stacks, another payload
#: and another geometry.
CONFIGS = {
    "default": {},
    "one_platform": {"platforms": 1},
    "seven_platforms": {"platforms": 7},
    "light_far_payload": {"payload": PayloadConfig(mass=0.5, offset=0.35)},
    "wide_plates": {"platforms": 3, "plate": PlateConfig(node_radius=0.18, node_spacing_deg=14.0, mass=0.35)},
}


def _config(changes: dict):
    return load_config().replace(**changes)


def _assert_same_document(fast: dict, full: dict) -> None:
    """Key by key: the same keys in the same order, numbers to 1e-9 (N, m), deflections to
    1e-5 deg (arccos of a cosine one ulp from 1 is ~1e-6 deg: both paths are 0 to rounding)."""
    assert list(fast) == list(full)
    for key, ref in full.items():
        if key in ("feasible", "violations"):
            assert fast[key] == ref, key
            continue
        if key == "clearance":  # the same two bodies, the distance to 1e-9 m
            assert fast[key]["between"] == ref["between"]
            assert abs(fast[key]["min_distance_m"] - ref["min_distance_m"]) <= 1e-9
            continue
        tol = 1e-5 if key == "deflection_deg" else 1e-9
        got, want = np.array(fast[key], dtype=float), np.array(ref, dtype=float)
        assert got.shape == want.shape, key
        np.testing.assert_allclose(got, want, rtol=0, atol=tol, err_msg=key)


@pytest.mark.parametrize("name", list(CONFIGS))
def test_home_document_equals_the_pinocchio_path(name):
    """The fast document against ``evaluate_state`` (Pinocchio's statics, leg state,
    constraint check) of the home pose, for several configurations."""
    cfg = _config(CONFIGS[name])
    am = AssemblerModel.from_config(cfg)
    fast = home_state_document(cfg, home_clearance(cfg, *home_anchors(cfg)))
    assert fast is not None
    _assert_same_document(fast, evaluate_state(am, am.home).to_dict())


def _cli_json(argv: list[str]) -> tuple[int, dict]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = main(argv)
    return status, json.loads(out.getvalue())


def test_cli_statics_home_json_is_todays_answer(tmp_path):
    """``statics --home --json`` (fast) against the full path's JSON (``--plates`` of the
    home pose), through a config file."""
    cfg = _config(CONFIGS["wide_plates"])
    path = tmp_path / "wide.yaml"
    path.write_text(yaml.safe_dump(cfg.to_dict()))
    am = AssemblerModel.from_config(cfg)
    plates = tmp_path / "home.json"
    plates.write_text(json.dumps({"plates": [m.homogeneous.tolist() for m in am.home]}))
    status, fast = _cli_json(["statics", "--home", "--json", "--config", str(path)])
    status_full, full = _cli_json(["statics", "--plates", str(plates), "--json", "--config", str(path)])
    assert status == status_full == 0
    _assert_same_document(fast, full)


def test_home_outside_a_limit_takes_the_full_path(tmp_path):
    """A payload the home pose cannot hold: no fast document; the command still lists the
    violations of the full path (exit 1: answered, the pose breaks a limit)."""
    cfg = _config({"payload": PayloadConfig(mass=400.0, offset=0.2)})
    assert home_state_document(cfg, home_clearance(cfg, *home_anchors(cfg))) is None
    path = tmp_path / "heavy.yaml"
    path.write_text(yaml.safe_dump(cfg.to_dict()))
    status, doc = _cli_json(["statics", "--home", "--json", "--config", str(path)])
    am = AssemblerModel.from_config(cfg)
    ref = evaluate_state(am, am.home)
    assert status == 1 and doc["feasible"] is False and not ref.feasible
    assert doc["violations"] == [v.to_dict() for v in ref.violations]
    assert {v["kind"] for v in doc["violations"]} == {"compression"}


def test_fast_path_only_for_the_plain_command():
    """Any option beyond --home, --json and --config (a carrier, a text answer) takes the
    full path."""
    base = {"command": "statics", "func": None, "verbose": False, "quiet": False, "config": None}
    assert not _fast_home(argparse.Namespace(**base, home=True, json=False, plates=None, carrier=None))
    assert not _fast_home(argparse.Namespace(**base, home=True, json=True, plates=None, carrier="ur5"))
    assert not _fast_home(argparse.Namespace(**base, home=False, json=True, plates="-", carrier=None))


@pytest.mark.parametrize("changes", [{"platforms": 1}, {"platforms": 6}, CONFIGS["wide_plates"]])
def test_home_anchors_are_the_geometry_rule(changes):
    cfg = _config(changes)
    bottom, top = home_anchors(cfg)
    geo = leg_geometry(cfg)
    np.testing.assert_allclose(bottom, geo.bottom_in_plate, rtol=0, atol=1e-15)
    np.testing.assert_allclose(top, geo.top_in_plate, rtol=0, atol=1e-15)


def test_screen_condition_is_below_the_statics_limit():
    assert SCREEN_CONDITION < CONDITION_LIMIT


def _modules_after(code: str) -> list[str]:
    """The heavy top-level packages a fresh interpreter has loaded after ``code``."""
    probe = f"{code}\nimport sys\nprint(sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY!r})))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1].replace("'", '"'))


def test_statics_home_json_loads_no_numerical_library():
    code = (
        "import contextlib, io\nfrom assembler_pin.cli.app import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n    assert main(['statics', '--home', '--json']) == 0"
    )
    assert _modules_after(code) == []


def test_help_loads_no_numerical_library():
    code = (
        "import contextlib, io\nfrom assembler_pin.cli.app import main\n"
        "with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):\n    main(['--help'])"
    )
    assert _modules_after(code) == []


@pytest.mark.parametrize(
    "argv",
    [
        ["statics", "--home", "--json"],
        ["-v", "solve", "--goal", "0", "0", "0.9", "0", "0", "0", "--starts", "all", "--w1", "2"],
        ["map", "--grid", "x=0:1:2,y=0,z=0.8", "--out", "m"],
        ["-q", "bench", "--speed"],
    ],
)
def test_parser_of_one_subcommand_reads_as_the_whole_parser(argv):
    """The parser ``main`` builds (the arguments of the subcommand named alone) gives the
    arguments of the complete parser, and ``--help`` lists every subcommand alike."""
    from assembler_pin.cli.app import _command_of, build_parser

    full, partial = build_parser(), build_parser(only=_command_of(argv))
    assert vars(partial.parse_args(argv)) == vars(full.parse_args(argv))
    assert build_parser(only="").format_help() == full.format_help()
    name = _command_of(argv)

    def sub_help(parser) -> str:
        return next(a for a in parser._actions if a.dest == "command").choices[name].format_help()

    assert sub_help(partial) == sub_help(full)


def test_home_document_with_a_payload_body_equals_the_pinocchio_path():
    """A payload sphere (``payload.radius``): the fast document equals the full path's, and a
    sphere too large for its bound (offset − radius − motor radius ≤ the closest pair) leaves
    the answer to the full path."""
    for radius in (0.05, 0.19):
        cfg = load_config().replace(payload=PayloadConfig(mass=5.0, offset=0.2, radius=radius))
        fast = home_state_document(cfg, home_clearance(cfg, *home_anchors(cfg)))
        full = evaluate_state(AssemblerModel.from_config(cfg), AssemblerModel.from_config(cfg).home).to_dict()
        if radius == 0.19:
            assert fast is None and full["clearance"]["min_distance_m"] > 0
        else:
            assert fast is not None
            _assert_same_document(fast, full)
