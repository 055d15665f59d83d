"""Hostile arguments found by tests/fuzz that are now refused with a specific AssemblerError."""

from __future__ import annotations

import numpy as np
import pytest

import assembler_pin as ap
from assembler_pin.exceptions import ConfigError, PoseError, TrajectoryError


@pytest.mark.parametrize(
    "kwargs",
    [
        {"tol": float("nan")},
        {"tol": -1.0},
        {"max_iterations": -1},
        {"max_iterations": True},
        {"max_iterations": 10**12},
    ],
)
def test_stack_fk_refuses_bad_tolerance_and_iteration_counts(am, kwargs):
    """A NaN or negative tolerance, a negative, boolean or astronomic iteration count is refused
    before any Newton step (it used to fail with UnboundLocalError or report 'did not converge')."""
    with pytest.raises(PoseError, match=next(iter(kwargs))):
        ap.stack_forward_kinematics(am, np.full((am.n, 6), 0.27), **kwargs)


def test_stack_fk_still_solves_with_defaults(am):
    """Values inside the bounds pass: FK of the home leg lengths (from the design anchors,
    independently of the package) gives back the home plates."""
    from checks import sp_legs

    home = np.array([m.homogeneous for m in am.home])  # world poses of the plates
    R, p = home[:, :3, :3], home[:, :3, 3]
    lengths = np.array([sp_legs(am.config, j, R[j], p[j], R[j + 1], p[j + 1])[0] for j in range(am.n)])
    fk = ap.stack_forward_kinematics(am, lengths, max_iterations=30, tol=1e-12)
    assert fk.success
    assert np.abs(np.asarray(fk.plates.p) - p).max() < 1e-9


def test_plan_refuses_negative_refinements(am):
    import pinocchio as pin

    goal = am.home[-1] * pin.SE3(np.eye(3), np.array([0.0, 0.0, -0.01]))
    path = ap.EEPath((am.home[-1], goal))
    with pytest.raises(TrajectoryError, match="refinements"):
        ap.plan_trajectory(am, path, am.home, refinements=-1)


@pytest.mark.parametrize("key", ["max_speed", "max_acceleration"])
def test_config_refuses_near_zero_leg_rate_limits(key):
    """1e-12 m/s would plan a motion of millions of years: refused by the documented bound."""
    with pytest.raises(ConfigError, match=f"leg.{key}"):
        ap.load_config({"leg": {key: 1e-12}})


@pytest.mark.parametrize("path", [5, None, 1.5])
def test_read_trajectory_refuses_a_path_that_is_not_a_path(path):
    with pytest.raises(TrajectoryError, match="str or path"):
        ap.read_trajectory(path)


def test_eepath_refuses_non_finite_or_non_se3_waypoints_and_boolean_times(am):
    import pinocchio as pin

    from assembler_pin.exceptions import AssemblerError

    nan_goal = pin.SE3(np.eye(3), np.array([np.nan, 0.0, 0.9]))
    with pytest.raises(AssemblerError, match="NaN"):
        ap.EEPath((am.home[-1], nan_goal))
    with pytest.raises(AssemblerError, match=r"pin\.SE3"):
        ap.EEPath((np.eye(4), np.eye(4)))
    with pytest.raises(AssemblerError, match="booleans"):
        ap.EEPath((am.home[-1], am.home[-1]), times=(False, True))
    assert ap.EEPath((am.home[-1], am.home[-1]), times=(0, 2.5)).times == (0, 2.5)


def test_plan_refuses_a_path_that_is_not_an_eepath(am):
    from assembler_pin.exceptions import PathError

    with pytest.raises(PathError, match="EEPath"):
        ap.plan_trajectory(am, [am.home[-1], am.home[-1]], am.home)


def test_cli_plan_refuses_timed_waypoints_away_from_the_from_pose(tmp_path, capsys):
    """--waypoints starts at --from (as --to does); times that start elsewhere are refused."""
    from assembler_pin.cli.app import main

    wp = tmp_path / "wp.json"
    wp.write_text('{"waypoints": [[0, 0, 0.95, 0, 0, 0], [0, 0, 0.94, 0, 0, 0]], "times": [0, 2]}')
    code = main(["plan", "--json", "--waypoints", str(wp), "--from", "0", "0", "0.9", "0", "0", "0"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--waypoints" in err[0] and "--from pose" in err[0]


@pytest.fixture(scope="module")
def ur5():
    return ap.carrier.Carrier("ur5")


def test_carrier_refuses_string_angles_and_negative_ik_iterations(ur5):
    from assembler_pin.exceptions import OptionsError

    with pytest.raises(PoseError, match="numbers"):
        ur5.check_q(["0"] * 6)
    with pytest.raises(OptionsError, match="max_iterations"):
        ur5.ik(ur5.base_pose(ur5.upright_q), ur5.upright_q, max_iterations=-1)
    assert ur5.ik(ur5.base_pose(ur5.upright_q), ur5.upright_q).success


def test_carrier_statics_refuses_a_carrier_name(am):
    from assembler_pin.exceptions import OptionsError

    with pytest.raises(OptionsError, match="Carrier"):
        ap.carrier.carrier_statics(am, "ur5", np.zeros(6), am.home)


def test_solve_on_carrier_refuses_a_nan_carrier_weight(am, ur5):
    import pinocchio as pin

    from assembler_pin.exceptions import OptionsError

    goal = pin.SE3(np.eye(3), np.array([0.3, 0.2, 1.4]))
    with pytest.raises(OptionsError, match="w_carrier"):
        ap.carrier.solve_on_carrier(am, ur5, goal, w_carrier=np.nan)


def test_stack_fk_refuses_astronomic_lengths_without_a_numpy_warning(am):
    """1e300 m legs used to overflow inside the Newton solve (a RuntimeWarning escaped)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(PoseError, match="at most"):
            ap.stack_forward_kinematics(am, np.full((am.n, 6), 1e300))


def test_payload_capacity_refuses_an_astronomic_iteration_count(am):
    import pinocchio as pin

    from assembler_pin.exceptions import OptionsError

    goal = pin.SE3(np.eye(3), np.array([0.02, 0.01, 0.85]))
    with pytest.raises(OptionsError, match="max_iterations"):
        ap.payload_capacity(am, goal, max_iterations=10**9)
