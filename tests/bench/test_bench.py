"""bench: the figures are measured on real calls (their results checked), in a quick run."""

from __future__ import annotations

import json

import numpy as np
import pytest
from checks import sp_legs

from assembler_pin.bench.scaling import benchmark_platform_count, format_sweep
from assembler_pin.bench.timing import random_reachable_plates


def test_random_reachable_plates_are_the_fk_of_their_lengths(am):
    lengths, plates = random_reachable_plates(am, np.random.default_rng(0))
    for j in range(am.n):  # leg lengths from the design anchors
        legs = sp_legs(am.config, j, plates.R[j], plates.p[j], plates.R[j + 1], plates.p[j + 1])[0]
        np.testing.assert_allclose(legs, lengths[j], atol=1e-9)


def test_one_stack_size_row():
    row = benchmark_platform_count(2, repeat=3)
    assert row["platforms"] == 2 and row["initial_success"] and row["optimize_success"]
    assert all(row[k] > 0 for k in ("build_s", "resident_mb", "statics_us", "stack_fk_us", "initial_s"))
    table = format_sweep([row, {**row, "platforms": 3, "optimize_note": "skipped: test"}])
    assert "n = 3: skipped: test" in table and len(table.splitlines()) == 5


def test_startup_row_runs_each_command_and_names_its_target(monkeypatch):
    """The start-up row times real processes of each command (each one exits 0: a failing
    command raises) interleaved round by round, and reports the medians beside the targets."""
    import subprocess
    from pathlib import Path

    from assembler_pin.bench import speed as bench_speed

    calls: list[tuple[str, ...]] = []
    real = subprocess.run

    def recording(argv, **kwargs):
        calls.append(tuple(argv[1:]))
        assert kwargs["cwd"] == Path(bench_speed.__file__).resolve().parent.parent  # this package, not the cwd's
        return real(argv, **kwargs)

    monkeypatch.setattr(subprocess, "run", recording)
    row = bench_speed.benchmark_startup(repeat=2)
    per_round = [("-m", "assembler_pin.cli", *args) for args in bench_speed.STARTUP_COMMANDS.values()]
    assert calls == [*per_round, ("-c", "pass")] * 2
    assert row["cli_help_target_s"] == 0.2 and row["cli_statics_home_json_target_s"] == 0.25
    for key in ("cli_help", "cli_statics_home_json", "bare_python"):
        assert 0 < row[f"{key}_s"] < 60 and 0 < row[f"{key}_cpu_s"] < 60, key


def test_single_statics_row_times_both_paths():
    """The row times Pinocchio's statics and the kernel's at each size asked (a figure per
    path and input kind, all positive)."""
    import importlib.util

    from assembler_pin.bench.speed import benchmark_single_statics

    row = benchmark_single_statics(platforms=(2,), repeat=3, rounds=1)
    paths = ("pinocchio", "kernel") if importlib.util.find_spec("numba") else ("pinocchio",)
    for path in paths:
        assert row[f"n2_{path}_us"] > 0 and row[f"n2_{path}_4x4_us"] > 0


