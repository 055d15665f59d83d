"""The shipped example inputs (``examples/``): each is read by the package's strict reader,
and the cheap commands the documentation runs on them answer as the file says."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from assembler_pin import AssemblerModel, load_config
from assembler_pin.cli import main
from assembler_pin.cli.plate_file import plates_from_file
from assembler_pin.collision import read_scene
from assembler_pin.config import AssemblerConfig
from assembler_pin.kinematics import plate_arrays, taa_to_se3
from assembler_pin.motion.paths import read_waypoints
from assembler_pin.motion.trajfile import read_trajectory

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
CONFIGS = ("config.yaml", "light.yaml", "heavy.yaml")
WAYPOINTS = [[0.0, 0.0, 0.966062, 0.0, 0.0, 0.0], [0.2, 0.1, 0.85, 0.5, 0.5, 0.5], [0.3, 0.0, 0.75, 0.0, 0.6, 0.0]]


def run_json(capsys, *argv: str) -> tuple[int, dict]:
    """Exit status and the JSON answer of ``assembler-pin ARGV``."""
    status = main(list(argv))
    return status, json.loads(capsys.readouterr().out)


def test_every_example_is_documented_and_read():
    """Each file of examples/ is named in its README and parsed by the strict reader of its kind."""
    readme = (EXAMPLES / "README.md").read_text(encoding="utf-8")
    files = sorted(p.name for p in EXAMPLES.iterdir() if p.name != "README.md")
    scenes = ["truss_bay.yaml", "walk_strut.yaml"]
    assert files == sorted([*CONFIGS, "poses.json", "waypoints.json", "waypoints.csv", *scenes])
    for name in files:
        assert f"`{name}`" in readme, name
    for name in CONFIGS:
        AssemblerModel.from_config(load_config(EXAMPLES / name))
    assert len(read_scene(EXAMPLES / "truss_bay.yaml").obstacles) == 9
    strut = read_scene(EXAMPLES / "walk_strut.yaml")
    assert strut.floor_z == 0.0 and [o.name for o in strut.obstacles] == ["strut"]


def test_config_example_holds_every_key_at_its_default():
    """config.yaml names every configuration key (a key added to the package without it fails here)
    and its values are the defaults."""
    doc = yaml.safe_load((EXAMPLES / "config.yaml").read_text(encoding="utf-8"))
    default = AssemblerConfig()
    for f in dataclasses.fields(default):
        value = getattr(default, f.name)
        if dataclasses.is_dataclass(value):
            assert set(doc[f.name]) == {g.name for g in dataclasses.fields(value)}, f.name
        else:
            assert f.name in doc, f.name
    assert load_config(EXAMPLES / "config.yaml") == default


def test_sweep_designs(capsys):
    """light: 2 kg; heavy: 8 kg on 300 N legs. At home every leg carries the same share of the
    weight, so the difference of the two home forces is the 6 kg of payload spread over the six
    legs of a platform along their axes (the sign: compression)."""
    light, heavy = (load_config(EXAMPLES / n) for n in ("light.yaml", "heavy.yaml"))
    assert (light.payload.mass, heavy.payload.mass) == (2.0, 8.0)
    assert (heavy.leg.max_tension, heavy.leg.max_compression) == (300.0, 300.0)
    assert light.leg == AssemblerConfig().leg and light.platforms == heavy.platforms == 4
    answers = {}
    for name in ("light", "heavy"):
        status, doc = run_json(capsys, "statics", "--home", "--config", str(EXAMPLES / f"{name}.yaml"), "--json")
        assert status == 0 and doc["feasible"]
        answers[name] = doc
    diff = np.array(answers["heavy"]["forces"]) - np.array(answers["light"]["forces"])
    bottom, top = (np.array(answers["light"][k]) for k in ("bottom_points", "top_points"))
    axis = (top - bottom) / np.linalg.norm(top - bottom, axis=-1, keepdims=True)
    g = AssemblerConfig().gravity
    # six legs of each platform hold the extra weight 6 kg · g along -z: Σ F_i u_i,z = -6 g
    np.testing.assert_allclose((diff * axis[..., 2]).sum(axis=1), -6.0 * g, rtol=1e-9)


def test_poses_example_through_statics(am, capsys):
    """poses.json is a valid plate file; statics reads it and finds the leg lengths it was
    built from (every leg 0.275 m but SP0 legs 0-2 at 0.22 m and SP1 legs 3-5 at 0.33 m)."""
    plates = plate_arrays(am, plates_from_file(str(EXAMPLES / "poses.json")))
    assert len(plates) == am.n + 1
    status, doc = run_json(capsys, "statics", "--plates", str(EXAMPLES / "poses.json"), "--json")
    assert status == 0 and doc["feasible"] and doc["violations"] == []
    expected = np.full((am.n, 6), 0.275)
    expected[0, :3] = 0.22
    expected[1, 3:] = 0.33
    np.testing.assert_allclose(doc["leg_lengths"], expected, atol=1e-9)


@pytest.mark.parametrize("name", ["waypoints.json", "waypoints.csv"])
def test_waypoint_examples(name):
    """Both waypoint files give the same three poses (rotation vectors in radians)."""
    path = read_waypoints(EXAMPLES / name)
    assert len(path.waypoints) == len(WAYPOINTS)
    for pose, row in zip(path.waypoints, WAYPOINTS, strict=True):
        assert pose.isApprox(taa_to_se3(row), 1e-12)


def test_waypoints_start_where_to_starts(tmp_path, capsys):
    """``plan --waypoints`` starts at the home pose, as ``--to`` does: the home pose is put
    before a first waypoint that is elsewhere, the answer says so, and the trajectory's first
    row holds the home lengths (0.275 m every leg), not the first waypoint's optimized pose."""
    waypoints = tmp_path / "w.json"
    waypoints.write_text(json.dumps({"waypoints": [[0.0, 0.0, 0.962, 0, 0, 0], [0.0, 0.0, 0.958, 0, 0, 0]]}))
    out = tmp_path / "t.json"
    argv = ["-q", "plan", "--waypoints", str(waypoints), "--rate", "5", "--out", str(out), "--json"]
    status, doc = run_json(capsys, *argv)
    assert doc["start"] == "home" and doc["path_segments"] == 2 and status in (0, 1)
    first = read_trajectory(out).lengths[0]
    np.testing.assert_allclose(first, 0.275, atol=1e-9)


def test_timed_waypoints_away_from_the_start_are_refused(tmp_path, capsys):
    """Times cannot be kept when the start is put before the first waypoint: one line, exit 2."""
    waypoints = tmp_path / "w.json"
    rows = [[0.0, 0.0, 0.95, 0, 0, 0], [0.1, 0, 0.9, 0, 0, 0]]
    waypoints.write_text(json.dumps({"waypoints": rows, "times": [0, 2]}))
    assert main(["plan", "--waypoints", str(waypoints)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "home pose" in err and "0.966062" in err
