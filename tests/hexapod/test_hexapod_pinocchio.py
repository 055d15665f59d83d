"""The hexapod's equilibrium held to Pinocchio's whole-stack model and its constraint API: each
stack is its URDF model (plate 0 a free flyer), its ball joints Pinocchio's constraints; at our
equilibrium its gravity is balanced by the springs' forces (ours), the ground's wrench on the
foot (ours) and a wrench from the body on the EE plate, with nothing left over; and the body,
a free flyer, is balanced by its weight and those wrenches."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import assembler_pin as ap
from assembler_pin.common.naming import names
from assembler_pin.hexapod import ring_stacks, stand


def _frame_jacobian(am, q, plate):
    data = am.model.createData()
    pin.computeJointJacobians(am.model, data, q)
    pin.framesForwardKinematics(am.model, data, q)
    frame = am.model.getFrameId(names.plate(plate))
    return pin.getFrameJacobian(am.model, data, frame, pin.LOCAL_WORLD_ALIGNED)


def _stack_balance(am, plates, forces, foot_wrench):
    """(residual [N], the body's wrench on the EE plate (6,), world axes at its origin)."""
    model, data = am.model, am.data
    pa = ap.kinematics.PlateArrays(plates[:, :3, :3], plates[:, :3, 3])
    q = ap.kinematics.q_from_plates(am, pa)
    g = pin.computeGeneralizedGravity(model, data, q)
    pin.computeJointJacobians(model, data, q)
    for cm, cd in zip(am.constraint_models, am.constraint_datas, strict=True):
        cm.calc(model, data, cd)
    jc = pin.getConstraintsJacobian(model, data, am.constraint_models, am.constraint_datas)
    select = np.zeros((6 * am.n, model.nv))
    select[np.arange(6 * am.n), am.leg_idx_v[:, :, 2].ravel()] = 1.0
    J0, Jn = _frame_jacobian(am, q, 0), _frame_jacobian(am, q, am.n)
    rhs = g - select.T @ (-forces.ravel()) - J0.T @ foot_wrench
    A = np.hstack([jc.T, Jn.T])
    x = np.linalg.lstsq(A, rhs, rcond=None)[0]
    return float(np.abs(A @ x - rhs).max()), x[-6:], float(np.abs(rhs).max())


@pytest.mark.parametrize("feet", ["welded", "resting"])
def test_every_stack_and_the_body_balance_in_pinocchio(feet):
    am = ap.AssemblerModel.from_config({"platforms": 2, "payload": {"mass": 0.0}})
    stacks = ring_stacks(am, 3, 0.4)
    com = np.array([0.03, -0.02, stacks[0].p[-1, 2] + 0.1])
    lengths = stand(am, stacks, 20.0, com).lengths + 3e-4 * np.sin(np.arange(36)).reshape(3, 2, 6)
    ours = stand(am, stacks, 20.0, com, lengths=lengths, feet=feet)
    body = np.zeros(6)
    for i in range(3):
        residual, w_ee, scale = _stack_balance(am, ours.plates[i], ours.forces[i], ours.foot_wrenches[i])
        assert residual <= 1e-9 * scale
        r = ours.plates[i, -1, :3, 3] - ours.body_com
        body += np.concatenate([w_ee[:3], w_ee[3:] + np.cross(r, w_ee[:3])])
    # what the body applies to the EE plates is its weight, at its centre of mass
    np.testing.assert_allclose(body, [0, 0, -20.0 * am.config.gravity, 0, 0, 0], atol=1e-8)
