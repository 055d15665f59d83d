"""What the command says in the terminal: its subcommands when given none, a quiet end when
the reader of its output goes away, a header above the bench figures, a plan's re-plans
and its whole time, and paths as the user typed them."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from assembler_pin.cli.app import EXIT_PIPE, SUBCOMMANDS, main

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": str(ROOT)}


@pytest.mark.parametrize("argv", [[], ["-q"], ["-v", "-q"]], ids=["bare", "quiet", "verbose-quiet"])
def test_no_subcommand_lists_the_subcommands(argv, capsys):
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert err == ""
    for module in SUBCOMMANDS:
        assert module.__name__.rsplit(".", 1)[-1] in out


def test_a_closed_pipe_ends_quietly_with_141():
    """``assembler-pin statics --home | head -0``: the reader is gone before the answer."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "assembler_pin.cli", "statics", "--home"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=ENV,
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()
    err = proc.stderr.read()
    assert proc.wait(timeout=120) == EXIT_PIPE == 141
    assert err == b""


def test_bench_prints_a_header_above_its_figures(capsys):
    assert main(["bench", "--quick", "--no-optimize", "--repeat", "2"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("assembler-pin bench: median of 2 calls per figure, 4 platforms")
    assert lines[1].startswith("on Python ") and "pin " in lines[1] and "CPUs" in lines[1]
    assert lines[2].startswith("units by suffix: _us µs")
    assert lines[3].split() == ["figure", "median"]
    assert all(len(line) <= 100 for line in lines)


def test_plan_progress_says_when_it_replans():
    from assembler_pin.motion.timing import _replan_progress

    seen: list[tuple[int, int, str]] = []
    noted = _replan_progress(lambda *c: seen.append(c), 1, 2)
    assert noted is not None
    noted(5, 10, "planning: 3 samples")
    assert "re-plan 1/2" in seen[0][2] and "half steps" in seen[0][2]
    assert seen[1] == (5, 10, "re-plan 1/2 with half steps: planning: 3 samples")
    assert _replan_progress(None, 1, 2) is None


def test_plan_summary_gives_the_whole_commands_time_and_paths_as_typed(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    argv = ["plan", "--from", "0", "0", "0.95", "0", "0", "0", "--to", "0.01", "0", "0.95", "0", "0", "0"]
    assert main([*argv, "--out", "t.csv"]) == 0
    out = capsys.readouterr().out
    assert "wrote t.csv" in out.splitlines()
    assert out.splitlines()[-1].startswith("done in ") and "planned in" not in out


def test_view_prints_the_page_path_as_typed(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["view", "--home", "--html", "page.html"]) == 0
    assert "wrote page.html" in capsys.readouterr().out.splitlines()


@pytest.mark.parametrize("columns", [80, 102])
def test_every_usage_fits_the_terminal_and_names_every_option(columns, monkeypatch):
    """argparse leaves a group of alternatives on one line however long; the usage of every
    subcommand is broken at its ``|`` to fit the terminal, and still names every option once."""
    import argparse

    from assembler_pin.cli import build_parser

    monkeypatch.setenv("COLUMNS", str(columns))
    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    for name, p in sub.choices.items():
        usage = p.format_help().split("\n\n")[0]
        assert usage == p.format_usage().rstrip("\n")
        assert max(len(line) for line in usage.splitlines()) <= columns - 2, (name, usage)
        words = usage.replace("(", " ").replace(")", " ").replace("[", " ").replace("]", " ").split()
        for action in p._actions:
            if action.option_strings:
                assert words.count(action.option_strings[0]) == 1, (name, action.option_strings[0])


def test_bench_truss_names_its_figures_with_their_unit(monkeypatch, capsys):
    """``bench --truss``' figures are times per call: each key carries the header's ``_s``
    suffix, so that ``stiffness`` does not read as a stiffness."""
    import assembler_pin.bench.supports as supports
    import assembler_pin.bench.truss as truss

    monkeypatch.setattr(truss, "benchmark_stiffness", lambda am: {"stiffness": 1.5e-4, "loaded_pose": 2e-3})
    monkeypatch.setattr(supports, "benchmark_supports", lambda am: {"two_point_statics": 3e-4})
    assert main(["bench", "--truss"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[2].startswith("units by suffix:") and "_s s" in lines[2]
    figures = [line.split() for line in lines[3:]]
    assert figures == [
        ["stiffness", "(median", "time", "per", "call):"],
        ["stiffness_s:", "0.00015"],
        ["loaded_pose_s:", "0.002"],
        ["supports", "(median", "time", "per", "call):"],
        ["two_point_statics_s:", "0.0003"],
    ]
