"""Internal-pose optimization: feasibility checked independently, monotone objective,
determinism, infeasible starts, the paper baseline."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from checks import assert_feasible, design_objective, design_problems

from assembler_pin import AssemblerModel, load_config
from assembler_pin.config.options import GoalTolerance
from assembler_pin.optimize import OptimizeOptions, optimize_internal_poses

HAS_NUMBA = importlib.util.find_spec("numba") is not None


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


def test_iterates_take_one_compiled_call_per_point(am, start, monkeypatch):
    """Each point takes one compiled call for its values and one for its derivatives (and the
    start one, for its max|F|: the force cap); the numpy pass never runs, and the statics of
    :func:`~assembler_pin.state.evaluate_state` only re-check returned states."""
    import assembler_pin.optimize.problem as problem
    import assembler_pin.state as state_module
    from assembler_pin.statics.pose_kernel import CompiledPass

    calls = {"values": 0, "derivatives": 0, "numpy": 0, "statics": 0}
    real_values, real_derivatives, real_numpy = CompiledPass.values, CompiledPass.derivatives, problem.pose_values

    def counted(key, real):
        def call(*args, **kwargs):
            calls[key] += 1
            return real(*args, **kwargs)

        return call

    monkeypatch.setattr(CompiledPass, "values", counted("values", real_values))
    monkeypatch.setattr(CompiledPass, "derivatives", counted("derivatives", real_derivatives))
    monkeypatch.setattr(problem, "pose_values", counted("numpy", real_numpy))
    monkeypatch.setattr(state_module, "solve_statics", counted("statics", state_module.solve_statics))
    result = optimize_internal_poses(am, start)
    assert result.success
    assert calls["values"] == result.evaluations + 1 + 2 and calls["numpy"] == 0  # + the optimality check's
    assert calls["derivatives"] == result.gradient_evaluations + 1 > 1
    # the start, the answer, the best point met and at most four pull-back trials
    assert 2 <= calls["statics"] <= 7 < result.evaluations
    _assert_feasible_independently(am, result.optimized, goal=start.se3(am.n))


def test_smooth_form_derivatives_match_finite_differences(start):
    """Objective gradient and every constraint row's Jacobian (epigraph, unequal force
    limits, leg limits, EE tolerance, motion step) against central differences."""
    from assembler_pin.kinematics import leg_state
    from assembler_pin.optimize import MotionTerm
    from assembler_pin.optimize.problem import Problem
    from assembler_pin.optimize.smooth import SmoothForm

    am = AssemblerModel.from_config(load_config({"leg": {"max_tension": 150.0, "max_compression": 120.0}}))
    opts = OptimizeOptions(w1=0.7, w2=3.0, ee_tolerance=GoalTolerance(position=0.01, rotation=0.02))
    motion = MotionTerm(leg_state(am, start).lengths + 0.003, max_step=0.02, w3=50.0)
    form = SmoothForm(Problem(am, start, start.se3(am.n), opts, False, motion))
    rng = np.random.default_rng(3)
    x = np.concatenate([rng.normal(0.0, 0.01, form.problem.nx_pose), [60.0]])
    grad, jac = form.grad(x), form.cons_jac(x)
    h = 1e-6
    fd_grad, fd_jac = np.zeros_like(grad), np.zeros_like(jac)
    for c in range(x.size):
        e = np.zeros_like(x)
        e[c] = h
        fd_grad[c] = (form.fun(x + e) - form.fun(x - e)) / (2 * h)
        fd_jac[:, c] = (form.cons(x + e) - form.cons(x - e)) / (2 * h)
    assert np.abs(grad - fd_grad).max() <= 1e-6 * np.abs(fd_grad).max()
    row_scale = np.abs(fd_jac).max(axis=1, keepdims=True)  # each row held at its own scale
    assert np.all(np.abs(jac - fd_jac) <= 1e-6 * row_scale + 1e-10)
    assert jac.shape[0] == 2 * 24 + 2 * 24 + 5 * 24 + 2 + 2 * 24  # every family present


def test_auto_method_is_slsqp_bit_for_bit_on_short_stacks(am, start):
    """``method="auto"`` below :data:`~assembler_pin.config.options.AUTO_IPOPT_PLATFORMS` is SLSQP:
    the same plates to the last bit, and the result names the method that ran."""
    from assembler_pin.config.options import AUTO_IPOPT_PLATFORMS

    assert am.n < AUTO_IPOPT_PLATFORMS
    slsqp = optimize_internal_poses(am, start)
    auto = optimize_internal_poses(am, start, options=OptimizeOptions(method="auto"))
    assert auto.method == "slsqp" and auto.success
    assert np.array_equal(auto.optimized.plates.as_matrices(), slsqp.optimized.plates.as_matrices())
