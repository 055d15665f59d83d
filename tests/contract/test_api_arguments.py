"""The API takes what a user holds: a state where plates are expected, a pose built by the
converter the CLI uses; swapped arguments and a bare six-vector goal are refused with the
error the contract names and a pointer at what was expected."""

from __future__ import annotations

import numpy as np
import pytest

import assembler_pin as ap
from assembler_pin.exceptions import ArgumentError, PoseError


@pytest.fixture(scope="module")
def state(am):
    return ap.evaluate_state(am, am.home)


@pytest.mark.parametrize("function", [ap.stiffness, ap.evaluate_state, ap.solve_statics], ids=lambda f: f.__name__)
def test_a_state_is_taken_where_plates_are_expected(am, state, function):
    from_state, from_plates = function(am, state), function(am, state.plates)
    if function is ap.stiffness:
        np.testing.assert_array_equal(from_state.stiffness, from_plates.stiffness)
    else:
        forces = (from_state if function is ap.solve_statics else from_state.statics).forces
        reference = (from_plates if function is ap.solve_statics else from_plates.statics).forces
        np.testing.assert_array_equal(forces, reference)


@pytest.mark.parametrize("function", [ap.stiffness, ap.evaluate_state, ap.solve_statics], ids=lambda f: f.__name__)
def test_swapped_arguments_are_an_argument_error_naming_the_model(am, state, function):
    for args in ((state, am), (am.home, am), (am, am)):
        with pytest.raises(ArgumentError, match="AssemblerModel") as err:
            function(*args)
        assert "first" in str(err.value)


def test_a_failed_fk_result_is_no_pose(am):
    from types import SimpleNamespace

    fk = ap.stack_forward_kinematics(am, np.full((am.n, 6), 0.3))
    failed = SimpleNamespace(plates=fk.plates, success=False, message="did not converge")
    with pytest.raises(PoseError, match="did not succeed"):
        ap.solve_statics(am, failed)
    np.testing.assert_array_equal(ap.solve_statics(am, fk).forces, ap.solve_statics(am, fk.plates).forces)


def test_a_state_of_another_stack_size_is_refused(am):
    other = ap.AssemblerModel.from_config({"platforms": 2})
    with pytest.raises(PoseError, match="expected 5 plate poses"):
        ap.evaluate_state(am, ap.evaluate_state(other, other.home))


def test_a_six_vector_goal_points_at_the_converter(am):
    with pytest.raises(PoseError, match=r"ap\.kinematics\.taa_to_se3") as err:
        ap.solve(am, [0.3, 0, 0.75, 0, np.pi / 2, 0])
    assert len(str(err.value)) <= 200
    goal = ap.kinematics.taa_to_se3([0.3, 0, 0.75, 0, np.pi / 2, 0])
    np.testing.assert_allclose(goal.translation, [0.3, 0, 0.75])


@pytest.mark.parametrize(
    "argv",
    [["solve", "--goal", "0.3", "0", "0.75", "0", "90", "0"], ["plan", "--to", "0.3", "0", "0.75", "0", "90", "0"]],
    ids=["solve", "plan"],
)
def test_degrees_typed_as_radians_are_refused_in_one_line(argv, capsys):
    from assembler_pin.cli.app import main

    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "more than 2π" in err
    if argv[0] == "solve":
        assert "--goal-deg" in err
