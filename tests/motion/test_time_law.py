"""The time laws (quintic, TOPP-RA optimal) on a planned path, held to independent checks:
finite differences of the written lengths at 1 ms against the legs' limits, the forces with
the motion's part recomputed from those differences, MuJoCo's servos following the motion."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from assembler_pin import AssemblerModel, load_config
from assembler_pin.dynamics import inverse_dynamics_from_lengths
from assembler_pin.exceptions import ConfigError, TrajectoryError
from assembler_pin.kinematics import stack_forward_kinematics
from assembler_pin.motion import EEPath, PlanOptions, plan_path
from assembler_pin.motion.laws import QuinticLaw, TimingProblem
from assembler_pin.motion.timing import law_by_name, plan_trajectory, time_parametrize, trajectory_states
from assembler_pin.motion.trajfile import read_trajectory


@pytest.fixture(scope="module")
def plan(am):
    goal = pin.SE3(am.home[-1])
    goal.translation = goal.translation + np.array([0.015, 0.0, -0.01])
    opts = PlanOptions(position_step=0.005, rotation_step=0.0174, max_leg_step=0.005)
    result = plan_path(am, EEPath((pin.SE3(am.home[-1]), goal)), am.home, opts)
    assert result.success, result.reason
    return result


@pytest.fixture(scope="module")
def optimal(am, plan):
    return time_parametrize(am, plan, rate=1000.0, time_law="optimal")


def test_optimal_law_rows_at_1ms_hold_every_limit(am, plan, optimal):
    leg = am.config.leg
    traj = optimal
    assert traj.meta["time_law"] == "optimal" and traj.feasible.all()
    dt = np.diff(traj.times)
    assert dt.max() <= 1e-3 + 1e-12
    v = np.diff(traj.lengths, axis=0) / dt[:, None, None]
    a = np.diff(v, axis=0) / (0.5 * (dt[1:] + dt[:-1]))[:, None, None]
    assert np.abs(v).max() <= 1.01 * leg.max_speed
    assert np.abs(a).max() <= 1.01 * leg.max_acceleration
    assert max(np.abs(v).max() / leg.max_speed, np.abs(a).max() / leg.max_acceleration) > 0.8  # a limit binds
    # the forces with the motion's part, from the differences of the written lengths
    worst = 0.0
    for k in range(1, len(traj.times) - 1, 97):
        fk = stack_forward_kinematics(am, traj.lengths[k], guess=plan.states[0].plates)
        assert fk.success
        rate = (traj.lengths[k + 1] - traj.lengths[k - 1]) / (traj.times[k + 1] - traj.times[k - 1])
        F = inverse_dynamics_from_lengths(am, fk.plates, rate, a[k - 1]).forces
        worst = max(worst, float(np.abs(F - traj.dynamic_forces[k]).max()))
        assert F.max() <= leg.max_tension + 0.5 and F.min() >= -leg.max_compression - 0.5
    assert worst < 0.5, worst


def test_optimal_is_shorter_than_quintic(am, plan, optimal):
    quintic = time_parametrize(am, plan, rate=50.0, time_law="quintic")
    assert optimal.duration <= 0.6 * quintic.duration
    assert quintic.meta["time_law"] == "quintic"


def test_written_file_keeps_the_law_and_dynamic_forces(am, optimal, tmp_path):
    for name in ("t.csv", "t.json"):
        back = read_trajectory(optimal.write(tmp_path / name))
        assert back.meta["time_law"] == "optimal"
        np.testing.assert_array_equal(back.dynamic_forces, optimal.dynamic_forces)


def test_auto_picks_the_faster_valid_law(am):
    goal = pin.SE3(am.home[-1])
    goal.translation = goal.translation + np.array([0.0, 0.0, -0.02])
    motion = plan_trajectory(am, EEPath((pin.SE3(am.home[-1]), goal)), am.home, rate=20.0)
    assert motion.success, motion.reason
    assert set(motion.law_durations) == {"quintic", "optimal"}
    assert motion.time_law == min(motion.law_durations, key=motion.law_durations.get)
    assert motion.to_dict()["time_law"] == motion.time_law


def test_forces_beyond_the_limit_at_rest_make_the_path_impossible(am, plan):
    tight = AssemblerModel.from_config(load_config({"leg": {"max_tension": 5.0, "max_compression": 5.0}}))
    with pytest.raises(TrajectoryError, match="forces at rest"):
        time_parametrize(tight, plan, rate=50.0, time_law="optimal")


def test_optimal_law_refuses_waypoint_times(plan):
    problem = TimingProblem(lambda s, o=0: np.zeros((len(np.atleast_1d(s)), 6)), 3, [(0, 2, 5.0)], 0.05, 0.2)
    with pytest.raises(TrajectoryError, match="waypoint times"):
        law_by_name("optimal").duration(problem)
    with pytest.raises(TrajectoryError, match="time law must be"):
        law_by_name("fastest")
    assert isinstance(law_by_name("quintic"), QuinticLaw)


@pytest.mark.parametrize("value", [0.0, float("nan"), float("inf"), -1.0, 1e9])
def test_absurd_leg_limits_are_refused(value):
    with pytest.raises(ConfigError, match="max_speed"):
        load_config({"leg": {"max_speed": value}})


def test_mujoco_servos_follow_the_optimal_law(am, plan):
    from assembler_pin.simulate import follow_trajectory

    traj = time_parametrize(am, plan, rate=100.0, time_law="optimal")
    result = follow_trajectory(am, traj, settle=0.3, tolerance=2e-3)
    assert result.followed, result.message
    assert result.saturated.sum() == 0
    assert result.ee_error.max() < 2e-3
    # settled at the last command: the forces within the held-pose tolerance of our statics
    last = trajectory_states(am, traj, frames=2)[1][-1]
    tolerance = max(0.01 * float(np.abs(last.forces).max()), 0.5)
    assert np.abs(result.final_forces - last.forces).max() <= tolerance
