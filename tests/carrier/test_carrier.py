"""The stack on a carrier arm: torques and leg forces held to two independent routes.

(a) the carrier's torques against its own gravity torques plus the stack's base wrench pushed
through the Jacobian transpose of a frame at the base plate; (b) the mounted leg forces against
the fixed-base stack with gravity rotated into the base plate's frame, solved on the
whole-stack Pinocchio model with Pinocchio's own constraint Jacobian.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from checks import design_forces, design_plate_deviation, kinematic_problems, whole_stack_forces

import assembler_pin as ap
from assembler_pin.bench.timing import random_reachable_plates
from assembler_pin.carrier import (
    CARRIERS,
    Carrier,
    UnknownCarrierError,
    carrier_objective,
    carrier_statics,
    solve_on_carrier,
)
from assembler_pin.cli import main

MOUNTS = {
    "flange": pin.SE3.Identity(),
    "sideways": pin.SE3(pin.exp3(np.array([np.pi / 2, 0, 0])), np.array([0.0, 0.05, 0.02])),
    "upside_down": pin.SE3(pin.exp3(np.array([np.pi, 0, 0])), np.array([0.0, 0.0, 0.03])),
}


@pytest.fixture(scope="module")
def carriers():
    return {name: Carrier(name) for name in ("ur10", "panda", "ur5")}


@pytest.mark.parametrize("mount", list(MOUNTS))
@pytest.mark.parametrize("name", ["ur10", "panda", "ur5"])
def test_torques_equal_gravity_plus_jacobian_transpose_of_the_base_wrench(am, name, mount):
    carrier = Carrier(name, MOUNTS[mount])
    rng = np.random.default_rng(7)
    _, plates = random_reachable_plates(am, rng)
    for q in (carrier.upright_q, carrier.upright_q + rng.uniform(-0.3, 0.3, carrier.model.nq)):
        q = np.clip(q, carrier.lower, carrier.upper)
        st = carrier_statics(am, carrier, q, plates)
        # (a) on a fresh model and data: g(q) + Jᵀ·w, w the wrench the mount applies to plate 0
        model = carrier.model.copy()
        data = model.createData()
        g = pin.computeGeneralizedGravity(model, data, q)
        J = pin.computeFrameJacobian(model, data, q, carrier.base_frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        expected = g + J.T @ st.state.statics.base_wrench
        np.testing.assert_allclose(st.torques, expected, atol=1e-9)
        # the base plate is where the carrier's FK puts the tool frame times the mount
        pin.framesForwardKinematics(model, data, q)
        tool = data.oMf[model.getFrameId(CARRIERS[name].tool_frame)]
        assert st.state.plates.se3(0).isApprox(tool * MOUNTS[mount], 1e-12)


@pytest.mark.parametrize("mount", list(MOUNTS))
def test_mounted_forces_equal_fixed_base_statics_with_gravity_rotated(am, carriers, mount):
    carrier = Carrier("ur10", MOUNTS[mount])
    _, plates = random_reachable_plates(am, np.random.default_rng(11))
    q = carrier.upright_q
    st = carrier_statics(am, carrier, q, plates)
    R = carrier.base_pose(q).rotation
    fixed = ap.AssemblerModel.from_config()
    fixed.model.gravity.linear = R.T @ np.array([0.0, 0.0, -fixed.config.gravity])
    np.testing.assert_allclose(st.state.forces, whole_stack_forces(fixed, plates), atol=1e-9)
    if mount == "upside_down":  # hanging: the legs pull where they pushed
        assert st.state.forces.mean() > 0 > ap.evaluate_state(am, am.home).forces.mean()


def test_solve_in_the_world_with_and_without_moving_the_carrier(am, carriers):
    carrier = carriers["ur10"]
    base = carrier.base_pose(carrier.upright_q)
    goal = base * ap.scenario("translation").goal
    held = solve_on_carrier(am, carrier, goal, move_carrier=False)
    moved = solve_on_carrier(am, carrier, goal)
    for result in (held, moved):
        assert result.success, result.message
        st = result.statics
        # the world goal is reached: the stack FK of the legs from the carrier's base plate
        fk = ap.stack_forward_kinematics(am, st.state.leg_lengths, base=carrier.base_pose(st.q), guess=st.state.plates)
        assert fk.success and fk.plates.se3(am.n).isApprox(goal, 1e-6)
        assert kinematic_problems(am.config, st.state.plates, goal=goal, tol=1e-6) == []
        assert np.all(st.q >= carrier.lower) and np.all(st.q <= carrier.upper)
        assert result.binding in ("stack", "carrier") and st.within_limits
    np.testing.assert_allclose(held.statics.q, carrier.upright_q)

    # moving the carrier never scores worse than holding it (holding is one of the candidates);
    # Ω_c recomputed here from its definition: free-body forces and λ of the world plates (checks.py)
    def omega(st):
        lam = design_plate_deviation(st.state.plates)
        forces = design_forces(am.config, st.state.plates)
        np.testing.assert_allclose(st.state.forces, forces, rtol=1e-9, atol=1e-9)
        return (
            np.abs(forces).max() + np.sqrt(np.sum(lam**2)) + 200.0 * np.max(np.abs(st.torques) / carrier.effort_limit)
        )

    assert held.candidates[0][2] == pytest.approx(omega(held.statics), rel=1e-9)  # the score it ranked by
    assert omega(moved.statics) <= omega(held.statics) + 1e-9
    assert carrier_objective(am, moved.statics) == pytest.approx(omega(moved.statics), rel=1e-9)
    assert np.isnan(moved.candidates[-1][0]) and "joint optimization" in moved.candidates[-1][3]
    assert "array(" not in repr(moved)


def test_an_overloaded_carrier_is_not_within_limits(am):
    heavy = ap.AssemblerModel.from_config({"payload": {"mass": 60.0}})
    panda = Carrier("panda")
    st = carrier_statics(heavy, panda, panda.upright_q, heavy.home)
    assert st.carrier_ratio > 1 and not st.within_limits and st.binding == "carrier"


def test_unknown_carrier_and_bad_q_are_one_line_errors(capsys):
    with pytest.raises(UnknownCarrierError, match="supported: ur3, ur5, ur10, panda"):
        Carrier("abb_irb")
    assert main(["statics", "--home", "--carrier", "abb_irb"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "supported: ur3, ur5, ur10, panda" in err[0]
    assert main(["statics", "--home", "--carrier", "ur10", "--carrier-q", "0", "0"]) == 2
    assert "6 finite joint angles" in capsys.readouterr().err
    assert main(["statics", "--home", "--carrier-q", "0"]) == 2


def test_cli_statics_on_a_carrier(am, carriers, capsys):
    assert main(["statics", "--home", "--carrier", "ur10", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    st = carrier_statics(am, carriers["ur10"], carriers["ur10"].upright_q, am.home)
    np.testing.assert_allclose(doc["carrier_torques"], st.torques, atol=1e-9)
    np.testing.assert_allclose(doc["forces"], st.state.forces, atol=1e-9)
    assert doc["binding"] in ("stack", "carrier")
