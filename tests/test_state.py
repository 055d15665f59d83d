"""evaluate_state: one call from plate poses to legs, statics and violations."""

from __future__ import annotations

import json

import numpy as np
from checks import kinematic_problems

import assembler_pin as ap


def test_feasible_exactly_when_every_constraint_holds(am, random_poses):
    leg = am.config.leg
    for _, plates in random_poses:
        state = ap.evaluate_state(am, plates)
        independent_ok = kinematic_problems(am.config, plates) == [] and np.all(
            np.abs(state.forces) <= max(leg.max_tension, leg.max_compression)
        )
        assert state.feasible == independent_ok
        assert state.feasible == (state.violations == [])


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
