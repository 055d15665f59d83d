"""The hexapod's MJCF in MuJoCo, a second engine: its masses, kinematics and constraint
Jacobian know nothing of our structure.

* At our equilibrium, MuJoCo's gravity is balanced by the actuators pulling with our forces,
  the ground pushing with our foot wrenches and the constraints (ball joints, welds) alone:
  the least-squares residual of ``qfrc_bias = qfrc_actuator + qfrc_feet + J_eqᵀ λ`` is rounding
  (1e-11 N of 292 N). This holds the statics; which of the statically admissible
  distributions the springs choose is held by the energy minimization of test_hexapod_stand.py.
* Simulated with the same commanded lengths on resting feet, MuJoCo's machine stands (no tip,
  every foot on the floor) and its feet carry what ours do within its soft constraints' error.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

import assembler_pin as ap
from assembler_pin.hexapod import ring_stacks, stand
from assembler_pin.hexapod.mjcf import BODY, hexapod_mjcf
from assembler_pin.simulate import MujocoStack


def _machine():
    am = ap.AssemblerModel.from_config({"platforms": 2, "payload": {"mass": 0.0}})
    stacks = ring_stacks(am, 3, 0.4)
    return am, stacks, np.array([0.03, -0.02, stacks[0].p[-1, 2] + 0.1])


def _id(m, kind, name):
    return mujoco.mj_name2id(m, kind, name)


def _set_equilibrium(m, d, am, result, feet):
    """MuJoCo's qpos at our equilibrium: each stack's joints in closed form, the feet and the body."""
    one = MujocoStack(am)
    for i in range(result.plates.shape[0]):
        pa = ap.kinematics.PlateArrays(result.plates[i, :, :3, :3], result.plates[i, :, :3, 3])
        start = m.jnt_qposadr[_id(m, mujoco.mjtObj.mjOBJ_JOINT, f"s{i}_sp0_leg0_ux")]
        q = one.qpos_from_plates(pa)
        d.qpos[start : start + len(q)] = q
        if feet == "resting":
            adr = m.jnt_qposadr[_id(m, mujoco.mjtObj.mjOBJ_JOINT, f"s{i}_foot")]
            x, y, z, w = pin.Quaternion(pa.R[0]).coeffs()
            d.qpos[adr : adr + 7] = [*pa.p[0], w, x, y, z]
    adr = m.jnt_qposadr[_id(m, mujoco.mjtObj.mjOBJ_JOINT, f"{BODY}_free")]
    x, y, z, w = pin.Quaternion(pin.exp3(result.body_displacement[3:])).coeffs()
    d.qpos[adr : adr + 7] = [*result.body_com, w, x, y, z]
    d.ctrl[:] = result.lengths.ravel()
    mujoco.mj_forward(m, d)


@pytest.mark.parametrize("feet", ["welded", "resting"])
def test_our_equilibrium_is_mujocos(feet):
    am, stacks, com = _machine()
    lengths = stand(am, stacks, 20.0, com).lengths + 3e-4 * np.cos(np.arange(36)).reshape(3, 2, 6)
    ours = stand(am, stacks, 20.0, com, lengths=lengths, feet=feet)
    assert ours.converged
    m = mujoco.MjModel.from_xml_string(hexapod_mjcf(am, stacks, 20.0, com, feet=feet))
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    d = mujoco.MjData(m)
    _set_equilibrium(m, d, am, ours, feet)
    rows = np.flatnonzero(d.efc_type[: d.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    assert np.abs(d.efc_pos[rows]).max() < 1e-9  # the loops and welds closed at our configuration
    J = d.efc_J[: d.nefc * m.nv].reshape(d.nefc, m.nv)[rows]
    act = np.zeros(m.nv)
    act[m.jnt_dofadr[m.actuator_trnid[:, 0]]] = -ours.forces.ravel()  # MuJoCo's force pushes: compression
    feet_q = np.zeros(m.nv)
    if feet == "resting":
        for i, w in enumerate(ours.foot_wrenches):
            body = _id(m, mujoco.mjtObj.mjOBJ_BODY, f"s{i}_plate_0")
            mujoco.mj_applyFT(m, d, w[:3].copy(), w[3:].copy(), ours.plates[i, 0, :3, 3].copy(), body, feet_q)
    rhs = d.qfrc_bias - act - feet_q
    lam = np.linalg.lstsq(J.T, rhs, rcond=None)[0]
    assert np.abs(J.T @ lam - rhs).max() <= 1e-8 * np.abs(rhs).max()


def test_mujoco_stands_on_resting_feet_with_our_foot_forces():
    am, stacks, com = _machine()
    ours = stand(am, stacks, 20.0, com, feet="resting")
    m = mujoco.MjModel.from_xml_string(hexapod_mjcf(am, stacks, 20.0, com, feet="resting"))
    d = mujoco.MjData(m)
    d.ctrl[:] = ours.lengths.ravel()
    for _ in range(3000):  # 3 s: the servos and the contacts settle
        mujoco.mj_step(m, d)
    assert np.abs(d.qvel).max() < 1e-6
    body = _id(m, mujoco.mjtObj.mjOBJ_BODY, BODY)
    tilt = np.degrees(np.arccos(np.clip(d.xmat[body].reshape(3, 3)[2, 2], -1, 1)))
    assert tilt < 0.1 and abs(d.xipos[body][2] - com[2]) < 2e-3  # standing, not tipped
    normal, f6 = np.zeros(3), np.zeros(6)
    for c in range(d.ncon):
        mujoco.mj_contactForce(m, d, c, f6)
        bodies = {m.geom_bodyid[d.contact[c].geom1], m.geom_bodyid[d.contact[c].geom2]}
        for i in range(3):
            if _id(m, mujoco.mjtObj.mjOBJ_BODY, f"s{i}_plate_0") in bodies:
                normal[i] += f6[0]
    weight = ours.mass * am.config.gravity
    assert normal.sum() == pytest.approx(weight, rel=1e-3)
    np.testing.assert_allclose(normal, ours.foot_wrenches[:, 2], atol=0.01 * weight)


def test_cli_exports_the_configured_hexapod(tmp_path):
    from assembler_pin.cli import main

    (tmp_path / "c.yaml").write_text("platforms: 2\nhexapod:\n  stacks: 4\n  body_mass: 12.0\n")
    assert main(["export", "--hexapod", "--config", str(tmp_path / "c.yaml"), "--out", str(tmp_path / "out")]) == 0
    m = mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "hexapod.xml"))
    assert m.nu == 4 * 2 * 6 and m.neq == 4 * (2 * 6 + 1)
    body = _id(m, mujoco.mjtObj.mjOBJ_BODY, BODY)
    assert m.body_mass[body] == 12.0
    # the whole machine's mass: the body and four stacks without a tool
    cfg = ap.load_config({"platforms": 2})
    stack = 3 * cfg.plate.mass + 12 * (cfg.leg.motor_mass + cfg.leg.shaft_mass)
    assert m.body_mass.sum() == pytest.approx(12.0 + 4 * stack, rel=1e-12)
    (tmp_path / "z.yaml").write_text("hexapod:\n  body_mass: 0.0\n")
    assert main(["export", "--hexapod", "--config", str(tmp_path / "z.yaml"), "--out", str(tmp_path / "z")]) == 2
    assert not (tmp_path / "z").exists()  # refused before any file is written
