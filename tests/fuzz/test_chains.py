"""Chains of commands a user runs one after another: the README's plan → simulate → view,
a map rerun into the same directory with another grid or config, and Ctrl-C in a long
command. Each step is held to the contract and to what the previous step wrote."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from . import answers
from .harness import child_env, fail, judge_cli, run_cli

README_GOAL = "0.2 0.1 0.85 0.5 0.5 0.5"


def _cli(argv: list[str], cwd: Path, expect: str = "answer"):
    outcome = run_cli(argv, cwd=cwd)
    judge_cli(outcome, expect, "assembler-pin " + " ".join(argv))
    return outcome


@pytest.mark.slow
def test_readme_plan_simulate_view(am, tmp_path):
    """``plan --to (README goal) --out traj.csv``, then ``simulate --trajectory`` and
    ``view --trajectory`` on the same file: each answers, and the file holds rows that
    agree with their own lengths."""
    plan = _cli(["plan", "--json", "--to", *README_GOAL.split(), "--out", "traj.csv"], tmp_path)
    doc = answers.strict_json(plan.out, "plan")
    answers.check_plan_doc(am, doc, plan.code, "plan (README goal)", tmp_path / "traj.csv")
    sim = _cli(["simulate", "--json", "--trajectory", "traj.csv"], tmp_path)
    if answers.strict_json(sim.out, "simulate").get("followed") is not True:
        fail("wrong-answer", "simulate --trajectory of the README plan: not followed")
    _cli(["view", "--trajectory", "traj.csv", "--html", "traj.html"], tmp_path)


def _map(grid: str, out: Path, cwd: Path, config: str | None = None):
    argv = ["map", "--json", "--workers", "0", "--no-progress", "--grid", grid, "--out", str(out)]
    outcome = run_cli([*argv, *(["--config", config] if config else [])], cwd=cwd)
    judge_cli(outcome, "any", "assembler-pin " + " ".join(argv))
    return outcome


@pytest.mark.slow
def test_map_rerun_with_another_grid_does_not_reuse_cells(tmp_path):
    """The same --out, cell 0 first a reachable goal, then an unreachable one: the second
    map is refused (the directory holds another map) or computes its own cell."""
    out = tmp_path / "m"
    first = _map("x=0,y=0,z=0.85", out, tmp_path)
    assert first.code == 0, first.err
    second = _map("x=5,y=0,z=0.5", out, tmp_path)
    if second.code == 2:
        return
    doc = answers.strict_json(second.out, "map rerun")
    if doc.get("reachable"):
        fail(
            "wrong-answer",
            f"map rerun with an unreachable grid into the same --out: {doc['reachable']} "
            f"reachable (cells reused: {doc.get('already_done')})",
        )


@pytest.mark.slow
def test_map_rerun_with_an_edited_config_does_not_reuse_cells(tmp_path):
    """The same --out and config name, the payload edited from 5 kg to 40 kg: no cell of
    the 5 kg map is reported for the 40 kg config."""
    out, cfg = tmp_path / "m", tmp_path / "design.yaml"
    cfg.write_text("payload:\n  mass: 5.0\n")
    first = _map("x=0,y=0,z=0.85", out, tmp_path, str(cfg))
    assert first.code == 0, first.err
    cfg.write_text("payload:\n  mass: 40.0\n")
    second = _map("x=0,y=0,z=0.85", out, tmp_path, str(cfg))
    if second.code == 2:
        return
    doc = answers.strict_json(second.out, "map rerun")
    if doc.get("already_done"):
        fail(
            "wrong-answer",
            f"map rerun after the config's payload changed 5 -> 40 kg reused "
            f"{doc['already_done']} cell(s) computed for 5 kg",
        )


def _interrupt(argv: list[str], cwd: Path, after: float) -> tuple[int | None, str]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "assembler_pin.cli", *argv],
        cwd=cwd,
        env=child_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    time.sleep(after)
    if proc.poll() is not None:  # done before Ctrl-C: the case does not test an interruption
        fail("too-short", f"{argv[0]} ended (exit {proc.returncode}) before the signal at {after} s")
    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        return None, ""
    return proc.returncode, err.decode(errors="replace")


@pytest.mark.slow
@pytest.mark.parametrize(
    "argv, output, after",
    [
        # the signal at 2 s: planning (the whole command takes 3.5 s on a quiet machine, more
        # at 200 output samples a second)
        (["plan", "--to", *README_GOAL.split(), "--rate", "200", "--out", "t.csv"], "t.csv", 2.0),
        (["reproduce", "--out", "rep"], "rep/report.md", 8.0),
        # 900 cells: still running when the signal comes (3 cells were done within the 8 s)
        (["map", "--workers", "0", "--grid", "x=-0.1:0.1:30,y=-0.1:0.1:30,z=0.85", "--out", "m"], None, 8.0),
    ],
    ids=["ctrl_c.plan", "ctrl_c.reproduce", "ctrl_c.map"],
)
def test_ctrl_c_ends_with_one_line_and_no_partial_file(tmp_path, argv, output, after):
    code, err = _interrupt(argv, tmp_path, after=after)
    what = f"Ctrl-C in assembler-pin {argv[0]}"
    if code is None:
        fail("hang", f"{what}: still running 30 s after SIGINT")
    lines = err.strip().splitlines()
    if "Traceback" in err:
        fail("traceback", f"{what}: {lines[-1] if lines else ''}")
    if code != 130 or len(lines) != 1:
        fail("exit-status", f"{what}: exit {code}, {len(lines)} stderr line(s): {' | '.join(lines[-2:])[:300]}")
    if output and (tmp_path / output).exists() and (tmp_path / output).stat().st_size == 0:
        fail("wrong-answer", f"{what}: left an empty {output}")
    if argv[0] == "map":
        for part in (tmp_path / "m").glob("*"):
            if not part.name.endswith(".parquet") and part.name != "map.json":  # map.json: the manifest
                fail("wrong-answer", f"{what}: left {part.name} in the map directory")


def test_json_answers_are_strict(ws):
    """``dumps``'s contract seen from outside: the answer of a singular pose has no NaN token."""
    outcome = run_cli(["statics", "--plates", str(ws.root / "plates_far.json"), "--json"], cwd=ws.root)
    judge_cli(outcome, "any", "statics of a far pose")
    if outcome.code in (0, 1):
        json.loads(outcome.out, parse_constant=lambda c: fail("wrong-answer", f"token {c}"))
