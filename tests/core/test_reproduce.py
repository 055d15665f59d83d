"""`reproduce`: the scenario table and its reference columns (random valid poses, multistart)."""

from __future__ import annotations

import numpy as np
import pytest
from checks import design_problems, sp_legs

from assembler_pin import stack_forward_kinematics
from assembler_pin.reproduce import random_valid_poses, run_scenarios, summary_table


@pytest.fixture(scope="module")
def outcome(am):
    return run_scenarios(am, ["orientation_transition"])[0]


def test_random_valid_poses_are_valid_independently(am, outcome):
    goal = outcome.scenario.goal
    poses = random_valid_poses(am, goal, outcome.initial, 4)
    assert poses
    cfg = am.config
    for state in poses:
        pa = state.plates
        # every constraint from the design anchors and free-body forces (checks.py)
        assert design_problems(cfg, pa, goal=goal, tol=1e-9) == []
        lengths = np.array([sp_legs(cfg, j, pa.R[j], pa.p[j], pa.R[j + 1], pa.p[j + 1])[0] for j in range(am.n)])
        fk = stack_forward_kinematics(am, lengths).raise_if_failed()
        np.testing.assert_allclose(fk.as_matrices()[-1], goal.homogeneous, atol=1e-9)
    # they are different poses, not one pose repeated
    assert len({round(float(s.max_abs_force), 6) for s in poses}) == len(poses)


def test_reference_columns(outcome):
    ref, ours = outcome.reference, outcome.optimized.max_abs_force
    assert ref is not None and ref.multistart_best <= ours + 1e-9
    assert ref.worst >= ref.median
    # the optimum is no worse than a typical valid pose, and the table shows both columns
    assert ours <= ref.median
    table = summary_table([outcome])
    assert "vs median / worst random valid pose" in table and "gap to multistart" in table
    assert f"{100 * (1 - ours / ref.median):.0f}%" in table


def test_sag_table_sets_the_sag_optimum_beside_the_force_optimum(am, outcome):
    from assembler_pin import loaded_pose
    from assembler_pin.kinematics import leg_vectors
    from assembler_pin.reproduce import sag_table

    force, sag = outcome.optimized, outcome.sag_result.optimized
    assert outcome.sag_result.success and design_problems(am.config, sag.plates, goal=outcome.scenario.goal) == []

    def loaded(state) -> float:  # the nonlinear elastic equilibrium of the pose's own lengths
        lp = loaded_pose(am, leg_vectors(am, state.plates)[3], base=state.plates.se3(0))
        assert lp.success
        return float(np.linalg.norm(lp.translation))

    sag_force, sag_sag = loaded(force), loaded(sag)
    assert sag_sag < sag_force and sag.max_abs_force >= force.max_abs_force
    text = sag_table(am, [outcome])
    assert max(len(line) for line in text.splitlines()) <= 100
    row = text.splitlines()[-1].split()
    assert row[0] == "orientation_transition"
    assert float(row[1]) == pytest.approx(force.max_abs_force, abs=0.05)
    assert float(row[2]) == pytest.approx(1e3 * sag_force, rel=1e-2)
    assert float(row[4]) == pytest.approx(sag.max_abs_force, abs=0.05)
    assert float(row[5]) == pytest.approx(1e3 * sag_sag, rel=1e-2)
    md = sag_table(am, [outcome], markdown=True).splitlines()
    assert len(md) == 3 and md[0].count(" | ") == 7 and "max\\|F\\|" in md[0]
