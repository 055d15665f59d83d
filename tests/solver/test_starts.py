"""The start portfolio: its poses, when the default stops, which run answers, what it reports."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest
from checks import design_forces, design_problems

from assembler_pin import AssemblerModel
from assembler_pin.cli import main
from assembler_pin.compliance.loaded import loaded_pose
from assembler_pin.kinematics import stack_forward_kinematics
from assembler_pin.solver import solve
from assembler_pin.solver.starts import (
    SAME_OPTIMUM,
    STARTS,
    agreeing,
    best_run,
    lean_poses,
    same_optimum,
    settled,
)

#: A goal whose helper-arm optimum (56.90 N) is a local optimum only: the screw start reaches
#: 56.37 N.
NAMED_GOAL = pin.SE3(pin.exp3(np.array([-0.337649, -0.031864, 0.341136])), np.array([-0.026004, 0.269468, 0.910221]))


def _run(objective: float, optimal: bool = True, success: bool = True) -> SimpleNamespace:
    """What the portfolio reads of an optimizer run."""
    return SimpleNamespace(objective_optimized=objective, optimal=optimal, success=success)


# ------------------------------------------------------------------ poses
def test_lean_poses_start_at_the_base_end_at_the_goal_and_need_four_platforms(am):
    """The lean starts: plate 0 at the base, plate n at the goal, 12 per goal, the first
    leaning toward the goal's horizontal offset; none for a stack of fewer than 4 platforms."""
    goal = pin.SE3(np.eye(3), np.array([0.2, 0.2, 0.5]))
    poses = list(lean_poses(am, goal))
    assert len(poses) == 12
    for plates in poses:
        assert len(plates) == am.n + 1
        assert np.allclose(plates[0].homogeneous, am.home[0].homogeneous)
        assert np.allclose(plates[-1].homogeneous, goal.homogeneous)
    tilted_normal = poses[0][1].rotation[:, 2]  # plate 1 leans toward +x +y
    assert tilted_normal[0] > 0.3 and tilted_normal[1] > 0.3
    assert list(lean_poses(AssemblerModel.from_config({"platforms": 3}), goal)) == []


# ------------------------------------------------------------------ the rule
def test_the_answer_is_the_first_start_at_the_lowest_optimum_whatever_the_last_digits():
    """Optima within SAME_OPTIMUM of the lowest are one optimum: the first in the order tried
    answers, whichever of them the rounding made lowest; a lower optimum beyond it wins."""
    for wobble in (-0.4, 0.0, 0.4):
        runs = {"helper_arm": _run(50.0), "screw": _run(50.0 * (1 + wobble * SAME_OPTIMUM)), "home": _run(60.0)}
        assert best_run(runs)[0] == "helper_arm"
        assert agreeing(runs, runs["helper_arm"]) == 2
    runs = {"helper_arm": _run(50.0), "screw": _run(50.0 * (1 - 3 * SAME_OPTIMUM))}
    assert best_run(runs)[0] == "screw" and agreeing(runs, runs["screw"]) == 1
    # a proven optimum wins over a lower pose where a run stalled; nothing valid: no answer
    assert best_run({"helper_arm": _run(40.0, optimal=False), "screw": _run(45.0)})[0] == "screw"
    assert best_run({"home": _run(40.0, optimal=False, success=False)}) == (None, None)
    assert same_optimum(1.0, 1.0 + 0.5 * SAME_OPTIMUM) and not same_optimum(1.0, 1.0 + 2 * SAME_OPTIMUM)


def test_the_default_stops_at_two_agreeing_optima_only():
    """``settled``: two proven optima at one value; not one run, not two disagreeing optima,
    not an optimum beside a stalled run at the same value."""
    assert not settled({"helper_arm": _run(50.0)})
    assert settled({"helper_arm": _run(50.0), "screw": _run(50.0 * (1 + 0.5 * SAME_OPTIMUM))})
    assert not settled({"helper_arm": _run(50.0), "screw": _run(49.0)})
    assert not settled({"helper_arm": _run(50.0, optimal=False), "screw": _run(50.0)})
    assert settled({"helper_arm": _run(50.0, optimal=False), "screw": _run(49.0), "home": _run(49.0)})


def _lean_stage(monkeypatch, runs, lean_objectives, is_compressed):
    """``lean_runs`` on ``runs`` with lean starts whose runs end at ``lean_objectives`` (None:
    a run that meets no constraint); the names of the lean runs made."""
    from assembler_pin.solver import starts

    results = iter(lean_objectives)

    def fake_run(am, start, goal, opts, scene=None):
        value = next(results)
        run = _run(value if value is not None else 1e3, optimal=value is not None, success=value is not None)
        run.optimized = SimpleNamespace(feasible=value is not None)
        return run

    monkeypatch.setattr(starts, "lean_starts", lambda am, goal: ((f"lean_{k}", None) for k in range(12)))
    monkeypatch.setattr(starts, "optimize_internal_poses", fake_run)
    monkeypatch.setattr(starts, "compressed", lambda am, run, opts: is_compressed)
    for r in runs.values():
        r.optimized = SimpleNamespace(feasible=r.success)
    starts.lean_runs(None, None, runs, None, None)
    return [name for name in runs if name.startswith("lean_")]


