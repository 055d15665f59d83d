"""What a person reads when an answer is "not possible": one line of at most 200 characters
naming the binding cause in the package's vocabulary (:mod:`assembler_pin.common.messages`), with its
numbers and units and never NaN; and text answers no wider than 100 characters."""

from __future__ import annotations

import json
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest

from assembler_pin import AssemblerModel, load_config, solve, stack_forward_kinematics
from assembler_pin.cli import main
from assembler_pin.common.messages import CAUSES, MAX_LENGTH, binding, describe, one_line
from assembler_pin.helper_arm import HelperArmOptions, initial_condition
from assembler_pin.motion import EEPath, plan_path
from assembler_pin.optimize import optimize_internal_poses
from assembler_pin.reproduce import ScenarioOutcome, summary_table
from assembler_pin.scenarios import SCENARIOS
from assembler_pin.state import evaluate_state

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
FAR = np.array([0.3, 0.0, 10.0])  # beyond any span of the stack: answered before the scan
HIGH = np.array([0.3, 0.0, 2.5])  # within the span, beyond the helper arm: the scan fails
QUICK = HelperArmOptions(max_attempts=2, repair_starts=0)  # the scan alone, no repair
NON_FINITE = re.compile(r"\b(nan|inf|infinity)\b", re.IGNORECASE)


def assert_readable(message: str, cause: str | None = None) -> None:
    """One line, at most 200 characters, no NaN/inf, a cause of the vocabulary (``cause``
    when given) followed by a number."""
    assert isinstance(message, str) and message, message
    assert "\n" not in message and len(message) <= MAX_LENGTH, (len(message), message)
    assert not NON_FINITE.search(message), message
    named = [c for c in CAUSES if c in message]
    assert named, f"no cause of {CAUSES} in {message!r}"
    if cause is not None:
        assert cause in message, message
    after = message[message.index(named[0]) :]
    assert re.search(r"\d", after), f"no number after the cause in {message!r}"


@pytest.fixture(scope="module")
def am():
    return AssemblerModel.from_config()


@pytest.fixture(scope="module")
def weak():
    """Legs of 5 N each way: the home pose and every other breaks a force limit."""
    return AssemblerModel.from_config(load_config({"leg": {"max_tension": 5, "max_compression": 5}}))


def test_unreachable_goals_through_the_api(am):
    """solve and the initial condition: the goal beyond the stack's span and beyond the
    helper arm's reach (the long form, every attempt, stays in ``details``)."""
    far = solve(am, pin.SE3(np.eye(3), FAR))
    assert not far.success
    assert_readable(far.message, "unreachable")
    assert "10 m" in far.message and far.to_dict()["details"]
    init = initial_condition(am, pin.SE3(np.eye(3), HIGH), QUICK)
    assert not init.success
    assert_readable(init.message, "unreachable")
    assert "mm" in init.message and len(init.details) > len(init.message)
    high = solve(am, pin.SE3(np.eye(3), HIGH), optimize=False, helper_options=QUICK)
    assert not high.success
    assert_readable(high.message, "unreachable")
    assert high.details.startswith("helper arm: no valid initial condition after 2 attempt(s)")


def test_plans_that_cannot_start_through_the_api(am):
    """A plan whose start is unreachable, and one whose given start is not at the path's start."""
    far = plan_path(am, EEPath.between(pin.SE3(np.eye(3), FAR), am.home[-1]))
    assert not far.success
    assert_readable(far.reason, "unreachable")
    elsewhere = EEPath.between(pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.9])), am.home[-1])
    moved = plan_path(am, elsewhere, am.home)
    assert not moved.success
    assert_readable(moved.reason, "goal missed")
    assert "mm from the goal" in moved.reason


def test_a_force_limited_pose_through_the_api(weak):
    """The optimizer cannot bring any force under 5 N: the message names the binding leg,
    its force, the limit and how far over, the same numbers as the state's violation."""
    result = optimize_internal_poses(weak, weak.home)
    assert not result.success
    assert_readable(result.message, "force limit")
    worst = binding(result.optimized.violations)
    assert f"{worst.value:.4g} N" in result.message and f"limit {worst.limit:.4g} N" in result.message


def test_a_non_converging_fk_through_the_api(am):
    """Lengths no pose has: the residual in mm after the iterations, the tolerance in m."""
    lengths = np.full((am.n, 6), 0.3)
    lengths[0] = [0.1, 0.1, 0.1, 0.9, 0.9, 0.9]
    fk = stack_forward_kinematics(am, lengths)
    assert not fk.success
    assert_readable(fk.message, "did not converge")
    assert "SP0" in fk.message and "mm after 30 iterations" in fk.message


@pytest.mark.parametrize(
    "kind, value, limit, words",
    [
        ("max_length", 0.36, 0.35, ["leg stroke", "SP1 leg 2", "360 mm", "350 mm", "10 mm over"]),
        ("min_length", 0.20, 0.22, ["leg stroke", "200 mm", "220 mm", "20 mm under"]),
        ("deflection_top", 0.6, 0.5, ["joint deflection", "top joint", "34.38°", "28.65°"]),
        ("compression", -250.0, -200.0, ["force limit", "-250 N", "-200 N", "50 N over"]),
        ("non_finite_force", float("inf"), float("inf"), ["force limit", "not finite"]),
    ],
)
def test_each_violation_reads_in_the_vocabulary(kind, value, limit, words):
    """A violation's cause, where, value, limit and how far past, in mm, ° or N."""
    from assembler_pin.constraints import Violation

    text = describe(Violation(kind, 1, 2, value, limit))
    assert all(w in text for w in words), text
    assert not NON_FINITE.search(text)


