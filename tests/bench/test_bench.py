"""bench: the figures are measured on real calls (their results checked), in a quick run."""

from __future__ import annotations

import json
import os

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
        "random_solves_numba": {"first_p50_s": 0.041, "first_p95_s": 0.099},
        "grid_solves": {"first_p95_s": 0.2, "first_solved": 110, "all_solved": 111},
        "grid_search": {"solved_by_search": 2},
        "statics_kernel": {"numba_100000_stacks_per_s": 260_000.0, "numba_100000_peak_kb_per_stack": float("nan")},
    }
    rows = {r.what: r for r in target_rows(doc)}
    met = {what: r.met for what, r in rows.items()}
    assert met["answers identical under 1 and 2 BLAS threads (1 = yes)"]
    assert met["solve, random goals, p50 [ms]"] and rows["solve, random goals, p50 [ms]"].value == 39.0
    assert not met["solve, random goals, p95 [ms]"]  # 101 ms > 100 ms
    assert met["random goals with a worse optimum than every start"]
    assert not met["solve, random goals, compiled pass (opt-in), p50 [ms]"]  # 41 ms > 40 ms
    assert met["solve, random goals, compiled pass (opt-in), p95 [ms]"]
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


def test_the_compiled_optimizer_is_asked_for_only_inside_its_bench_row(monkeypatch):
    """The opt-in row sets ASSEMBLER_PIN_STATICS=numba for its solves only, and gives the
    variable back as it was (unset, or the user's value)."""
    from assembler_pin.bench import targets as bench_targets
    from assembler_pin.statics import pose_kernel

    for before in (None, "numpy"):
        if before is None:
            monkeypatch.delenv("ASSEMBLER_PIN_STATICS", raising=False)
        else:
            monkeypatch.setenv("ASSEMBLER_PIN_STATICS", before)
        with bench_targets._compiled_optimizer():
            assert os.environ["ASSEMBLER_PIN_STATICS"] == "numba"
        assert os.environ.get("ASSEMBLER_PIN_STATICS") == before
        assert not pose_kernel.use_pose_kernel()


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
