"""The sag objectives and the sag limit of the optimizer: gradients against central finite
differences in the optimizer's chart, the sag-optimal pose against the force-optimal one,
its sag against the nonlinear elastic equilibrium, every constraint checked independently."""

from __future__ import annotations

import json

import numpy as np
import pytest
from checks import design_problems

from assembler_pin import loaded_pose
from assembler_pin.cli import main
from assembler_pin.common.messages import CAUSES
from assembler_pin.exceptions import OptionsError
from assembler_pin.helper_arm import initial_condition
from assembler_pin.kinematics import leg_vectors, plate_arrays
from assembler_pin.optimize import OptimizeOptions, optimize_internal_poses
from assembler_pin.optimize.problem import Problem
from assembler_pin.optimize.smooth import SmoothForm
from assembler_pin.scenarios import SCENARIOS

SCENARIO = "orientation_transition"


def _form(am, **options) -> tuple[SmoothForm, np.ndarray]:
    """The smooth form around the home pose (EE fixed at its home pose) and a chart point
    off the start."""
    home = plate_arrays(am, am.home)
    problem = Problem(am, home, home.se3(am.n), OptimizeOptions(**options), True)
    x = np.append(np.random.default_rng(3).uniform(-0.02, 0.02, problem.nx_pose), 40.0)
    return SmoothForm(problem), x


def _central(fun, x: np.ndarray, h: float = 1e-6) -> np.ndarray:
    cols = []
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h
        cols.append((np.asarray(fun(x + e)) - np.asarray(fun(x - e))) / (2 * h))
    return np.stack(cols, axis=-1)


@pytest.mark.parametrize("objective", ["sag", "weighted"])
def test_objective_gradient_matches_central_differences(am, objective):
    form, x = _form(am, objective=objective, sag_weight=0.7)
    grad = form.grad(x)
    fd = _central(form.fun, x)
    assert np.abs(grad).max() > 1.0  # the sag moves with the poses: a real test
    assert np.abs(grad - fd).max() <= 1e-6 * np.abs(grad).max()


def test_sag_row_jacobian_matches_central_differences(am):
    form, x = _form(am, objective="force", max_sag=1e-3)
    jac, fd = form.cons_jac(x), _central(form.cons, x)
    assert jac.shape == fd.shape
    sag_row, sag_fd = jac[-1], fd[-1]  # the sag row comes last
    assert np.abs(sag_row).max() > 0.1  # [1/m]: the sag row moves with the poses
    assert np.abs(sag_row - sag_fd).max() <= 1e-6 * np.abs(sag_row).max()
    assert np.abs(jac - fd).max() <= 1e-6 * np.abs(jac).max()


@pytest.fixture(scope="module")
def solved(am):
    """The scenario's helper-arm start and its force-, sag- and weighted-optimal results."""
    goal = SCENARIOS[SCENARIO].goal
    start = initial_condition(am, goal).state
    runs = {
        kind: optimize_internal_poses(am, start, goal, OptimizeOptions(objective=kind))
        for kind in ("force", "sag", "weighted")
    }
    return goal, start, runs


def _loaded_sag(am, state) -> float:
    """The EE's sag [m] of the nonlinear elastic equilibrium, commanding the pose's own lengths."""
    lengths = leg_vectors(am, state.plates)[3]
    lp = loaded_pose(am, lengths, base=state.plates.se3(0))
    assert lp.success, lp.message
    np.testing.assert_allclose(lp.rigid.p, state.plates.p, atol=1e-9)  # the pose is the rigid one
    return float(np.linalg.norm(lp.translation))


def test_sag_optimum_against_force_optimum(am, solved):
    goal, _, runs = solved
    force, sag, weighted = runs["force"], runs["sag"], runs["weighted"]
    assert force.success and sag.success and weighted.success, [r.message for r in runs.values()]
    sags = {k: _loaded_sag(am, r.optimized) for k, r in runs.items()}
    for kind, r in runs.items():
        # the reported (linear) sag within 1% of the nonlinear equilibrium's
        assert r.sag_optimized == pytest.approx(sags[kind], rel=1e-2)
        assert design_problems(am.config, r.optimized.plates, goal=goal, tol=1e-9) == []
    assert sags["sag"] < sags["force"]
    assert sag.optimized.max_abs_force >= force.optimized.max_abs_force
    # the weighted optimum lies between the two
    assert sags["sag"] <= sags["weighted"] <= sags["force"]
    assert force.optimized.max_abs_force <= weighted.optimized.max_abs_force <= sag.optimized.max_abs_force