def test_the_lean_starts_run_until_a_valid_pose_or_a_second_run_at_a_compressed_optimum(monkeypatch):
    """No valid run: lean starts until one is valid. A compressed optimum that no second run
    reached: lean starts until one reaches the answer's optimum (a lower one found on the way
    becomes the answer). Otherwise, none."""
    failed = {"helper_arm": _run(90.0, optimal=False, success=False)}
    assert _lean_stage(monkeypatch, failed, [None, None, 80.0, 70.0], True) == ["lean_0", "lean_1", "lean_2"]
    alone = {"helper_arm": _run(80.0), "screw": _run(90.0, optimal=False, success=False)}
    assert _lean_stage(monkeypatch, dict(alone), [85.0, 74.0, 74.0, 60.0], True) == ["lean_0", "lean_1", "lean_2"]
    assert _lean_stage(monkeypatch, dict(alone), [85.0, 80.0], True) == ["lean_0", "lean_1"]
    assert _lean_stage(monkeypatch, dict(alone), [85.0], False) == []
    agreed = {"helper_arm": _run(80.0), "screw": _run(80.0)}
    assert _lean_stage(monkeypatch, agreed, [70.0], True) == []


def test_the_default_runs_the_first_starts_of_every_start(am):
    """The default's starts are the first ones of ``all``'s, in the same order, and it stops
    after two exactly when they agree; the result reports what ran and what agreed, in the
    API and in the JSON alike."""
    goal = pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.8]))
    lazy, every = solve(am, goal), solve(am, goal, starts="all")
    assert every.starts_tried == STARTS
    assert lazy.starts_tried == every.starts_tried[: len(lazy.starts_tried)]
    two = {k: lazy.runs[k] for k in lazy.starts_tried[:2]}
    assert (len(lazy.starts_tried) == 2) == settled(two)
    assert 1 <= lazy.starts_agreeing <= len(lazy.starts_tried)
    doc = lazy.to_dict()
    assert doc["starts_tried"] == list(lazy.starts_tried) and doc["starts_agreeing"] == lazy.starts_agreeing


def test_the_named_goal_reaches_the_lower_optimum_by_default(am):
    """The goal whose helper-arm start ends at a local optimum (56.90 N): the default answers
    the screw start's optimum, at most 56.40 N, held by the design's own geometry and
    free-body forces; it is reported as a local optimum that not every start reached."""
    result = solve(am, NAMED_GOAL)
    assert result.success and result.optimal, result.message
    assert result.optimized.max_abs_force <= 56.40
    plates = result.optimized.plates
    assert design_problems(am.config, plates, NAMED_GOAL, tol=1e-6) == []
    assert np.abs(design_forces(am.config, plates)).max() == pytest.approx(result.optimized.max_abs_force, rel=1e-9)
    assert "screw" in result.starts_tried and result.starts_agreeing < len(result.starts_tried)


def _seeded_goals(am, count: int, seed: int) -> list[pin.SE3]:
    """EE poses of random stacks with legs over the whole stroke (by stack FK): reachable."""
    rng = np.random.default_rng(seed)
    goals = []
    while len(goals) < count:
        lengths = rng.uniform(am.config.leg.min_length + 0.01, am.config.leg.max_length - 0.01, (am.n, 6))
        fk = stack_forward_kinematics(am, lengths)
        if fk.success:
            goals.append(fk.plates.se3(am.n))
    return goals


@pytest.mark.slow
def test_the_default_finds_the_optimum_of_every_start(am):
    """On a seeded goal set (random stacks over the whole stroke, the named goal and grid goals
    where the starts reach different optima), the default's answer is the same or a better
    optimum than running every start (Ω within 0.1 %), from no more runs."""
    goals = [NAMED_GOAL, *_seeded_goals(am, 8, 54)]
    goals += [pin.SE3(np.eye(3), np.array(p)) for p in ((-0.3, 0.0, 0.7), (-0.3, 0.2, 0.6), (-0.1, 0.2, 0.6))]
    for goal in goals:
        lazy, every = solve(am, goal), solve(am, goal, starts="all")
        assert lazy.success == every.success
        if every.success:
            assert lazy.optimization.objective_optimized <= every.optimization.objective_optimized * (1 + 1e-3)
        assert len(lazy.runs) <= len(every.runs)


# ------------------------------------------------------------------ the sag on the result
def test_the_sag_is_on_the_result_and_the_cli_only_prints_it(am, capsys):
    """``SolveResult.sag`` is the EE's displacement under its own load: the elastic
    equilibrium's (Newton on the plates with the legs' stiffness, a separate computation) EE
    translation, to first order (1 %), for the answer and the helper arm's pose; ``solve
    --json`` prints the result's block."""
    goal = pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.8]))
    result = solve(am, goal)
    for state, block in ((result.best, result.sag.answer), (result.initial, result.sag.initial)):
        moved = loaded_pose(am, state.leg_lengths, base=am.home[0])
        assert moved.success and np.allclose(moved.rigid.p, state.plates.p, atol=1e-9)
        shift = moved.translation
        np.testing.assert_allclose(block["translation_m"], shift, atol=1e-2 * np.linalg.norm(shift))
        assert block["sag_m"] == pytest.approx(np.linalg.norm(block["translation_m"]), rel=1e-12)
    assert result.sag.stiffness_n_per_m == float(am.config.leg.stiffness) and result.sag.objective == "force"
    assert main(["solve", "--goal", "0.1", "0", "0.8", "0", "0", "0", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert list(doc["sag"]) == ["objective", "max_sag_m", "stiffness_n_per_m", "initial", "answer"]
    assert doc["sag"]["answer"]["sag_m"] == pytest.approx(result.sag.answer["sag_m"], rel=1e-6)
