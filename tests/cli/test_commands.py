"""The assembler-pin command: export, statics JSON contract and table, errors, bench."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from assembler_pin import AssemblerModel, evaluate_state
from assembler_pin.cli import main

STATE_KEYS = [
    "plates",
    "leg_lengths",
    "forces",
    "bottom_points",
    "top_points",
    "max_abs_force",
    "mean_abs_force",
    "feasible",
    "violations",
]


def run(*args, stdin: str | None = None):
    return subprocess.run(
        [sys.executable, "-m", "assembler_pin.cli", *args], input=stdin, capture_output=True, text=True, timeout=120
    )


def test_statics_json_contract(tmp_path, am, random_poses):
    _, plates = random_poses[4]
    path = tmp_path / "in.json"
    path.write_text(json.dumps({"plates": plates.as_matrices().tolist()}))
    out = run("statics", "--plates", str(path), "--json")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert list(doc)[: len(STATE_KEYS)] == STATE_KEYS
    n = am.n
    assert np.array(doc["plates"]).shape == (n + 1, 4, 4)
    assert np.array(doc["leg_lengths"]).shape == (n, 6) and np.array(doc["forces"]).shape == (n, 6)
    assert np.array(doc["bottom_points"]).shape == (n, 6, 3)
    # the output is the input's statics, as the API computes it
    ref = evaluate_state(am, plates)
    assert np.allclose(doc["forces"], ref.forces, atol=1e-9)
    # legs joined the points it reports
    lengths = np.linalg.norm(np.array(doc["top_points"]) - np.array(doc["bottom_points"]), axis=2)
    assert np.allclose(lengths, doc["leg_lengths"], atol=1e-12)
    assert doc["max_abs_force"] == pytest.approx(np.abs(doc["forces"]).max())
    assert isinstance(doc["feasible"], bool)
    for v in doc["violations"]:
        assert set(v) == {"kind", "platform", "leg", "value", "limit"}


def test_statics_stdin_table_and_violations(capsys):
    am = AssemblerModel.from_config()
    plates = [m.homogeneous.tolist() for m in am.home]
    plates[1][2][3] += 0.12  # first platform far past its stroke
    out = run("statics", "--plates", "-", stdin=json.dumps({"plates": plates}))
    assert out.returncode == 1  # answered, "not possible": the pose breaks a constraint
    assert "feasible: NO" in out.stdout and "max_length at SP0 leg" in out.stdout
    assert main(["statics", "--home"]) == 0
    assert "feasible: yes" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("stdin", "needle"),
    [
        ("not json", "not valid JSON"),
        ('{"plates": [[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]]}', "expected 5 plate poses"),
        ('{"poses": []}', "JSON object"),
        (
            '{"plates": [[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], [[2,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]],'
            "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]],"
            "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]]}",
            "not a rotation",
        ),
        ('{"plates": [[[NaN,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]]}', "NaN is not a number JSON allows"),
    ],
)
def test_statics_bad_input_is_one_line(stdin, needle):
    out = run("statics", "--plates", "-", stdin=stdin)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0] and "Traceback" not in out.stderr


def test_unreadable_file_and_bad_config(tmp_path):
    out = run("statics", "--plates", str(tmp_path / "missing.json"))
    assert out.returncode == 2 and "cannot read" in out.stderr
    cfg = tmp_path / "c.yaml"
    cfg.write_text("leg: {min_length: 0.4}\n")
    out = run("statics", "--home", "--config", str(cfg))
    assert out.returncode == 2 and "leg.max_length" in out.stderr and len(out.stderr.strip().splitlines()) == 1


def test_export_with_config(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("platforms: 2\n")
    assert main(["export", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 0
    assert AssemblerModel.from_files(tmp_path / "o").n == 2


def test_bench_json_keys():
    out = run("bench", "--json", "--repeat", "3", "--quick")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    for key in (
        "statics_us",
        "sp_fk_us",
        "stack_fk_us",
        "q_from_plates_us",
        "initial_scenarios_ms",
        "initial_random_ms",
        "optimize_slsqp_median_s",
        "optimize_paper_median_s",
        "optimize_speedup_median",
        "solve_p50_ms",
        "solve_p95_ms",
        "solve_all_p50_ms",
        "solve_time_over_all",
    ):
        assert doc[key] > 0, key
    assert doc["solve_p95_over_p50"] == pytest.approx(doc["solve_p95_ms"] / doc["solve_p50_ms"])
    assert 0 <= doc["initial_success_rate"] <= 1
    scn = doc["optimize_scenarios"]["orientation_transition"]
    assert scn["speedup"] == pytest.approx(scn["paper_s"] / scn["slsqp_s"])
    assert scn["slsqp_objective"] <= scn["initial_objective"]


def test_cli_defaults_come_from_the_options_dataclasses():
    from assembler_pin import HelperArmOptions, OptimizeOptions
    from assembler_pin.cli import build_parser
    from assembler_pin.cli.common import optimize_options

    args = build_parser().parse_args(["solve", "--goal", "0", "0", "0.9", "0", "0", "0"])
    d, h = OptimizeOptions(), HelperArmOptions()
    # not given: None in the arguments (so that an option with no effect can be refused)
    assert (args.method, args.w1, args.w2, args.max_iterations, args.ftol) == (None,) * 5
    assert optimize_options(args) == d
    assert (args.d_step, args.max_attempts) == (h.d_step, h.max_attempts)


def test_solve_starts_option_reaches_the_solver(capsys):
    """``--starts all`` runs every start of the solver; the default is ``first`` (here the
    helper arm's and the screw start agree, so the home start does not run); a wrong value is
    one line, exit 2."""
    from assembler_pin.config.choices import SOLVE_STARTS
    from assembler_pin.solver.starts import START_MODES, STARTS

    assert SOLVE_STARTS == START_MODES and SOLVE_STARTS[0] == "first"
    goal = ["0.1", "0.0", "0.8", "0", "0", "0"]
    assert main(["solve", "--goal", *goal, "--starts", "all", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert set(doc["starts"]) == set(STARTS) and doc["success"]
    assert main(["solve", "--goal", *goal, "--json"]) == 0
    lazy = json.loads(capsys.readouterr().out)
    assert lazy["success"] and "home" not in lazy["starts"]
    assert main(["solve", "--goal", *goal, "--starts", "best"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--starts" in err and "first" in err
    assert main(["solve", "--goal", *goal, "--starts", "all", "--carrier", "ur5"]) == 2
    assert "not available with --carrier" in capsys.readouterr().err


@pytest.mark.parametrize("entry", [(0, 0, 1.0000001), (3, 0, 1e-6), (1, 1, -1.0)])
def test_a_plate_file_is_refused_by_the_librarys_own_pose_check(am, tmp_path, entry):
    """A plate file's bad matrix gets the very refusal the library gives the same poses (one
    pose check, one message), naming the same plate."""
    from assembler_pin.cli.plate_file import plates_from_file
    from assembler_pin.exceptions import CLIError, PoseError
    from assembler_pin.kinematics import plate_arrays

    plates = [np.eye(4) for _ in range(am.n + 1)]
    row, col, value = entry
    plates[2][row, col] = value
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"plates": [m.tolist() for m in plates]}))
    with pytest.raises(CLIError) as from_file:
        plates_from_file(str(path))
    with pytest.raises(PoseError) as from_library:
        plate_arrays(am, plates)
    assert str(from_file.value) == str(from_library.value)
    assert str(from_file.value).startswith("plate 2: ")
