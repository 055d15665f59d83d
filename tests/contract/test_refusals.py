"""Bad input gets a specific error naming what was wrong and what is allowed; a NaN or an
overflow is never passed along or marked feasible; JSON output is strict."""

from __future__ import annotations

import inspect
import json
import math

import numpy as np
import pinocchio as pin
import pytest

import assembler_pin as ap
from assembler_pin import exceptions
from assembler_pin.cli import main
from assembler_pin.constraints import evaluate_constraints
from assembler_pin.statics import StaticsResult


@pytest.mark.parametrize(
    "doc, key",
    [
        ({"gravity": 1e308}, "gravity"),
        ({"payload": {"mass": 1e308}}, "payload.mass"),
        ({"leg": {"max_tension": 1e300}}, "leg.max_tension"),
        ({"plate": {"node_radius": 1e200}}, "plate.node_radius"),
        ({"payload": {"offset": -1e10}}, "payload.offset"),
    ],
)
def test_physically_meaningless_configs_are_refused(doc, key):
    with pytest.raises(ap.exceptions.ConfigError, match=f"'{key}'.*at most"):
        ap.load_config(doc)


def test_numpy_scalars_are_numbers():
    doc = {"platforms": np.int64(3), "gravity": np.float32(9.5), "leg": {"max_length": np.float64(0.34)}}
    cfg = ap.load_config(doc)
    assert (cfg.platforms, cfg.gravity, cfg.leg.max_length) == (3, 9.5, 0.34)


def test_yaml_duplicates_are_refused_and_scientific_numbers_read(tmp_path):
    dup = tmp_path / "dup.yaml"
    dup.write_text("leg:\n  max_length: 0.3\n  max_length: 0.4\n")
    with pytest.raises(ap.exceptions.ConfigError, match="given twice"):
        ap.load_config(dup)
    sci = tmp_path / "sci.yaml"
    sci.write_text("gravity: 2e-1\nleg:\n  max_tension: 1e3\n")
    cfg = ap.load_config(sci)
    assert cfg.gravity == 0.2 and cfg.leg.max_tension == 1000.0


def test_a_non_finite_force_is_never_feasible(am):
    state = ap.evaluate_state(am, am.home)
    for bad in (np.nan, np.inf):
        forces = state.forces.copy()
        forces[1, 2] = bad
        statics = StaticsResult(
            forces, state.statics.ball_forces, state.statics.base_wrench, state.statics.condition, False
        )
        kinds = {v.kind for v in evaluate_constraints(am.config, state.legs, statics)}
        assert "non_finite_force" in kinds


def test_coplanar_plates_are_a_singular_configuration(am):
    plates = [pin.SE3.Identity()] * (am.n + 1)
    with pytest.raises(ap.exceptions.SingularConfigurationError):
        ap.solve_statics(am, plates, raise_on_singular=True)
    state = ap.evaluate_state(am, plates)
    assert not state.feasible and "singular" in {v.kind for v in state.violations}


def test_every_error_class_lives_in_exceptions_and_derives_from_assembler_error():
    classes = [c for _, c in inspect.getmembers(exceptions, inspect.isclass) if issubclass(c, BaseException)]
    assert {"CLIError", "OptionsError", "UnknownScenarioError", "ViewerError"} <= {c.__name__ for c in classes}
    assert all(issubclass(c, ap.AssemblerError) for c in classes)
    with pytest.raises(exceptions.UnknownScenarioError, match="choose one of"):
        ap.scenario("no_such_scenario")


@pytest.mark.parametrize(
    "make",
    [
        lambda: ap.OptimizeOptions(max_iterations=-1),
        lambda: ap.OptimizeOptions(max_iterations=1.5),
        lambda: ap.OptimizeOptions(w1=float("nan")),
        lambda: ap.OptimizeOptions(ftol=-1.0),
        lambda: ap.OptimizeOptions(ee_tolerance=ap.constraints.GoalTolerance(math.inf, math.inf)),
        lambda: ap.HelperArmOptions(max_attempts="3"),
        lambda: ap.HelperArmOptions(d_step=float("inf")),
    ],
)
def test_options_out_of_range_are_options_errors(make):
    with pytest.raises(exceptions.OptionsError):
        make()


@pytest.mark.parametrize(
    "value",
    [1.5, "0", None, [[1, 2], [3]], [[[True] * 4] * 4] * 5, np.zeros((5, 4, 4)), [[0.0] * 4] * 4],
)
def test_wrong_plate_arguments_are_pose_errors(am, value):
    with pytest.raises(ap.AssemblerError):
        ap.evaluate_state(am, value)


def test_huge_rotation_vectors_are_out_of_range_not_nan():
    with pytest.raises(ap.exceptions.PoseError, match="out of range"):
        ap.kinematics.taa_to_se3([0, 0, 0.9, 1e300, 0, 0])


def _run(capsys, argv):
    code = main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err.splitlines()


@pytest.mark.parametrize(
    "argv, words",
    [
        (["bench", "--repeat", "0"], "--repeat"),
        (["solve", "--goal", "0.3", "0", "0.8", "0", "0.6", "0", "--w1", "inf"], "w1"),
        (["solve", "--goal", "0.3", "0", "0.8", "0", "0.6", "0", "--ftol", "nan"], "ftol"),
        (["solve", "--goal", "0.3", "0", "0.8", "0", "0.6", "0", "--ee-tolerance", "inf", "inf"], "ee_tolerance"),
        (["solve", "--goal", "0", "0"], "expected 6"),
        (["solve", "--bogus"], "unrecognized"),
        (["export", "--out", "/proc/no/such/dir"], "does not exist"),
        (["export", "--out", "/proc/x"], "cannot write in directory '/proc'"),
        (["view", "--home", "--html", "/no/such/dir/page.html"], "does not exist"),
        (["reproduce", "--out", "/no/such/dir/report"], "does not exist"),
    ],
)
def test_cli_refusals_are_one_line(capsys, argv, words):
    code, out, err = _run(capsys, argv)
    assert code == 2 and out == "" and len(err) == 1 and words in err[0], err


def test_negative_scientific_goals_parse(capsys):
    argv = ["solve", "--goal", "-1e-3", "0", "0.9", "0", "0", "-1e-2", "--no-optimize", "--json"]
    code, out, err = _run(capsys, argv)
    assert code == 0 and not err
    assert json.loads(out)["goal"][0] == pytest.approx(-1e-3)


def test_strict_json_for_a_singular_pose(tmp_path, capsys, am):
    plates = tmp_path / "coplanar.json"
    plates.write_text(json.dumps({"plates": [np.eye(4).tolist()] * (am.n + 1)}))
    code, out, _ = _run(capsys, ["statics", "--plates", str(plates), "--json"])
    assert code == 1  # answered, not a valid pose
    doc = json.loads(out, parse_constant=lambda c: pytest.fail(f"non-strict JSON token {c}"))
    assert doc["feasible"] is False