def test_target_rows_say_met_only_when_the_measured_value_meets_its_target():
    """Each row is read from its group and key and held to its target in its sense; a
    figure not measured (NaN, or absent) is never met, a group not run is left out."""
    from assembler_pin.bench.targets import format_targets, target_rows

    doc = {
        "threads": {"threads_identical": True},
        "random_solves": {"first_p50_s": 0.039, "first_p95_s": 0.101, "first_goals_worse": 0},
        "default_starts": {
            "solve_p95_over_p50": 3.2,
            "solve_time_over_all": 0.7,
            "solve_slowest_goal_over_all": 1.4,
            "solve_goals_worse_than_all": 1,
        },
        "grid_solves": {"first_p95_s": 0.2, "first_solved": 110, "all_solved": 111},
        "grid_search": {"solved_by_search": 2},
        "statics_kernel": {"numba_100000_stacks_per_s": 260_000.0, "numba_100000_peak_kb_per_stack": float("nan")},
    }
    rows = {r.what: r for r in target_rows(doc)}
    met = {what: r.met for what, r in rows.items()}
    assert met["answers identical under 1 and 2 BLAS threads (1 = yes)"]
    assert met["solve, random goals, p50 [ms]"] and rows["solve, random goals, p50 [ms]"].value == 39.0
    assert not met["solve, random goals, p95 [ms]"]  # 101 ms > 100 ms
    assert met["random goals with an optimum 0.1 % worse than every start's"]
    assert not met["solve, goals over the stroke, p95 ÷ p50"]  # 3.2 > 3
    assert met["solve, goals over the stroke, time ÷ every start's"]
    assert met["solve, slowest goal's time ÷ every start's"]
    assert not met["goals over the stroke with an optimum 0.1 % worse than every start's"]  # 1 goal
    assert met["solve, 120-goal grid, p95 [s]"]
    assert not met["grid goals solved (target: as many as every start)"]  # 110 < 111
    assert not met["grid goals unsolved that a 300-start search solves"]  # 2 > 0
    assert met["batched statics, 100,000 stacks [stacks/s]"]
    assert not met["batched statics, peak memory per stack [KB]"]  # not measured
    assert rows["batched statics, peak memory per stack [KB]"].text == "not measured"
    assert not any(w.startswith(("map", "one optimization", "one stack")) for w in rows)  # groups not run
    table = format_targets(list(rows.values()))
    assert table.splitlines()[-1] == f"{sum(met.values())} of {len(rows)} targets met"
    assert max(len(line) for line in table.splitlines()) <= 100


def test_default_starts_row_reads_its_ratios_from_the_solves(am, monkeypatch):
    """The default-against-every-start row: its goals are reachable (the stack FK of legs within
    the stroke), and its ratios are those of the interleaved solves' own figures."""
    from assembler_pin.bench import starts as bench_starts
    from assembler_pin.bench.speed import benchmark_solve_starts

    goals = bench_starts.stroke_goals(am, 2, seed=3)
    assert len(goals) == 2 and all(np.linalg.norm(g.translation) > 0 for g in goals)
    figures = {
        "first_p50_s": 0.05,
        "first_p95_s": 0.09,
        "all_p50_s": 0.1,
        "all_p95_s": 0.2,
        "first_time_over_all": 0.6,
        "first_slowest_goal_over_all": 1.1,
        "first_goals_worse": 0,
    }
    seen = []

    def fake(model, goal_set):
        seen.append(goal_set)
        return figures

    monkeypatch.setattr(bench_starts, "benchmark_solve_starts", fake)
    row = bench_starts.benchmark_default_starts(am, count=2, seed=3)
    monkeypatch.undo()
    assert len(seen[0]) == 2 and all(a == b for a, b in zip(seen[0], goals, strict=True))
    assert row["solve_p95_over_p50"] == pytest.approx(1.8) and row["solve_p50_ms"] == pytest.approx(50.0)
    assert row["solve_time_over_all"] == 0.6 and row["solve_goals_worse_than_all"] == 0
    out = benchmark_solve_starts(am, goals[:1])
    assert out["first_time_over_all"] == pytest.approx(out["first_total_s"] / out["all_total_s"])
    assert out["first_slowest_goal_over_all"] == pytest.approx(out["first_time_over_all"])  # one goal


def test_random_goals_are_reachable_poses_the_solver_finds(am):
    """The random solve row's goals: the solver finds a pose for each that meets every
    constraint and the goal, checked independently of the package."""
    from checks import design_problems

    from assembler_pin.bench.targets import random_goals
    from assembler_pin.solver import solve

    for goal in random_goals(am, 3, seed=1):
        result = solve(am, goal, optimize=False)
        assert result.success, result.message
        assert not design_problems(am.config, result.best.plates, goal, tol=1e-6)


def test_map_memory_row_samples_each_worker_of_a_real_map():
    """The map memory row runs a real map on two local workers and finds both worker
    processes (not their nannies or the resource tracker), each with a plausible resident
    size: more than an interpreter with numpy and Pinocchio loaded, less than the target's
    tenfold."""
    from assembler_pin.bench.targets import benchmark_map_memory

    row = benchmark_map_memory(8, workers=2)
    assert row["cells"] == 8 and row["workers_seen"] == 2
    assert 60 < row["worker_peak_mb"] < 3000
    assert row["worker_growth_mb"] < row["worker_peak_mb"]
    assert row["cells_per_s"] > 0 and row["one_worker_cells_per_s"] > 0 and row["speedup"] > 0


