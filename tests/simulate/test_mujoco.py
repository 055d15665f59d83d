"""The MJCF export in MuJoCo and in Pinocchio's MJCF parser, and MuJoCo's statics held to ours.

MuJoCo is a second engine: its gravity, its constraint Jacobian and its simulated servos
know nothing of our statics. Tolerances: the inverse statics from MuJoCo's model are exact
up to rounding (1e-9 N); a pose held by the simulated position servos agrees within
max(1% of max|F|, 0.5 N) — the servos' and soft ball joints' compliance let the stack sag
(0.1–4 mm on the default stack) and the forces of the sagged pose differ by that much.
"""

from __future__ import annotations

import json
import subprocess
import sys

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from assembler_pin import (
    SCENARIOS,
    AssemblerModel,
    load_config,
    scenario,
    solve,
    solve_statics,
    stack_forward_kinematics,
)
from assembler_pin.export import export_model_files
from assembler_pin.kinematics import leg_state
from assembler_pin.model.mjcf import MJCF_FILENAME, assembler_mjcf
from assembler_pin.simulate import MujocoStack, SimulationError, hold_pose, mujoco_statics


def _hold_tolerance(forces: np.ndarray) -> float:
    return max(0.01 * float(np.abs(forces).max()), 0.5)


@pytest.fixture(scope="module")
def stack(am) -> MujocoStack:
    return MujocoStack(am)


@pytest.fixture(scope="module")
def optimized_scenarios(am):
    out = {}
    for name in SCENARIOS:
        result = solve(am, scenario(name).goal)
        assert result.success, (name, result.message)
        out[name] = result.optimized.plates
    return out


@pytest.mark.parametrize("n", [1, 2, 3, 5, 8])
def test_mjcf_loads_in_mujoco_and_pinocchio_with_the_same_bodies(tmp_path, n):
    cfg = load_config({"platforms": n})
    path = export_model_files(cfg, tmp_path, mjcf=True)["mjcf"]
    assert path.name == MJCF_FILENAME
    m = mujoco.MjModel.from_xml_path(str(path))
    assert (m.nu, m.neq, m.nv) == (6 * n, 6 * n, 24 * n)
    # the same masses as the configuration: plates, motors, shafts, payload
    expected_mass = (n + 1) * cfg.plate.mass + 6 * n * (cfg.leg.motor_mass + cfg.leg.shaft_mass) + cfg.payload.mass
    assert m.body_mass.sum() == pytest.approx(expected_mass, rel=1e-12)
    model, point_constraints, _ = pin.buildModelAndConstraintsFromMJCF(str(path))
    assert (model.nq, model.nv, len(point_constraints)) == (m.nq, m.nv, 6 * n)
    assert sum(inertia.mass for inertia in model.inertias) == pytest.approx(expected_mass, rel=1e-12)
    # the home pose is MuJoCo's reference configuration, with the loops closed
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    assert np.abs(d.efc_pos[: 18 * n]).max() < 1e-12
    np.testing.assert_allclose(m.qpos0[m.jnt_qposadr[m.actuator_trnid[:, 0]]], 0.5 * (0.2 + 0.35), atol=1e-12)


def test_our_pose_closes_the_loops_and_places_the_ee_in_both_engines(am, stack, random_poses, tmp_path):
    path = tmp_path / MJCF_FILENAME
    path.write_text(assembler_mjcf(am.config))
    model, point_constraints, _ = pin.buildModelAndConstraintsFromMJCF(str(path))
    data = model.createData()
    ee_frame = model.getFrameId("plate_4")
    payload_body = mujoco.mj_name2id(stack.model, mujoco.mjtObj.mjOBJ_BODY, "payload")
    for lengths, plates in random_poses[:4]:
        stack.set_plates(plates)
        d = stack.data
        assert stack.closure_residual() < 1e-12
        # MuJoCo's plates and payload where ours are
        mj_plates = stack.plates()
        np.testing.assert_allclose(mj_plates.p, plates.p, atol=1e-12)
        np.testing.assert_allclose(mj_plates.R, plates.R, atol=1e-12)
        payload = plates.se3(am.n).act(np.array([0.0, 0.0, am.config.payload.offset]))
        np.testing.assert_allclose(d.xpos[payload_body], payload, atol=1e-12)
        # the slides hold the pin-to-pin lengths
        np.testing.assert_allclose(
            d.qpos[stack.model.jnt_qposadr[stack.model.actuator_trnid[:, 0]]], lengths.ravel(), atol=1e-9
        )
        # Pinocchio's MJCF model: same configuration layout with quaternions x y z w
        q = d.qpos.copy().reshape(am.n, 25)
        q[:, 21:25] = np.roll(q[:, 21:25], -1, axis=1)
        q = q.ravel()
        pin.framesForwardKinematics(model, data, q)
        np.testing.assert_allclose(data.oMf[ee_frame].homogeneous, plates.se3(am.n).homogeneous, atol=1e-12)
        for c in point_constraints:
            cdata = c.createData()
            c.calc(model, data, cdata)
            assert np.linalg.norm(cdata.constraint_position_error) < 1e-12
        # the two engines' gravity on the same file agree
        g = pin.computeGeneralizedGravity(model, data, q)
        np.testing.assert_allclose(g, d.qfrc_bias, atol=1e-10)


