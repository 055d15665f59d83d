"""The optimizer and solve at the edges of the envelope: degraded optima, the start
portfolio, a stack without internal plates, singular trial points, goals out of reach."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pinocchio as pin
import pytest
from checks import assert_feasible

from assembler_pin import AssemblerModel, solve_statics
from assembler_pin.cli import main
from assembler_pin.kinematics import taa_to_se3
from assembler_pin.optimize import OptimizeOptions, optimize_internal_poses
from assembler_pin.solver import solve
from assembler_pin.solver.starts import STARTS

#: Why the tests marked with it fail today (known, open).
OWN_PLATE_RULE = (
    "the check of each leg against its own plates refuses the leaning poses these goals were answered "
    "with (a motor inside a plate); the optimizer does not yet find a clear pose for all of them"
)


HAS_NUMBA = importlib.util.find_spec("numba") is not None

# A goal (the EE of random in-stroke lengths) whose converged optimum used to sit 1e-8 past a
# deflection row: it was rejected and the start returned as a success, 24% above the optimum.
DEGRADED_GOAL = [-0.067917, 0.231621, 0.923905, 0.190194, -0.388074, 0.041778]


def test_a_converged_optimum_is_not_lost_to_the_strict_check(am):
    goal = taa_to_se3(DEGRADED_GOAL)
    result = solve(am, goal)
    assert result.success
    assert_feasible(am, result.optimized, goal)
    # an independent restart from the returned optimum finds nothing better
    again = optimize_internal_poses(am, result.optimized, goal)
    assert again.optimized.max_abs_force >= result.optimized.max_abs_force * (1 - 1e-3)


def test_a_rejected_converged_point_is_never_a_success(am):
    # rows that let the solver end 1e-5 past the limits: its converged point breaks one
    options = OptimizeOptions(method="slsqp")
    object.__setattr__(options, "limit_margin", -1e-5)  # past the validation, on purpose
    goal = taa_to_se3(DEGRADED_GOAL)
    init = solve(am, goal, optimize=False).initial
    result = optimize_internal_poses(am, init, goal, options)
    # the returned state is valid by the strict check (success means exactly that)
    assert result.success and result.optimized.feasible
    assert_feasible(am, result.optimized, goal)


def test_every_start_of_the_portfolio_runs_and_the_best_is_kept(am):
    goal = taa_to_se3([0.3, 0.0, 0.8, 0.0, 0.6, 0.0])
    result = solve(am, goal, starts="all")
    assert result.success and set(STARTS) <= set(result.runs) and result.start in STARTS
    best = min(r.optimized.max_abs_force for r in result.runs.values() if r.optimized.feasible)
    assert result.optimized.max_abs_force == pytest.approx(best, abs=0.5)
    doc = result.to_dict()
    assert doc["start"] == result.start and set(doc["starts"]) == set(result.runs)


@pytest.mark.xfail(reason=OWN_PLATE_RULE, strict=False)
@pytest.mark.parametrize("xyz", [(0.0, 0.0, 0.6), (0.1, 0.0, 0.6), (0.3, 0.0, 0.5)])
def test_low_level_goals_the_helper_arm_alone_missed_are_solved(am, xyz):
    goal = pin.SE3(np.eye(3), np.array(xyz))
    result = solve(am, goal)
    assert result.success, result.message
    assert_feasible(am, result.optimized, goal)


@pytest.fixture(scope="module")
def one_platform():
    return AssemblerModel.from_config({"platforms": 1})


@pytest.mark.parametrize("method", ["slsqp", "paper"])
def test_one_platform_the_start_is_the_optimum(one_platform, method):
    goal = taa_to_se3([0.01, 0.0, 0.25, 0.0, 0.05, 0.0])
    result = solve(one_platform, goal, options=OptimizeOptions(method=method))
    assert result.success, result.message
    assert "nothing to optimize" in result.message
    np.testing.assert_allclose(result.optimized.plates.as_matrices(), result.initial.plates.as_matrices())
    assert_feasible(one_platform, result.optimized, goal)


def test_one_platform_from_the_cli(tmp_path, capsys):
    config = tmp_path / "one.yaml"
    config.write_text("platforms: 1\n")
    for method in ("slsqp", "paper"):
        argv = ["solve", "--config", str(config), "--goal", "0", "0", "0.25", "0", "0", "0", "--method", method]
        assert main([*argv, "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["success"] is True


def _patch_values(monkeypatch, wrap) -> None:
    """Route the optimizer's values (its compiled pass) through ``wrap(real)(*args)``."""
    from assembler_pin.statics.pose_kernel import CompiledPass

    monkeypatch.setattr(CompiledPass, "values", wrap(CompiledPass.values))


def test_a_singular_trial_point_is_an_infeasible_step(am, monkeypatch):
    goal = taa_to_se3([0.3, 0.0, 0.8, 0.0, 0.6, 0.0])
    init = solve(am, goal, optimize=False).initial
    calls = {"n": 0}

    def sometimes_singular(real):
        def values_at(*args, **kwargs):
            values = real(*args, **kwargs)
            calls["n"] += 1
            if calls["n"] % 3 == 0:  # the closed form's answer at a singular platform: NaN forces
                values.forces[...] = np.nan
            return values

        return values_at

    _patch_values(monkeypatch, sometimes_singular)
    result = optimize_internal_poses(am, init, goal)  # no exception escapes
    assert calls["n"] >= 3
    assert result.optimized.feasible
    assert_feasible(am, result.optimized, goal)


def test_singular_derivatives_end_the_solve_with_the_reason(am, monkeypatch):
    goal = taa_to_se3([0.3, 0.0, 0.8, 0.0, 0.6, 0.0])
    init = solve(am, goal, optimize=False).initial

    def singular(*args, **kwargs):
        raise np.linalg.LinAlgError("Singular matrix")

    from assembler_pin.statics.pose_kernel import CompiledPass

    monkeypatch.setattr(CompiledPass, "derivatives", singular)
    result = optimize_internal_poses(am, init, goal)
    # the valid start is kept: a valid answer, not proven optimal, and why
    assert result.success and not result.optimal and "singular" in result.message
    assert result.optimized.feasible


def test_exactly_singular_plates_are_flagged_not_raised(am):
    plates = [pin.SE3.Identity()] * (am.n + 1)  # every plate coplanar with its neighbour
    statics = solve_statics(am, plates)
    assert statics.singular


@pytest.mark.parametrize("goal", [[5e3, 0, 0.9, 0, 0, 0], [3.0, 0, 0.5, 0, 0, 0]])
def test_goals_out_of_reach_are_answers(goal, capsys):
    assert main(["solve", "--goal", *map(str, goal), "--json"]) == 1  # answered: not possible
    doc = json.loads(capsys.readouterr().out, parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))
    assert doc["success"] is False and "out of reach" in doc["message"]


def test_goals_beyond_the_translation_limit_are_refused(capsys):
    assert main(["solve", "--goal", "1e200", "0", "0.9", "0", "0", "0", "--json"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pose.translation" in err[0]
