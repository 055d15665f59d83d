"""Every subcommand of ``assembler-pin`` with the curated hostile command lines of
:mod:`.corpus`: a refusal is exit status 2 with one short line on stderr; an answer exits 0
or 1 and holds up to an independent re-check of what it claims; nothing hangs."""

from __future__ import annotations

import json
import math
from functools import cache
from pathlib import Path

import pytest

import assembler_pin as ap

from . import answers
from .corpus import CLI_CASES, CliCase
from .harness import TIMEOUT, fail, judge_cli, run_cli, run_cli_child


@cache
def model_for(config: str | None):
    return ap.AssemblerModel.from_config(config)


def _option(argv: list[str], name: str) -> str | None:
    return argv[argv.index(name) + 1] if name in argv and argv.index(name) + 1 < len(argv) else None


def _finite_numbers(doc, what: str) -> None:
    if isinstance(doc, float) and not math.isfinite(doc):
        fail("wrong-answer", f"{what}: a non-finite number in the answer")
    if isinstance(doc, dict):
        for v in doc.values():
            _finite_numbers(v, what)
    if isinstance(doc, list):
        for v in doc:
            _finite_numbers(v, what)


def check_answer(case: CliCase, argv: list[str], code: int, out: str, what: str) -> None:
    """The re-check named by ``case.check`` of an answer (exit 0 or 1)."""
    kind = case.check
    if kind is None:
        return
    am = model_for(_option(argv, "--config"))
    if kind in ("html", "export"):
        target = Path(_option(argv, "--html") or _option(argv, "--out"))
        if code == 0 and not target.exists():
            fail("wrong-answer", f"{what}: exit 0 but {target} was not written")
        if kind == "export" and code == 0:
            ap.AssemblerModel.from_files(target / "assembler.urdf")
        return
    doc = answers.strict_json(out, what)
    if kind == "state":
        answers.check_state_doc(am, doc, what)
    elif kind == "carrier":
        answers.check_state_doc(am, doc, what)
        if doc.get("within_limits") is True and not all(r <= 1 + 1e-9 for r in doc["carrier_torque_ratio"]):
            fail("wrong-answer", f"{what}: carrier within limits with torque ratios {doc['carrier_torque_ratio']}")
    elif kind == "solve":
        tolerance = (
            argv[argv.index("--ee-tolerance") + 1 : argv.index("--ee-tolerance") + 3]
            if ("--ee-tolerance" in argv)
            else None
        )
        ee_tol = max(float(v) for v in tolerance) * (1 + 1e-9) if tolerance else 1e-6
        answers.check_solve_doc(am, doc, code, what, ee_tol)
    elif kind == "carrier_capacity":
        answers.exit_agrees(code, doc.get("success"), what)
        if "capacity" not in doc:
            fail("accepted", f"{what}: --capacity with --carrier answered without a capacity (option dropped)")
    elif kind in ("plan", "plan_times", "plan_success"):
        out_file = _option(argv, "--out")
        answers.check_plan_doc(am, doc, code, what, Path(out_file) if out_file else None)
        if kind == "plan_success" and doc.get("success") is not True:
            fail("valid-input-refused", f"{what}: a short path near home answered not possible: {doc.get('reason')}")
        if kind == "plan_times" and out_file and Path(out_file).exists():
            duration = ap.read_trajectory(out_file).duration
            if duration < 30.0 - 1e-9:
                fail("accepted", f"{what}: waypoint times [0, 30] s given, trajectory lasts {duration:.3g} s")
    elif kind == "map":
        limit = max(am.config.leg.max_tension, am.config.leg.max_compression)
        cells = answers.check_map_dir(Path(_option(argv, "--out")), what, limit)
        if doc.get("reachable") != sum(cells.values()):
            fail("wrong-answer", f"{what}: says {doc.get('reachable')} reachable, its files {sum(cells.values())}")
    elif kind in ("held", "followed"):
        if not isinstance(doc.get(kind), bool):
            fail("wrong-answer", f"{what}: no '{kind}' verdict")
        _finite_numbers({k: v for k, v in doc.items() if not isinstance(v, list)}, what)
        if doc[kind] is not True and case.expect == "answer":
            fail("wrong-answer", f"{what}: a valid input not {kind}: {doc.get('message')}")
    elif kind == "finite":
        _finite_numbers(doc, what)


def _params() -> list:
    """The cases as a list (pytest will refuse a generator in ``parametrize``)."""
    return [
        pytest.param(case, id=case.id, marks=[pytest.mark.slow] if case.slow or case.isolate else [])
        for case in CLI_CASES
    ]


@pytest.mark.parametrize("case", _params())
def test_cli(case: CliCase, ws):
    argv = [a.replace("{d}", str(ws.root)).replace("{case}", case.id) for a in case.argv]
    what = "assembler-pin " + " ".join(a.replace(str(ws.root), "D")[:60] for a in argv)
    # a refusal comes before any real work; a child process (or a scheduler connection) takes longer
    timeout = TIMEOUT / 2 if case.expect == "refuse" and not case.isolate else TIMEOUT
    run = run_cli_child if case.isolate else run_cli
    outcome = run(argv, cwd=ws.root, timeout=timeout)
    judge_cli(outcome, case.expect, what, timeout)
    if outcome.code in (0, 1):
        try:
            check_answer(case, argv, outcome.code, outcome.out, what)
        except ap.AssemblerError as exc:
            fail("valid-input-refused", f"{what}: re-reading its own output: {type(exc).__name__}: {exc}")
        except json.JSONDecodeError as exc:  # pragma: no cover - strict_json reports it
            fail("wrong-answer", f"{what}: {exc}")