def test_wide_search_answers_with_a_state_that_meets_every_constraint_or_none(am):
    """The grid's search row: on a reachable goal its first repaired start optimizes to a
    state that meets every constraint by the design's own geometry and free-body forces; a
    goal past the stack's reach gives None; the row counts what it found."""
    import pinocchio as pin
    from checks import design_forces, design_problems

    from assembler_pin.bench.targets import benchmark_wide_search, wide_search

    goal = pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.8]))
    found = wide_search(am, goal, starts=5)
    assert found is not None and found.optimized.feasible
    assert design_problems(am.config, found.optimized.plates, goal, tol=1e-6) == []
    forces = design_forces(am.config, found.optimized.plates)
    assert np.abs(forces).max() == pytest.approx(found.optimized.max_abs_force, rel=1e-9)
    assert wide_search(am, pin.SE3(np.eye(3), np.array([0.0, 0.0, 2.0])), starts=3) is None
    row = benchmark_wide_search(am, [tuple(np.array([0.1, 0.0, 0.8])), (0.0, 0.0, 2.0)], starts=3)
    assert row["searched"] == 2 and row["solved_by_search"] == 1 and row["found"][0][0] == [0.1, 0.0, 0.8]
    json.dumps(row)  # numpy scalars of the grid's goals come back as floats (bench --targets --json)


def test_the_bench_truss_bay_is_the_example_and_the_solve_scene_has_ten_obstacles():
    from assembler_pin.bench.collision import SOLVE_SCENE, TRUSS_BAY
    from assembler_pin.collision import read_scene, scene_from_dict

    example, bench = read_scene("examples/truss_bay.yaml"), scene_from_dict(TRUSS_BAY)
    assert example is not None and bench.floor_z == example.floor_z
    assert [(o.name, o.kind, o.size) for o in bench.obstacles] == [(o.name, o.kind, o.size) for o in example.obstacles]
    for a, b in zip(bench.obstacles, example.obstacles, strict=True):
        assert np.array_equal(a.pose.homogeneous, b.pose.homogeneous), a.name
    assert len(scene_from_dict(SOLVE_SCENE).obstacles) == 10


def test_collision_rows_time_real_calls_and_are_held_to_their_targets(am):
    """The clearance row times the stack alone and the truss bay; the solve row finds the same
    optimum with and without its scene (the obstacles are near, not in the way); the targets
    read the group."""
    from assembler_pin.bench.collision import benchmark_clearance, benchmark_solve_scene
    from assembler_pin.bench.targets import target_rows

    poses = [random_reachable_plates(am, np.random.default_rng(k))[1] for k in range(2)]
    row = benchmark_clearance(am, poses, repeat=3)
    assert set(row) == {"clearance_us", "clearance_scene_us"}
    assert all(0 < row[k] < 1e6 for k in row), row
    solved = benchmark_solve_scene(am, rounds=1)
    assert solved["solve_scene_same_optimum"] and solved["solve_scene_ratio"] > 0
    rows = {r.what: r for r in target_rows({"collision": {"clearance_us": 45.0, "solve_scene_ratio": 2.5}})}
    assert rows["self-collision clearance, one stack, compiled kernel [µs]"].met
    assert not rows["solve with ten obstacles against without [×]"].met


def test_ratios_are_the_times_divided_and_the_table_says_which_targets_are_met(am):
    """``bench --ratios``: each ratio is its time over bare Pinocchio's; the table holds each
    measured figure beside its target and leaves out what was not measured (no goals)."""
    from assembler_pin.bench.ratios import benchmark_ratios, format_ratios

    doc = benchmark_ratios(am, repeat=3, goals=0)
    for key in ("evaluate_state", "solve_statics"):
        assert doc[f"{key}_ratio"] == pytest.approx(doc[f"{key}_us"] / doc["bare_pinocchio_us"], rel=1e-12)
    table = format_ratios({**doc, "evaluate_state_ratio": 11.0, "solve_statics_ratio": 1.5})
    assert "| `evaluate_state` (self clearance included) ÷ bare Pinocchio | 11 × | <= 10 × | no |" in table
    assert "| `solve_statics` ÷ bare Pinocchio | 1.5 × | <= 2 × | yes |" in table
    assert "solve`, random" not in table
