"""Results that chain: ``solve --out`` and ``solve --json`` are plate files for the commands
that read ``--plates``; the pose read back is held to the design's own free-body forces and
constraints (tests/checks.py), not to the package's statics."""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pinocchio as pin
from checks import design_forces, design_problems

import assembler_pin as ap
from assembler_pin.cli import main

GOAL = ["0.3", "0", "0.75", "0", "1.5708", "0"]
UNREACHABLE = ["0", "0", "3", "0", "0", "0"]


def run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    return status, out.getvalue(), err.getvalue()


def statics_of(path) -> dict:
    status, out, err = run(["statics", "--plates", str(path), "--json"])
    assert status == 0, err
    return json.loads(out)


def test_solve_out_is_a_plate_file_of_the_solved_pose(am, tmp_path):
    path = tmp_path / "pose.json"
    status, out, _ = run(["solve", "--goal", *GOAL, "--no-optimize", "--out", str(path), "--json"])
    answer = json.loads(out)
    assert status == 0 and answer["success"] and answer["out"] == str(path)
    doc = statics_of(path)
    plates = ap.kinematics.plate_arrays(am, [np.array(m) for m in doc["plates"]])
    goal = ap.kinematics.taa_to_se3([float(x) for x in GOAL])
    assert design_problems(am.config, plates, goal, tol=1e-6) == []
    np.testing.assert_allclose(doc["forces"], design_forces(am.config, plates), atol=1e-8)
    np.testing.assert_allclose(doc["plates"], answer["initial"]["plates"], atol=0)


def test_solve_json_is_accepted_by_plates(am, tmp_path):
    status, out, _ = run(["solve", "--goal", *GOAL, "--json"])
    assert status == 0
    path = tmp_path / "answer.json"
    path.write_text(out)
    doc = statics_of(path)
    answer = json.loads(out)
    np.testing.assert_allclose(doc["plates"], answer["optimized"]["plates"], atol=0)
    plates = ap.kinematics.plate_arrays(am, [np.array(m) for m in doc["plates"]])
    np.testing.assert_allclose(doc["forces"], design_forces(am.config, plates), atol=1e-8)
    ee = pin.SE3(np.array(doc["plates"][-1]))
    assert np.linalg.norm(ee.translation - np.array([0.3, 0.0, 0.75])) < 1e-6


def test_an_unsolved_goal_writes_no_file_and_its_answer_is_no_plate_file(tmp_path):
    path = tmp_path / "pose.json"
    status, out, _ = run(["solve", "--goal", *UNREACHABLE, "--no-optimize", "--out", str(path), "--json"])
    assert status == 1 and not path.exists() and json.loads(out)["out"] is None
    answer = tmp_path / "answer.json"
    answer.write_text(out)
    status, _, err = run(["statics", "--plates", str(answer)])
    assert status == 2 and err.count("\n") == 1 and "success is not true" in err


def test_out_with_a_carrier_is_refused_in_one_line(tmp_path):
    status, _, err = run(["solve", "--goal", *GOAL, "--carrier", "ur10", "--out", str(tmp_path / "p.json")])
    assert status == 2 and err.count("\n") == 1 and "--out" in err
