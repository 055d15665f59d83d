"""``assembler-pin hexapod stand``: its JSON answer, its exit statuses and its refusals."""

from __future__ import annotations

import json

import numpy as np
import pytest

from assembler_pin.cli import main

KEYS = {"feasible", "forces", "foot_wrenches", "body_displacement", "stability_margin_m", "max_abs_force", "clearance"}


def _run(capsys, argv):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err.splitlines()


@pytest.mark.parametrize("feet", ["welded", "resting"])
def test_stand_json_carries_the_machine(capsys, feet):
    code, out, err = _run(capsys, ["hexapod", "stand", "--stacks", "3", "--radius", "0.4", "--feet", feet, "--json"])
    doc = json.loads(out)
    assert code == 0 and not err and KEYS <= set(doc) and doc["feasible"]
    forces, wrenches = np.array(doc["forces"]), np.array(doc["foot_wrenches"])
    assert forces.shape == (3, 4, 6) and wrenches.shape == (3, 6)
    assert doc["max_abs_force"] == np.abs(forces).max()
    # the feet carry the whole machine: the default body (20 kg) and three stacks without a tool
    assert wrenches[:, 2].sum() == pytest.approx(doc["mass"] * 9.81, rel=1e-12)
    assert doc["mass"] == pytest.approx(20.0 + 3 * (5 * 0.2 + 24 * 0.14), rel=1e-12)
    assert (doc["stability_margin_m"] is None) == (feet == "welded")
    assert doc["clearance"]["min_distance"] >= doc["clearance"]["limit"]


