"""Internal-pose optimization: feasibility checked independently, monotone objective,
determinism, infeasible starts, the paper baseline."""

from __future__ import annotations

import numpy as np
import pytest
from checks import assert_feasible, design_objective, design_problems

from assembler_pin import AssemblerModel, GoalTolerance, load_config
from assembler_pin.optimize import OptimizeOptions, optimize_internal_poses


def _assert_feasible_independently(am, state, goal=None, tol=1e-9):
    """Every constraint of the paper, recomputed from the design (:mod:`checks`), the
    forces both by the package's statics and by free bodies."""
    assert_feasible(am, state, goal, tol)
    assert design_problems(am.config, state.plates, goal, tol) == []


@pytest.fixture(scope="module")
def start(random_poses):
    return random_poses[7][1]


def test_optimized_state_is_feasible_and_better(am, start):
    result = optimize_internal_poses(am, start)
    assert result.success and result.message == "converged"
    _assert_feasible_independently(am, result.optimized, goal=start.se3(am.n))
    assert result.objective_optimized <= result.objective_initial
    assert result.optimized.max_abs_force <= result.initial.max_abs_force
    # Ω (paper eq. 10) of both states, from free-body forces and plate normals (checks.py)
    assert result.objective_initial == pytest.approx(design_objective(am.config, start), rel=1e-9)
    assert result.objective_optimized == pytest.approx(design_objective(am.config, result.optimized.plates), rel=1e-9)
    # plate 0 and the EE did not move
    assert np.allclose(result.optimized.plates.as_matrices()[[0, -1]], start.as_matrices()[[0, -1]])


def test_smooth_method_beats_or_matches_the_paper_baseline(am, start):
    smooth = optimize_internal_poses(am, start)
    paper = optimize_internal_poses(am, start, options=OptimizeOptions(method="paper", max_iterations=60))
    _assert_feasible_independently(am, paper.optimized, goal=start.se3(am.n))
    assert paper.objective_optimized <= paper.objective_initial
    assert paper.objective_optimized == pytest.approx(design_objective(am.config, paper.optimized.plates), rel=1e-9)
    assert smooth.objective_optimized <= paper.objective_optimized + 1e-6
    assert smooth.evaluations < paper.evaluations


def test_weighted_objective_is_the_papers(am, start):
    """With w2 ≠ w1 the two terms of Ω are told apart: each weight on its own term."""
    result = optimize_internal_poses(am, start, options=OptimizeOptions(w1=0.5, w2=20.0))
    assert result.success
    assert result.objective_initial == pytest.approx(design_objective(am.config, start, 0.5, 20.0), rel=1e-9)
    optimized = design_objective(am.config, result.optimized.plates, 0.5, 20.0)
    assert result.objective_optimized == pytest.approx(optimized, rel=1e-9)
    assert optimized <= result.objective_initial
    _assert_feasible_independently(am, result.optimized, goal=start.se3(am.n))


def test_deterministic(am, start):
    a = optimize_internal_poses(am, start)
    b = optimize_internal_poses(am, start)
    assert np.array_equal(a.optimized.plates.as_matrices(), b.optimized.plates.as_matrices())
    assert a.iterations == b.iterations


def test_infeasible_start_is_driven_feasible(start):
    """Force limits between the optimum and the start: the start violates them."""
    am = AssemblerModel.from_config()
    first = optimize_internal_poses(am, start)
    limit = 0.5 * (first.initial.max_abs_force + first.optimized.max_abs_force)
    tight = AssemblerModel.from_config(load_config({"leg": {"max_tension": limit, "max_compression": limit}}))
    result = optimize_internal_poses(tight, start)
    assert not result.initial.feasible and {v.kind for v in result.initial.violations} <= {"tension", "compression"}
    assert result.success and result.optimized.feasible
    _assert_feasible_independently(tight, result.optimized)


def test_impossible_limits_are_reported_not_hidden(start):
    am = AssemblerModel.from_config(load_config({"leg": {"max_tension": 5, "max_compression": 5}}))
    result = optimize_internal_poses(am, start)
    assert not result.success and not result.optimized.feasible
    assert result.message.startswith("no feasible state found")


def test_free_end_effector_within_tolerance(am, start):
    tol = GoalTolerance(position=0.01, rotation=0.02)
    result = optimize_internal_poses(am, start, options=OptimizeOptions(ee_tolerance=tol))
    assert result.success
    goal = start.se3(am.n)
    ee = result.optimized.plates.se3(am.n)
    assert np.linalg.norm(ee.translation - goal.translation) <= tol.position + 1e-9
    fixed = optimize_internal_poses(am, start)
    assert result.objective_optimized <= fixed.objective_optimized + 1e-6


def test_bad_options():
    with pytest.raises(ValueError, match="method"):
        OptimizeOptions(method="newton")
    with pytest.raises(ValueError, match="weights"):
        OptimizeOptions(w1=0, w2=0)
