"""Motion: paths, the planner and the time law, each sample held to independent checks.

Checks that do not use the planner's own code: the design-based kinematic check of
``tests/checks.py`` on plate poses rebuilt by stack FK from the planned lengths (FK round
trip), SE(3) arithmetic for the path, finite differences for speeds and accelerations, and a
dense re-sampling of the interpolated lengths between samples.
"""

from __future__ import annotations

import itertools
import json

import numpy as np
import pinocchio as pin
import pytest
from checks import kinematic_problems
from pages import page_commands

from assembler_pin import evaluate_state, scenario, stack_forward_kinematics
from assembler_pin.cli import main
from assembler_pin.exceptions import OptionsError, TrajectoryError
from assembler_pin.motion import EEPath, PathError, PlanOptions, interpolate_pose, plan_path, read_waypoints
from assembler_pin.motion.compare import compare_motion
from assembler_pin.motion.result import verify_trajectory
from assembler_pin.motion.timing import plan_trajectory, read_trajectory, time_parametrize, trajectory_states
from assembler_pin.plots import trajectory_plot
from assembler_pin.viz import FORCE_BAND_LEVELS

#: Why the tests marked with it fail today (known, open).
OWN_PLATE_RULE = (
    "the check of each leg against its own plates refuses the leaning poses these goals were answered "
    "with (a motor inside a plate); the optimizer does not yet find a clear pose for all of them"
)


@pytest.fixture(scope="module")
def planned(am):
    """A planned and timed motion from the home pose to the orientation-transition goal."""
    path = EEPath.between(am.home[-1], scenario("orientation_transition").goal)
    return plan_trajectory(am, path, start=am.home, rate=20.0)


def test_screw_and_linear_paths_join_their_waypoints():
    rng = np.random.default_rng(3)
    a, b = pin.exp6(rng.normal(size=6) * 0.5), pin.exp6(rng.normal(size=6) * 0.5)
    for kind in ("screw", "linear"):
        assert interpolate_pose(a, b, 0.0, kind).isApprox(a, 1e-12)
        assert interpolate_pose(a, b, 1.0, kind).isApprox(b, 1e-12)
    # linear: the origin on the chord, the rotation by a constant angular rate
    mid = interpolate_pose(a, b, 0.25, "linear")
    np.testing.assert_allclose(mid.translation, 0.75 * a.translation + 0.25 * b.translation, atol=1e-12)
    angle = np.linalg.norm(pin.log3(a.rotation.T @ b.rotation))
    assert np.linalg.norm(pin.log3(a.rotation.T @ mid.rotation)) == pytest.approx(0.25 * angle, abs=1e-12)
    # screw: constant body twist, so equal steps compose
    q1, q2 = interpolate_pose(a, b, 0.5, "screw"), interpolate_pose(a, b, 0.25, "screw")
    assert (q2 * q2.actInv(q1)).isApprox(q1, 1e-12) and (a.actInv(q2) * a.actInv(q2)).isApprox(a.actInv(q1), 1e-10)


def test_path_sampling_respects_the_steps():
    path = EEPath((pin.SE3.Identity(), pin.SE3(pin.exp3(np.array([0, 0, 0.3])), np.array([0.1, 0, 0]))), "linear")
    u = path.parameters(0.01, np.radians(2.0))
    poses = [path.at(x) for x in u]
    steps = [np.linalg.norm(p.translation - q.translation) for p, q in itertools.pairwise(poses)]
    turns = [np.linalg.norm(pin.log3(p.rotation.T @ q.rotation)) for p, q in itertools.pairwise(poses)]
    assert max(steps) <= 0.01 + 1e-12 and max(turns) <= np.radians(2.0) + 1e-12
    assert u[0] == 0 and u[-1] == 1