def test_mujoco_statics_equal_ours_on_home_random_and_optimized_poses(am, stack, random_poses, optimized_scenarios):
    poses = [am.home] + [plates for _, plates in random_poses] + list(optimized_scenarios.values())
    for plates in poses:
        ours = solve_statics(am, plates).forces
        theirs = mujoco_statics(am, plates, stack)
        assert theirs.closure_residual < 1e-12
        np.testing.assert_allclose(theirs.forces, ours, atol=1e-9)


def test_mujoco_statics_with_a_tilted_base(am, stack, random_poses):
    base = pin.SE3(pin.exp3(np.array([0.4, -0.3, 0.2])), np.array([0.1, -0.2, 0.3]))
    lengths, _ = random_poses[0]
    plates = stack_forward_kinematics(am, lengths, base=base).raise_if_failed()
    np.testing.assert_allclose(mujoco_statics(am, plates, stack).forces, solve_statics(am, plates).forces, atol=1e-9)


def test_held_pose_forces_match_our_statics(am, stack, random_poses, optimized_scenarios):
    poses = {"home": am.home} | {f"random{k}": p for k, (_, p) in enumerate(random_poses[:4])} | optimized_scenarios
    for name, plates in poses.items():
        ours = solve_statics(am, plates).forces
        held = hold_pose(am, plates, seconds=1.5, samples=10, joint_limits=False, stack=stack)
        assert held.held, (name, held.message)
        gap = np.abs(held.final_forces - ours).max()
        assert gap <= _hold_tolerance(ours), (name, gap)
        assert held.closure_residual.max() < 5e-4, name
        # what remains is the sag: our statics at MuJoCo's settled pose agree more closely
        settled = solve_statics(am, held.plates).forces
        assert np.abs(held.final_forces - settled).max() < 0.1 * _hold_tolerance(ours), name


def test_end_stops_take_the_load_a_servo_at_its_stroke_end_cannot(am, stack, optimized_scenarios):
    """The optimized translation pose has legs exactly at their stroke ends: held with the
    joint limits on, the sagging legs rest on their end stops, and servo + stop together
    carry our statics' force."""
    plates = optimized_scenarios["translation"]
    ours = solve_statics(am, plates).forces
    held = hold_pose(am, plates, seconds=1.5, samples=10, stack=stack)
    stops = held.end_stop_forces[-1]
    assert np.abs(stops).max() > 0.1  # some stops do carry load
    lengths = leg_state(am, plates).lengths
    leg = am.config.leg
    at_stroke_end = np.isclose(lengths, leg.max_length, atol=1e-6) | np.isclose(lengths, leg.min_length, atol=1e-6)
    assert np.all(stops[~at_stroke_end] == 0.0)
    assert np.abs(held.final_forces + stops - ours).max() <= _hold_tolerance(ours)


