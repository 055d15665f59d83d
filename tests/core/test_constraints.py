"""Constraint evaluation: each class of the paper is detected with its amount."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from assembler_pin import AssemblerModel, evaluate_state, load_config
from assembler_pin.config.options import GoalTolerance
from assembler_pin.kinematics import PlateArrays, plate_arrays


def _kinds(state):
    return {v.kind for v in state.violations}


def _lift_top(am, dz, k=1):
    """Home pose with plate k and everything above moved up by dz."""
    pa = plate_arrays(am, am.home)
    p = pa.p.copy()
    p[k:, 2] += dz
    return PlateArrays(pa.R.copy(), p)


def test_home_is_feasible(am):
    state = evaluate_state(am, am.home, goal=am.home[-1])
    assert state.feasible and state.violations == []


def test_length_limits(am):
    too_long = evaluate_state(am, _lift_top(am, 0.1))
    assert "max_length" in _kinds(too_long)
    v = next(v for v in too_long.violations if v.kind == "max_length")
    assert v.limit == 0.35 and v.value > 0.35 and v.amount == v.value - 0.35
    assert {(w.platform, w.leg) for w in too_long.violations if w.kind == "max_length"} == {(0, i) for i in range(6)}
    too_short = evaluate_state(am, _lift_top(am, -0.1))
    assert "min_length" in _kinds(too_short)


def test_deflection_limit(am):
    pa = plate_arrays(am, am.home)
    p = pa.p.copy()
    p[1:, 0] += 0.25  # shear platform 0 sideways: legs lean far from their home direction
    state = evaluate_state(am, PlateArrays(pa.R.copy(), p))
    assert {"deflection_bottom", "deflection_top"} <= _kinds(state)
    worst = max(v.value for v in state.violations if v.kind == "deflection_bottom")
    assert worst > np.deg2rad(45)


def test_force_limits():
    cfg = load_config({"payload": {"mass": 150.0}})
    am = AssemblerModel.from_config(cfg)
    state = evaluate_state(am, am.home)
    assert "compression" in _kinds(state) and not state.feasible
    v = next(v for v in state.violations if v.kind == "compression")
    assert v.value < -200 and v.limit == -200
    cfg = load_config({"gravity": 9.81, "payload": {"mass": 150.0, "offset": -0.8}})
    hanging = AssemblerModel.from_config(cfg)
    flipped = [m * pin.SE3(pin.exp3(np.array([np.pi, 0, 0])), np.zeros(3)) for m in hanging.home]
    flipped = [pin.SE3(pin.exp3(np.array([np.pi, 0, 0])), np.zeros(3)) * m for m in hanging.home]
    state = evaluate_state(hanging, flipped)  # stack hanging upside down: legs in tension
    assert "tension" in _kinds(state)


def test_continuous_translation(am):
    state = evaluate_state(am, _lift_top(am, -0.3))
    assert "continuous_translation" in _kinds(state)


def test_goal_tolerance(am):
    goal = am.home[-1] * pin.SE3(np.eye(3), np.array([0.0, 0.0, 1e-3]))
    state = evaluate_state(am, am.home, goal=goal)
    assert _kinds(state) == {"ee_position"}
    v = state.violations[0]
    assert abs(v.value - 1e-3) < 1e-12 and v.platform is None
    assert evaluate_state(am, am.home, goal=goal, tolerance=GoalTolerance(position=2e-3)).feasible
    turned = am.home[-1] * pin.SE3(pin.exp3(np.array([0, 0, 0.01])), np.zeros(3))
    state = evaluate_state(am, am.home, goal=turned)
    assert _kinds(state) == {"ee_rotation"} and abs(state.violations[0].value - 0.01) < 1e-12