def test_sag_limit_is_held(am, solved):
    goal, start, runs = solved
    limit = 0.5 * (runs["force"].sag_optimized + runs["sag"].sag_optimized)
    r = optimize_internal_poses(am, start, goal, OptimizeOptions(max_sag=limit))
    assert r.success, r.message
    assert _loaded_sag(am, r.optimized) <= 1.01 * limit and r.sag_optimized <= limit
    assert design_problems(am.config, r.optimized.plates, goal=goal, tol=1e-9) == []
    # the force is the price of the limit: no better than the unconstrained force optimum
    assert r.optimized.max_abs_force >= runs["force"].optimized.max_abs_force - 1e-6


def test_sag_limit_out_of_reach_is_no_success(am, solved):
    goal, start, runs = solved
    limit = 0.5 * runs["sag"].sag_optimized
    r = optimize_internal_poses(am, start, goal, OptimizeOptions(max_sag=limit, max_iterations=30))
    assert not r.success
    assert r.message.startswith("sag limit:") and "sag limit" in CAUSES
    assert r.optimized.feasible  # a state that meets every other limit is still returned
    assert r.sag_optimized > limit


@pytest.mark.parametrize(
    "options, named",
    [
        ({"objective": "stiff"}, "objective must be one of force, sag, weighted"),
        ({"objective": "weighted", "sag_weight": 0.0}, "sag_weight"),
        ({"objective": "weighted", "sag_weight": float("nan")}, "sag_weight"),
        ({"max_sag": -1e-3}, "max_sag"),
        ({"max_sag": float("inf")}, "max_sag"),
        ({"objective": "sag", "method": "paper"}, "need method 'slsqp'"),
        ({"max_sag": 1e-3, "method": "paper"}, "need method 'slsqp'"),
    ],
)
def test_bad_sag_options_are_refused(options, named):
    with pytest.raises(OptionsError, match=named):
        OptimizeOptions(**options)


def _cli(capsys, *argv: str) -> tuple[int, str, str]:
    status = main(["-q", *argv])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def test_cli_sag_objective_and_limit(capsys):
    goal = [f"{x:.9f}" for x in SCENARIOS[SCENARIO].goal_taa]
    status, out, err = _cli(capsys, "solve", "--goal", *goal, "--objective", "sag", "--json")
    assert status == 0, err
    doc = json.loads(out)
    assert doc["success"] and doc["sag"]["objective"] == "sag"
    sag = doc["sag"]["answer"]["sag_m"]
    assert 0 < sag < doc["sag"]["initial"]["sag_m"]
    status, out, err = _cli(capsys, "solve", "--goal", *goal, "--max-sag", f"{0.5 * sag:.9f}", "--json")
    assert status == 1 and err == ""
    doc = json.loads(out)
    assert not doc["success"] and doc["message"].startswith("sag limit:")
    assert doc["sag"]["max_sag_m"] == pytest.approx(0.5 * sag)


@pytest.mark.parametrize(
    "argv, named",
    [
        (["--objective", "stiff"], "--objective"),
        (["--max-sag", "0"], "--max-sag"),
        (["--max-sag", "nan"], "--max-sag"),
        (["--sag-weight", "2"], "--sag-weight"),
        (["--objective", "weighted", "--sag-weight", "-1"], "--sag-weight"),
        (["--objective", "sag", "--method", "paper"], "slsqp"),
        (["--objective", "sag", "--no-optimize"], "--objective"),
    ],
)
def test_cli_refuses_bad_sag_options(capsys, argv, named):
    status, out, err = _cli(capsys, "solve", "--goal", "0", "0", "0.9", "0", "0", "0", *argv)
    assert status == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and named in err