def test_a_body_off_its_feet_tips_and_exits_1(capsys, tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("hexapod:\n  stacks: 3\n  radius: 0.4\n  body_com: [-0.9, 0.0, 0.1]\n  body_mass: 40\n")
    code, out, _ = _run(capsys, ["hexapod", "stand", "--feet", "resting", "--config", str(cfg), "--json"])
    doc = json.loads(out)
    assert code == 1 and not doc["feasible"] and doc["stability_margin_m"] < 0
    assert any("tips" in v for v in doc["violations"])
    code, out, _ = _run(capsys, ["hexapod", "stand", "--feet", "resting", "--config", str(cfg)])
    assert code == 1 and "violation" in out and max(len(line) for line in out.splitlines()) <= 100


@pytest.mark.parametrize(
    "args",
    [
        ["--stacks", "0"],
        ["--stacks", "17"],
        ["--stacks", "two"],
        ["--radius", "nan"],
        ["--radius", "0"],
        ["--body-mass", "-1"],
        ["--body-mass", "inf"],
        ["--feet", "glued"],
        ["--scene", "/nonexistent/scene.yaml"],
    ],
)
def test_bad_input_is_refused_in_one_line(capsys, args):
    code, out, err = _run(capsys, ["hexapod", "stand", *args])
    assert code == 2 and not out and len(err) == 1


def test_an_unknown_action_and_a_bad_section_are_refused(capsys, tmp_path):
    assert _run(capsys, ["hexapod", "walk"])[0] == 2
    cfg = tmp_path / "c.yaml"
    cfg.write_text("hexapod:\n  stacks: 2.5\n")
    code, _, err = _run(capsys, ["hexapod", "stand", "--config", str(cfg)])
    assert code == 2 and len(err) == 1 and "hexapod.stacks" in err[0]


def test_bench_hexapod_figures_name_each_call_its_time_and_target():
    from assembler_pin.bench.hexapod import HEXAPOD_TARGETS_MS, benchmark_hexapod

    got = benchmark_hexapod(repeat=1)
    assert HEXAPOD_TARGETS_MS == {"six_stack_welded_stand": 500.0, "six_stack_resting_stand": 500.0}
    for key, target in HEXAPOD_TARGETS_MS.items():
        assert got[f"{key}_ok"] and got[f"{key}_target_ms"] == target
        assert 0.0 < got[f"{key}_ms"] < 1e5 and 0.0 <= got[f"{key}_cpu_ms"] < 1e5


def test_optimal_commands_stand_the_body_where_it_is_with_smaller_forces(capsys, tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("platforms: 2\nhexapod:\n  stacks: 3\n  radius: 0.4\n  body_com: [0.08, 0.03, 0.1]\n")
    base = ["hexapod", "stand", "--config", str(cfg), "--json"]
    code, out, _ = _run(capsys, base)
    own = json.loads(out)
    code_opt, out, _ = _run(capsys, [*base, "--commands", "optimal"])
    opt = json.loads(out)
    assert code == code_opt == 0 and opt["commands"] == "optimal" and own["commands"] == "own"
    assert opt["max_abs_force"] < own["max_abs_force"]
    assert np.abs(opt["body_displacement"]).max() < 1e-9 < np.abs(own["body_displacement"]).max()
    # one micrometre on every leg: a stiffness-sized figure (k = 1e6 N/m is 1 N/µm on one leg alone)
    assert 0.5 < opt["force_per_micron"] < 10.0
    heavy = tmp_path / "h.yaml"
    heavy.write_text("hexapod:\n  body_mass: 5000\n")
    code, out, _ = _run(capsys, ["hexapod", "stand", "--config", str(heavy), "--commands", "optimal", "--json"])
    doc = json.loads(out)
    assert code == 1 and doc["commands"] == "own" and any("no force-optimal commands" in v for v in doc["violations"])


def test_the_formats_page_lists_every_key_of_the_answer(capsys):
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "formats.md").read_text(encoding="utf-8")
    section = page[page.index("## `hexapod stand --json`") : page.index("## Errors in the API")]
    _, out, _ = _run(capsys, ["hexapod", "stand", "--stacks", "2", "--json"])
    for key in json.loads(out):
        assert f"`{key}`" in section, f"docs/formats.md does not describe {key}"


def test_capacity_from_the_command_line(capsys):
    """The capacity with the poses' own lengths: the machine stands there and not 1 % above it
    (the API's stand), and no more than the linear program's best distribution of every mass."""
    import assembler_pin as ap
    from assembler_pin.hexapod import configured_hexapod, stand

    code, out, _ = _run(capsys, ["hexapod", "capacity", "--stacks", "3", "--radius", "0.4", "--json"])
    doc = json.loads(out)
    assert code == 0 and "leg.max_" in doc["limit"]
    assert doc["capacity_kg"] <= doc["optimal_commands_capacity_kg"] * (1 + 1e-3)
    cfg = ap.load_config({"payload": {"mass": 0.0}, "hexapod": {"stacks": 3, "radius": 0.4}})
    am = ap.AssemblerModel.from_config(cfg)
    stacks, _, com = configured_hexapod(am)
    assert stand(am, stacks, doc["capacity_kg"], com).feasible
    assert not stand(am, stacks, 1.01 * doc["capacity_kg"], com).feasible
    assert _run(capsys, ["hexapod", "capacity", "--plot", "x.png"])[0] == 2


WALK_KEYS = {"t", "step", "phase", "body_pose", "stance", "stability_margin_m", "max_abs_force", "violations"}


def test_walk_json_reaches_the_goal_and_exits_0(capsys):
    argv = ["hexapod", "walk", "--to", "0.08", "0.0", "0.1", "--step", "0.05", "--samples", "1", "--json"]
    code, out, err = _run(capsys, argv)
    doc = json.loads(out)
    assert code == 0 and not err and doc["success"] and doc["reason"] is None
    # the longest foot travel over the step, rounded up: the default ring of six feet, 0.6 m
    angles = np.arange(6) * np.pi / 3
    feet = 0.6 * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    moved = 0.6 * np.stack([np.cos(angles + 0.1), np.sin(angles + 0.1)], axis=1) + [0.08, 0.0]
    steps = int(np.ceil(np.linalg.norm(moved - feet, axis=1).max() / 0.05))
    assert (doc["gait"], doc["feet"], doc["steps"]) == ("tripod", "resting", steps)
    samples = doc["samples"]
    assert len(samples) == 1 + steps * (2 * 3 + 1) and all(WALK_KEYS == set(s) for s in samples)
    assert all(not s["violations"] and s["stability_margin_m"] >= 0.0 for s in samples)
    assert {sum(s["stance"]) for s in samples} == {3, 6}
    assert np.all(np.diff([s["t"] for s in samples]) >= 0)
    # the body's centre of mass turned by the yaw about the feet's centre, then moved
    start = np.array(samples[0]["body_pose"][:3])
    c, s_ = np.cos(0.1), np.sin(0.1)
    goal = np.array([c * start[0] - s_ * start[1] + 0.08, s_ * start[0] + c * start[1], start[2]])
    np.testing.assert_allclose(samples[-1]["body_pose"], [*goal, 0.0, 0.0, 0.1], atol=1e-12)


def test_a_walk_that_stops_says_which_step_and_exits_1(capsys):
    argv = ["hexapod", "walk", "--to", "0.5", "0", "0", "--step", "0.5", "--samples", "1", "--json"]
    code, out, _ = _run(capsys, argv)
    doc = json.loads(out)
    assert code == 1 and not doc["success"] and doc["reason"].startswith("step 1 (")
    assert doc["samples"][-1]["violations"] and doc["reason"].endswith(doc["samples"][-1]["violations"][0])


@pytest.mark.parametrize(
    "extra",
    [
        [],
        ["--to", "0.1", "0"],
        ["--to", "0", "0", "4"],
        ["--to", "0.1", "0", "0", "--step", "0"],
        ["--to", "0.1", "0", "0", "--html", "x.html"],
    ],
)
def test_walk_refusals_are_one_line(capsys, extra):
    code, out, err = _run(capsys, ["hexapod", "walk", *extra])
    assert code == 2 and not out and len(err) <= 2 and "error" in err[-1]


def test_walk_out_writes_the_file_that_reads_back(capsys, tmp_path):
    from assembler_pin.hexapod import read_walk

    out = tmp_path / "walk.json"
    argv = [
        "hexapod",
        "walk",
        "--to",
        "0.04",
        "0",
        "0",
        "--step",
        "0.05",
        "--samples",
        "1",
        "--out",
        str(out),
        "--json",
    ]
    code, printed, _ = _run(capsys, argv)
    doc, back = json.loads(printed), read_walk(out)
    assert code == 0 and back.success and len(back.t) == len(doc["samples"])
    np.testing.assert_array_equal(back.body_pose, [s["body_pose"] for s in doc["samples"]])
    np.testing.assert_array_equal(back.stance, [s["stance"] for s in doc["samples"]])
    assert [p.name for p in tmp_path.iterdir()] == ["walk.json"]
    # every sample's forces in the file: six stacks of four platforms of six legs
    assert np.isfinite(back.forces).all() and back.forces.shape[1:] == (6, 4, 6)


def test_out_is_refused_for_stand_and_an_unwritable_out_for_walk(capsys, tmp_path):
    code, _, err = _run(capsys, ["hexapod", "stand", "--out", str(tmp_path / "x.json")])
    assert code == 2 and "--out" in err[-1]
    bad = tmp_path / "file"
    bad.write_text("")
    code, out, err = _run(capsys, ["hexapod", "walk", "--to", "0.04", "0", "0", "--out", str(bad / "w.json")])
    assert code == 2 and not out and "--out" in err[-1]
