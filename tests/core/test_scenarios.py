"""The representative goals of the paper's §V: each is solved validly by the helper arm.

Validity is checked independently (stack FK of the returned leg lengths, constraints
recomputed from the design anchors; see ``test_helper_arm``).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from checks import check_result

from assembler_pin import SCENARIOS, AssemblerError, initial_condition, scenario
from assembler_pin.scenarios import Scenario

PAPER = {  # §V: initial -> optimized, max |F| and mean |F| [N]
    "translation": (145.6, 43.8, 50.0, 27.0),
    "ninety_degrees": (40.9, 20.2, 20.2, 15.0),
    "inchworm": (80.6, 52.7, 25.9, 28.3),
    "vertical_lift": (73.1, 47.9, 26.5, 31.0),
    "orientation_transition": (66.2, 31.3, 24.5, 17.7),
}


def test_the_five_scenarios_of_the_paper():
    assert list(SCENARIOS) == list(PAPER)
    for name, figures in PAPER.items():
        s = scenario(name)
        assert isinstance(s, Scenario) and s.name == name and s.title and len(s.description) > 80
        got = (
            s.paper_initial_max_force,
            s.paper_optimized_max_force,
            s.paper_initial_mean_force,
            s.paper_optimized_mean_force,
        )
        assert got == figures
        R = s.goal.rotation
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(s.goal_matrix, s.goal.homogeneous)
        np.testing.assert_allclose(pin.exp3(s.goal_taa[3:]), R, atol=1e-12)


@pytest.mark.parametrize("name", list(PAPER))
def test_scenario_is_solved_validly(am, name):
    s = scenario(name)
    result = initial_condition(am, s.goal)
    check_result(am, result)


def test_scenario_geometry_matches_its_intent():
    z = np.array([0.0, 0.0, 1.0])

    def tilt_deg(s: Scenario) -> float:
        return float(np.rad2deg(np.arccos(s.goal.rotation[:, 2] @ z)))

    assert tilt_deg(scenario("translation")) == pytest.approx(0.0, abs=1e-9)
    assert scenario("translation").goal.translation[0] >= 0.5
    assert tilt_deg(scenario("ninety_degrees")) == pytest.approx(90.0, abs=1e-9)
    for name in ("inchworm", "vertical_lift"):  # EE facing the floor, beside the base, low
        s = scenario(name)
        assert tilt_deg(s) >= 135.0
        assert s.goal.translation[2] < 0.3 and np.hypot(*s.goal.translation[:2]) > 0.5
    assert 30.0 < tilt_deg(scenario("orientation_transition")) < 60.0


def test_unknown_scenario_lists_the_names():
    with pytest.raises(AssemblerError) as info:
        scenario("moonwalk")
    message = str(info.value)
    assert "moonwalk" in message and all(name in message for name in PAPER)
