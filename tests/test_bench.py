"""bench: the figures are measured on real calls (their results checked), in a quick run."""

from __future__ import annotations

import numpy as np
from checks import sp_legs

from assembler_pin.bench import random_reachable_plates
from assembler_pin.bench_scaling import benchmark_platform_count, format_sweep


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

    from assembler_pin import bench_speed

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

    from assembler_pin.bench_speed import benchmark_single_statics

    row = benchmark_single_statics(platforms=(2,), repeat=3, rounds=1)
    paths = ("pinocchio", "kernel") if importlib.util.find_spec("numba") else ("pinocchio",)
    for path in paths:
        assert row[f"n2_{path}_us"] > 0 and row[f"n2_{path}_4x4_us"] > 0
