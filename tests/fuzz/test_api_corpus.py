"""The public API with the hostile arguments of :data:`corpus.API_CASES`: a refusal is an
``AssemblerError`` subclass with a one-line message; anything else raised is a defect; a
result never claims what its arguments make impossible (a NaN goal reached, a pose
feasible against a NaN tolerance)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

import assembler_pin as ap

from . import answers
from .corpus import API_CASES, ApiCase, ApiContext, Workspace
from .harness import REPO, ContractError, call_api, fail, run_child


def judge_result(case: ApiCase, am, result) -> None:
    """What a returned result may not claim."""
    if case.verdict is not None:
        flag = getattr(result, case.verdict, None)
        if flag is True:
            fail("wrong-answer", f"{case.id}: returned {case.verdict} true: {str(result)[:200]}")
    if isinstance(result, ap.StackState) and result.feasible:
        answers.check_state_doc(am, result.to_dict(), case.id)
    if isinstance(result, ap.kinematics.StackFKResult) and result.success:
        answers.check_fk_result(am, result, case.id, case.fk_lengths)


def run_case(case: ApiCase, context: ApiContext) -> None:
    called = call_api(lambda: case.call(context), case.expect, case.id)
    if called.error is None:
        judge_result(case, context.am, called.result)


def run_isolated(case_id: str, root: str) -> None:
    """Entry point of a child process: run one case, print its verdict on the last line."""
    am = ap.AssemblerModel.from_config()
    ws = Workspace(Path(root), None, "", "", Path(root) / "model")
    case = next(c for c in API_CASES if c.id == case_id)
    try:
        run_case(case, ApiContext(am, ws))
    except ContractError as exc:
        print(f"\nVERDICT {exc}", flush=True)
        return
    print("\nVERDICT ok", flush=True)


@pytest.fixture(scope="module")
def context(am, ws) -> ApiContext:
    return ApiContext(am, ws)


def _params() -> list:
    """The cases as a list (pytest will refuse a generator in ``parametrize``)."""
    return [
        pytest.param(case, id=case.id, marks=[pytest.mark.slow] if case.slow or case.isolate else [])
        for case in API_CASES
    ]


@pytest.mark.parametrize("case", _params())
def test_api(case: ApiCase, context: ApiContext):
    if not case.isolate:
        run_case(case, context)
        return
    code = (
        f"import sys; sys.path.insert(0, {str(REPO / 'tests')!r}); from fuzz.test_api_corpus import "
        f"run_isolated; run_isolated({case.id!r}, {str(context.ws.root)!r})"
    )
    outcome = run_child([sys.executable, "-c", code], cwd=context.ws.root)
    if outcome.hung:
        fail("hang", f"{case.id}: no answer within the time limit")
    verdict = [line for line in outcome.out.splitlines() if line.startswith("VERDICT ")]
    if not verdict:
        last = outcome.err.strip().splitlines()[-1:] or [f"exit {outcome.code}"]
        kind = "traceback" if outcome.code and outcome.code > 0 else "non-assembler-error"
        fail(kind, f"{case.id}: the child process ended without a verdict: {last[0][:300]}")
    text = verdict[-1][len("VERDICT ") :]
    if text != "ok":
        raise ContractError(text)