def test_waypoint_files(tmp_path):
    (tmp_path / "w.csv").write_text("x,y,z,rx,ry,rz,t\n0,0,0.9,0,0,0,0\n0.1,0,0.9,0,0,0,2\n")
    path = read_waypoints(tmp_path / "w.csv")
    assert path.times == (0.0, 2.0) and np.allclose(path.waypoints[1].translation, [0.1, 0, 0.9])
    (tmp_path / "w.json").write_text(
        json.dumps({"waypoints": [[0, 0, 0.9, 0, 0, 0], [0, 0, 0.9, 0, 0, 90]], "degrees": True})
    )
    path = read_waypoints(tmp_path / "w.json", kind="linear")
    assert np.linalg.norm(pin.log3(path.waypoints[1].rotation)) == pytest.approx(np.pi / 2)
    (tmp_path / "bad.csv").write_text("0,0,0.9,0,0\n")
    with pytest.raises(PathError, match="6 numbers"):
        read_waypoints(tmp_path / "bad.csv")
    with pytest.raises(PathError, match="at least 2"):
        EEPath((pin.SE3.Identity(),))
    with pytest.raises(OptionsError):
        PlanOptions(max_leg_step=0.0)


def test_every_sample_is_valid_continuous_and_on_the_path(am, planned):
    assert planned.success, planned.reason
    plan, problems = planned.plan, planned.problems
    assert problems == []
    assert len(plan.states) >= 10
    leg = am.config.leg
    for u, state in zip(plan.parameters, plan.states, strict=True):
        # FK round trip of the planned lengths reproduces the planned plates
        fk = stack_forward_kinematics(am, state.leg_lengths, base=state.plates.se3(0), guess=state.plates)
        assert fk.success
        np.testing.assert_allclose(fk.plates.p, state.plates.p, atol=1e-9)
        # the design-based check of every kinematic limit, and the EE on the path
        assert kinematic_problems(am.config, state.plates, goal=plan.path.at(u), tol=1e-9) == []
        assert np.abs(state.forces).max() <= min(leg.max_tension, leg.max_compression)
    # continuity: no leg jumps between samples
    assert np.abs(np.diff(plan.lengths, axis=0)).max() <= PlanOptions().max_leg_step + 1e-9
    # the path is followed end to end
    assert plan.parameters[-1] == 1.0
    assert plan.states[-1].plates.se3(am.n).isApprox(plan.path.at(1.0), 1e-8)


def test_trajectory_between_samples_and_its_time_law(am, planned):
    plan, traj = planned.plan, planned.trajectory
    leg = am.config.leg
    # starts and ends at the planned lengths, at rest
    np.testing.assert_allclose(traj.lengths[0], plan.lengths[0], atol=1e-12)
    np.testing.assert_allclose(traj.lengths[-1], plan.lengths[-1], atol=1e-12)
    v, a = traj.speeds(), traj.accelerations()
    assert np.abs(v).max() <= leg.max_speed and np.abs(a).max() <= leg.max_acceleration
    # from rest: the first step's mean speed is at most half the acceleration limit times its length
    assert np.abs(v[0]).max() <= 0.5 * leg.max_acceleration * traj.times[1] * (1 + 1e-9)
    # every resampled time re-checked independently: FK of the interpolated lengths + design check
    guess = plan.states[0].plates
    for k in range(0, len(traj.times), 5):
        fk = stack_forward_kinematics(am, traj.lengths[k], base=guess.se3(0), guess=guess)
        assert fk.success
        guess = fk.plates
        assert kinematic_problems(am.config, fk.plates, tol=1e-9) == [], traj.times[k]
        np.testing.assert_allclose(fk.plates.p[-1], traj.ee[k, :3], atol=1e-9)
        assert evaluate_state(am, fk.plates).feasible


def test_trajectory_files_round_trip(tmp_path, planned):
    traj = planned.trajectory
    for name in ("t.csv", "t.json"):
        back = read_trajectory(traj.write(tmp_path / name))
        np.testing.assert_allclose(back.lengths, traj.lengths, rtol=0, atol=1e-15)
        np.testing.assert_allclose(back.times, traj.times, atol=1e-15)
        assert back.feasible.all() and set(back.margins) == set(traj.margins)


def test_time_law_scales_with_the_limits(am, planned):
    plan = planned.plan
    traj = time_parametrize(am, plan, rate=20.0, time_law="quintic")
    slow = time_parametrize(
        am,
        plan,
        rate=20.0,
        max_speed=am.config.leg.max_speed / 2,
        max_acceleration=am.config.leg.max_acceleration / 4,
        time_law="quintic",
    )
    assert slow.duration == pytest.approx(2 * traj.duration, rel=1e-6)
    assert verify_trajectory(am, slow) == []


