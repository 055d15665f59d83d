"""evaluate_state: one call from plate poses to legs, statics and violations."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from checks import design_forces, design_problems

import assembler_pin as ap

#: limits that split the random poses into feasible and infeasible ones, each by one rule
_TIGHT = {
    "default": {},
    "tension": {"leg": {"max_tension": 40.0}},
    "compression": {"leg": {"max_compression": 75.0}},
    "deflection": {"leg": {"max_deflection_deg": 27.0}},
    "stroke": {"leg": {"min_length": 0.222, "max_length": 0.32}},
    "goal": {},
}


def test_forces_equal_the_free_body_statics(am, random_poses):
    """Pinocchio's statics against a second method: free bodies of the legs and plates."""
    for _, plates in random_poses:
        forces = ap.evaluate_state(am, plates).forces
        reference = design_forces(am.config, plates)
        np.testing.assert_allclose(forces, reference, rtol=1e-9, atol=1e-9 * np.abs(reference).max())


@pytest.mark.parametrize("limits", list(_TIGHT))
def test_feasible_exactly_when_the_design_checks_pass(random_poses, limits):
    """`feasible` against every constraint recomputed from the design (forces included)."""
    am = ap.AssemblerModel.from_config(ap.load_config(_TIGHT[limits]))
    tol = ap.constraints.GoalTolerance()
    assert tol.position == tol.rotation
    verdicts = []
    for k, (_, plates) in enumerate(random_poses):
        goal = plates.se3(am.n)
        if limits == "goal" and k % 2:  # every other goal a little off, in position or in rotation
            goal = goal * pin.exp6(np.roll([3 * tol.position, 0, 0, 0, 0, 0], 3 * (k % 4 == 1)))
        state = ap.evaluate_state(am, plates, goal=goal, tolerance=tol)
        problems = design_problems(am.config, plates, goal=goal, tol=tol.position)
        assert state.feasible == (problems == []), problems
        verdicts.append(state.feasible)
    if limits == "default":
        assert all(verdicts)
    else:
        assert any(verdicts) and not all(verdicts), f"the {limits} case does not split the poses"


def test_a_stretched_leg_is_reported_with_its_place_and_amount(am, random_poses):
    lengths, _ = random_poses[0]
    lengths = lengths.copy()
    lengths[2, 4] = am.config.leg.max_length + 0.01
    plates = ap.stack_forward_kinematics(am, lengths).raise_if_failed()
    state = ap.evaluate_state(am, plates)
    hits = [v for v in state.violations if v.kind == "max_length"]
    assert [(v.platform, v.leg) for v in hits] == [(2, 4)]
    assert abs(hits[0].amount - 0.01) < 1e-9


def test_to_dict_is_strict_json_and_matches_the_state(am, random_poses):
    state = ap.evaluate_state(am, random_poses[3][1])
    doc = json.loads(json.dumps(state.to_dict(), allow_nan=False))
    np.testing.assert_allclose(doc["forces"], state.forces)
    np.testing.assert_allclose(doc["leg_lengths"], state.leg_lengths)
    assert doc["max_abs_force"] == state.max_abs_force and doc["feasible"] == state.feasible


def test_a_caller_data_gives_the_same_state(am, random_poses):
    """The state on the caller's whole-stack Data: forces of the free-body statics."""
    data = am.create_data()
    for _, plates in random_poses[:2]:
        state = ap.evaluate_state(am, plates, data=data)
        reference = design_forces(am.config, plates)
        np.testing.assert_allclose(state.forces, reference, rtol=0, atol=1e-9 * np.abs(reference).max())
        assert state.feasible == (design_problems(am.config, plates) == [])