def test_one_line_folds_cuts_and_hides_nan():
    text = one_line("a\nb  nan; " + "word " * 80)
    assert "\n" not in text and len(text) <= MAX_LENGTH and text.endswith("…") and "not finite" in text


def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    status = main(["-q", *argv])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def test_failures_through_the_cli(capsys, tmp_path):
    """The same failures at the command line: exit 1, nothing on stderr, the message of the
    JSON answer readable, and the text answer carrying it."""
    far = [str(x) for x in (*FAR, 0, 0, 0)]
    status, out, err = run_cli(capsys, "solve", "--goal", *far, "--json")
    assert status == 1 and err == ""
    doc = json.loads(out)
    assert_readable(doc["message"], "unreachable")
    status, out, err = run_cli(capsys, "solve", "--goal", *far)
    assert status == 1 and err == "" and "unreachable" in out
    status, out, err = run_cli(capsys, "plan", "--from", *far, "--to", "0", "0", "0.9", "0", "0", "0", "--json")
    assert status == 1 and err == ""
    assert_readable(json.loads(out)["reason"], "unreachable")
    weak = tmp_path / "weak.yaml"
    weak.write_text("leg:\n  max_tension: 5\n  max_compression: 5\n")
    goal = ["0.3", "0", "0.75", "0", "1.5708", "0"]
    status, out, err = run_cli(capsys, "solve", "--config", str(weak), "--goal", *goal, "--json")
    assert status == 1 and err == ""
    doc = json.loads(out)
    assert_readable(doc["message"], "force limit")


#: Text answers checked for width: cheap commands covering every text table.
TEXT_COMMANDS = [
    ["statics", "--home"],
    ["statics", "--plates", str(EXAMPLES / "poses.json")],
    ["solve", "--goal", "0.3", "0", "10", "0", "0", "0"],
    ["solve", "--goal", "0.3", "0", "0.75", "0", "1.5708", "0"],
    ["plan", "--from", "0.3", "0", "10", "0", "0", "0", "--to", "0", "0", "0.9", "0", "0", "0"],
    ["stiffness", "--home"],
    ["support", "--home"],
]


@pytest.mark.parametrize("argv", TEXT_COMMANDS, ids=lambda a: " ".join(a[:2]))
def test_text_answers_are_at_most_100_wide(capsys, argv):
    _, out, _ = run_cli(capsys, *argv)
    wide = [line for line in out.splitlines() if len(line) > 100]
    assert out and not wide, wide


def test_map_text_is_at_most_100_wide(capsys, tmp_path):
    """A map of two cells out of reach (answered at once)."""
    argv = ["map", "--grid", "x=3:3.2:2,y=0,z=0.8", "--workers", "0", "--out", str(tmp_path / "m")]
    status, out, _ = run_cli(capsys, *argv)
    assert status == 0 and out
    assert all(len(line) <= 100 for line in out.splitlines()), out


def test_state_tables_of_many_platforms_fold_into_blocks():
    """Six platforms: two blocks of legs, every line within 100 characters."""
    from assembler_pin.cli.common import format_state_table

    am6 = AssemblerModel.from_config(load_config({"platforms": 6}))
    text = format_state_table(evaluate_state(am6, am6.home), "six")
    assert max(map(len, text.splitlines())) <= 100
    assert "SP5 F [N]" in text and text.count("leg | SP") == 2


def test_reproduce_summary_is_at_most_100_wide(am):
    """The terminal summary of the five scenarios (failed and solved rows alike)."""
    state = evaluate_state(am, am.home)
    solved = SimpleNamespace(initial=state, optimized=state, message="converged", timing_s={"initial": 1.0})
    failed = SimpleNamespace(initial=None, optimized=None, message="no valid initial condition", timing_s={})
    stroke = (am.config.leg.min_length, am.config.leg.max_length)
    outcomes = [ScenarioOutcome(s, solved if k % 2 else failed, stroke) for k, s in enumerate(SCENARIOS.values())]
    text = summary_table(outcomes)
    assert max(map(len, text.splitlines())) <= 100, text
    assert all(name in text for name in SCENARIOS)
    markdown = summary_table(outcomes, markdown=True)
    assert len(markdown.splitlines()) == 2 + len(outcomes)  # the report keeps one table


def test_state_tables_write_no_nan(am):
    """A force that overflowed reads "not finite" in the table, never "inf" or "nan"."""
    from assembler_pin.cli.common import format_state_table
    from assembler_pin.constraints import Violation

    home = evaluate_state(am, am.home)
    forces = home.forces.copy()
    forces[1, 2] = np.inf
    state = SimpleNamespace(
        forces=forces,
        leg_lengths=home.leg_lengths,
        max_abs_force=np.inf,
        mean_abs_force=np.nan,
        statics=home.statics,
        feasible=False,
        violations=[Violation("non_finite_force", 1, 2, np.inf, np.inf)],
    )
    text = format_state_table(state, "overflow")
    assert "not finite" in text and not NON_FINITE.search(text)