def test_a_motion_from_a_state_that_is_not_at_the_path_start_is_refused(am):
    path = EEPath.between(pin.SE3(np.eye(3), np.array([0.1, 0, 0.9])), scenario("translation").goal)
    result = plan_path(am, path, start=am.home)
    assert not result.success and "not valid at the path's start" in result.reason and result.states == []


def test_an_unreachable_goal_stops_with_the_valid_prefix(am):
    path = EEPath.between(am.home[-1], pin.SE3(np.eye(3), np.array([0.0, 0.0, 1.6])))
    result = plan_path(am, path, start=am.home, options=PlanOptions(position_step=0.05, max_refinements=1))
    assert not result.success and "no valid sample" in result.reason
    assert 1 <= len(result.states) and all(s.feasible for s in result.states)
    assert result.parameters[-1] < 1.0


def test_cli_plan(tmp_path, capsys):
    out = tmp_path / "traj.json"
    code = main(["plan", "--to", "0.05", "0", "0.97", "0", "0", "0", "--rate", "10", "--out", str(out), "--json"])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["success"] is True and doc["samples"] >= 2
    assert read_trajectory(out).feasible.all()
    assert main(["plan", "--to", "0", "0", "0.9", "0", "0", "0", "--rate", "0"]) == 2


def test_motion_result_reads_and_agrees_with_its_plan(planned):
    text = repr(planned)
    assert text.startswith("MotionResult(success=True") and "array(" not in text
    doc = planned.to_dict()
    # travel recomputed from the planned lengths, bounded below by the net change (triangle inequality)
    lengths = np.array([s.leg_lengths for s in planned.plan.states])
    assert doc["total_leg_travel_m"] == pytest.approx(np.abs(np.diff(lengths, axis=0)).sum(), rel=1e-12)
    assert doc["total_leg_travel_m"] >= np.abs(lengths[-1] - lengths[0]).sum() - 1e-12
    assert doc["duration_s"] == planned.trajectory.times[-1]


def test_trajectory_states_rebuild_the_file_by_fk(am, tmp_path, planned):
    back = read_trajectory(planned.trajectory.write(tmp_path / "t.json"))
    times, states = trajectory_states(am, back, frames=12)
    assert len(states) == 12 and times[0] == 0 and times[-1] == back.times[-1]
    for t, st in zip(times, states, strict=True):
        k = int(np.argmin(np.abs(back.times - t)))
        # the rebuilt stack has the commanded lengths and the EE written in the file
        np.testing.assert_allclose(st.leg_lengths, back.lengths[k], atol=1e-9)
        np.testing.assert_allclose(st.plates.p[-1], back.ee[k, :3], atol=1e-9)
        assert kinematic_problems(am.config, st.plates, tol=1e-9) == []
        assert st.max_abs_force == pytest.approx(back.max_abs_force[k], rel=1e-6)  # FK converged to ~1e-10 m
    # a file whose EE column disagrees with its lengths is refused
    back.ee[5, 0] += 1e-3
    with pytest.raises(TrajectoryError, match="EE"):
        trajectory_states(am, back)
    fig = trajectory_plot(am, back, states, times, "test")
    lines = {round(float(line.get_ydata()[0]), 6) for ax in fig.axes for line in ax.lines if len(line.get_ydata()) == 2}
    leg = am.config.leg
    assert {
        leg.min_length,
        leg.max_length,
        leg.max_speed,
        -leg.max_speed,
        leg.max_tension,
        -leg.max_compression,
    } <= lines
    # a row per platform; a column per quantity, the last one the forces with the motion's part
    assert len(fig.axes) == 5 * am.n and fig.get_suptitle().startswith("test")
    assert "static+dynamic" in fig.axes[4].get_ylabel()