def test_a_pose_over_the_force_limit_is_not_held(random_poses):
    """The same pose with force limits below its max|F|: MuJoCo's force-limited servos sag."""
    _, plates = random_poses[2]
    base = AssemblerModel.from_config()
    peak = solve_statics(base, plates).max_abs_force
    limit = 0.7 * peak
    weak = AssemblerModel.from_config({"leg": {"max_tension": limit, "max_compression": limit}})
    result = hold_pose(weak, plates, seconds=1.0, samples=10)
    assert not result.held
    assert result.saturated.any()
    assert result.ee_drift[-1] > 5e-3
    # and with limits above the peak the same pose is held
    strong = AssemblerModel.from_config({"leg": {"max_tension": 1.2 * peak, "max_compression": 1.2 * peak}})
    assert hold_pose(strong, plates, seconds=1.0, samples=10).held


def test_hold_pose_refuses_bad_arguments(am, stack):
    for kwargs in ({"seconds": float("nan")}, {"seconds": 0.0}, {"samples": 1}, {"drift_tolerance": -1.0}):
        with pytest.raises(SimulationError):
            hold_pose(am, am.home, stack=stack, **kwargs)


def _cli(*args: str, stdin: str | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "assembler_pin.cli", *args], capture_output=True, text=True, input=stdin, timeout=300
    )


def test_cli_export_mjcf_and_simulate(tmp_path, am):
    out = _cli("export", "--mjcf", "--out", str(tmp_path))
    assert out.returncode == 0, out.stderr
    assert mujoco.MjModel.from_xml_path(str(tmp_path / MJCF_FILENAME)).nu == 24
    plates = {"plates": [p.homogeneous.tolist() for p in am.home]}
    res = _cli("simulate", "--plates", "-", "--seconds", "0.5", "--json", stdin=json.dumps(plates))
    assert res.returncode == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["held"] is True
    np.testing.assert_allclose(doc["final_forces"], solve_statics(am, am.home).forces, atol=0.5)
    bad = _cli("simulate", "--home", "--seconds", "-1")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1 and "seconds" in bad.stderr


def test_servos_follow_a_planned_trajectory(am, tmp_path, capsys):
    import assembler_pin as ap
    from assembler_pin.cli import main
    from assembler_pin.motion import EEPath
    from assembler_pin.simulate import follow_trajectory

    goal = pin.SE3(np.eye(3), am.home[-1].translation + np.array([0.03, 0.0, -0.01]))
    motion = ap.plan_trajectory(am, EEPath((am.home[-1], goal)), am.home, rate=10.0)
    assert motion.success, motion.reason
    result = follow_trajectory(am, motion.trajectory)
    assert result.followed, result.message
    assert result.ee_error.max() < 5e-3 and not result.saturated.any()
    # after settling, MuJoCo's servos carry what our statics say the final pose needs
    final = ap.evaluate_state(
        am,
        ap.stack_forward_kinematics(
            am, motion.trajectory.lengths[-1], base=am.home[0], guess=motion.plan.states[-1].plates
        ).plates,
    )
    gap = np.abs(result.final_forces - final.forces).max()
    assert gap <= max(0.01 * final.max_abs_force, 0.5), gap
    path = motion.trajectory.write(tmp_path / "t.csv")
    assert main(["simulate", "--trajectory", str(path), "--json"]) == 0
    assert main(["simulate", "--trajectory", str(path), "--html", str(tmp_path / "x.html")]) == 2
    # the text answer: its t = 0 row is unloaded, and says why, as simulate --home does
    capsys.readouterr()
    assert main(["simulate", "--trajectory", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    first = lines[2].split()
    assert first[0] == "0.00" and first[2] == "unloaded" and result.max_abs_force[0] == 0.0
    assert "At t = 0 the servos stand at the commanded lengths and push nothing" in "\n".join(lines)


def test_cli_hold_text_explains_its_first_row_and_the_drift(am, capsys):
    """A loaded stack's first row is not a 0 N force, and the drift stands beside the legs' sag."""
    from assembler_pin.cli import main

    assert main(["simulate", "--home", "--seconds", "0.3", "--samples", "5"]) == 0
    lines = capsys.readouterr().out.splitlines()
    first = lines[2].split()
    assert first[0] == "0.000" and first[3] == "unloaded"
    assert all(float(line.split()[3]) > 10 for line in lines[3:7])
    note = " ".join(lines)
    sag = 1e3 * float(np.linalg.norm(__import__("assembler_pin").stiffness(am, am.home).sag_translation))
    assert f"the legs' sag alone ('assembler-pin stiffness'): {sag:.3f} mm" in note
    assert "ball joints" in note