@pytest.mark.xfail(reason=OWN_PLATE_RULE, strict=False)
def test_compare_against_simple_plans(am):
    path = EEPath.between(am.home[-1], scenario("orientation_transition").goal)
    c = compare_motion(am, path, start=am.home, rate=10.0, name="ot")
    assert c.motion.success and list(c.figures) == ["optimized", "helper_arm", "linear_lengths"]
    ours, arm, linear = c.figures.values()
    assert ours.valid_fraction == 1.0
    assert ours.peak_max_abs_force <= min(arm.peak_max_abs_force, linear.peak_max_abs_force) + 1e-9
    # linear leg lengths travel exactly their net change between the two end poses ...
    first, last = c.motion.plan.states[0], c.motion.plan.states[-1]
    assert linear.total_leg_travel == pytest.approx(np.abs(last.leg_lengths - first.leg_lengths).sum(), rel=1e-9)
    # ... and the EE is not steered: independent FK of the mid lengths puts it off the path
    fk = stack_forward_kinematics(am, 0.5 * (first.leg_lengths + last.leg_lengths), base=am.home[0], guess=first.plates)
    mid_off = min(np.linalg.norm(fk.plates.p[-1] - path.at(u).translation) for u in np.linspace(0, 1, 201))
    assert linear.max_path_deviation >= mid_off - 1e-6 > 2e-3 and linear.valid_fraction < 1.0
    for f in c.figures.values():
        assert 0 <= f.valid_fraction <= f.limits_fraction <= 1 and f.duration > 0
        assert f.total_leg_travel >= np.abs(last.leg_lengths - first.leg_lengths).sum() * (f is not arm) - 1e-9
    assert "array(" not in repr(c)


def test_cli_plan_compare_prints_the_table(capsys):
    assert main(["plan", "--compare", "--to", "0.03", "0", "0.97", "0", "0", "0", "--rate", "5"]) == 0
    out = capsys.readouterr().out
    assert "peak max|F| N" in out and all(m in out for m in ("optimized", "helper_arm", "linear_lengths"))


def test_cli_view_trajectory_page_shows_each_legs_force_level(am, tmp_path, planned):
    traj_file = planned.trajectory.write(tmp_path / "t.csv")
    page = tmp_path / "t.html"
    assert main(["view", "--trajectory", str(traj_file), "--frames", "6", "--html", str(page)]) == 0
    (anim,) = [c for c in page_commands(page.read_text()) if c["type"] == "set_animation"]
    visible = {}  # (platform, leg, level) -> visibility per frame
    for clip in anim["animations"]:
        parts = clip["path"].split("/")
        if "assembler_force_bands" in parts:
            j, i = (int(x) for x in parts[-2].removeprefix("sp").split("_leg"))
            for track in clip["clip"]["tracks"]:
                if track["name"] == ".visible":
                    visible[j, i, int(parts[-1].removeprefix("level"))] = [k["value"] for k in track["keys"]]
    # the frames' forces, independently: FK of the file's lengths at the animation's samples
    traj = read_trajectory(traj_file)
    picks = np.unique(np.round(np.linspace(0, len(traj.times) - 1, 6)).astype(int))
    from assembler_pin.viz.colors import FORCE_SCALE_FLOOR

    leg = am.config.leg
    guess = evaluate_state(am, am.home).plates
    frames = []
    for k in picks:
        fk = stack_forward_kinematics(am, traj.lengths[k], base=am.home[0], guess=guess)
        guess = fk.plates
        frames.append(evaluate_state(am, fk.plates).forces)
    # one scale for the whole animation: its largest force, at least the floor of the "auto" scale
    scale = max(max(np.abs(f).max() for f in frames), FORCE_SCALE_FLOOR * min(leg.max_tension, leg.max_compression))
    for frame, forces in enumerate(frames):
        fraction = forces / scale
        for j in range(am.n):
            for i in range(6):
                shown = [lvl for (jj, ii, lvl), keys in visible.items() if (jj, ii) == (j, i) and keys[frame]]
                assert len(shown) == 1  # exactly one sleeve per leg and frame
                assert abs(FORCE_BAND_LEVELS[shown[0]] - fraction[j, i]) <= 0.5 * np.diff(FORCE_BAND_LEVELS)[0] + 1e-9
    assert main(["view", "--trajectory", str(tmp_path / "missing.csv"), "--html", str(page)]) == 2
