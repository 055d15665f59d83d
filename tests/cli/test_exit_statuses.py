"""The command line keeps the contract on every surface: exit statuses, interrupts, atomic
outputs, bounded counts, the carrier's options and its joint optimization, progress.

Exit statuses: 0 answered and successful, 1 answered "not possible", 2 refused input (one
line), 70 a bug (one line), 130 / 143 interrupted by Ctrl-C / SIGTERM (one line, no partial file).
"""

from __future__ import annotations

import io
import json
import math
import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import assembler_pin as ap
from assembler_pin.cli import main
from assembler_pin.common.progress import TerminalProgress
from assembler_pin.exceptions import OptionsError, SimulationError, SingularConfigurationError

REACHABLE = ["0.2", "0.1", "0.85", "0.5", "0.5", "0.5"]
UNREACHABLE = ["3", "0", "0.8", "0", "0", "0"]


def _run(capsys, argv: list[str]) -> tuple[int, str, list[str]]:
    code = main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err.splitlines()


def _leftovers(directory: Path) -> list[str]:
    """Temporary files of the atomic writers left in ``directory``."""
    return sorted(p.name for p in directory.iterdir() if p.name.endswith(".tmp"))


# --- exit statuses ------------------------------------------------------------------------


def _replace_run(monkeypatch, body) -> None:
    """Make ``assembler-pin statics`` run ``body(args)`` instead (the parser is built per call)."""
    import assembler_pin.cli.statics as statics_cli

    monkeypatch.setattr(statics_cli, "run", body)


@pytest.mark.parametrize("json_out", [False, True])
def test_statics_of_a_pose_that_breaks_a_constraint_is_exit_1(tmp_path, capsys, json_out):
    """``statics`` answers every pose; the status says whether it is valid: 0 when every
    constraint holds, 1 (the answer printed all the same) when one does not; here the clearance
    of ``--scene``, a post through the stack's axis, against the same pose without it."""
    import yaml

    scene = tmp_path / "post.yaml"
    scene.write_text(yaml.safe_dump({"obstacles": [{"sphere": {"radius": 0.05, "center": [0.0, 0.0, 0.5]}}]}))
    flag = ["--json"] if json_out else []
    code, out, err = _run(capsys, ["statics", "--home", *flag])
    assert code == 0 and not err
    code, out, err = _run(capsys, ["statics", "--home", "--scene", str(scene), *flag])
    assert code == 1 and not err
    if json_out:
        doc = json.loads(out)
        assert doc["feasible"] is False and any(v["kind"] == "collision" for v in doc["violations"])
    else:
        assert "feasible: NO" in out


def test_an_unexpected_exception_is_one_line_and_exit_70(monkeypatch, capsys):
    def broken(args):
        raise TypeError("unsupported operand type(s)")

    _replace_run(monkeypatch, broken)
    code, out, err = _run(capsys, ["statics", "--home"])
    assert code == 70 and out == "" and len(err) == 1, err
    assert "TypeError" in err[0] and "bug" in err[0] and "-v" in err[0]
    code, _, err = _run(capsys, ["-v", "statics", "--home"])  # the traceback only with -v
    assert code == 70 and err[0].startswith("Traceback") and "TypeError" in err[-1]


def test_ctrl_c_is_one_line_and_exit_130(monkeypatch, capsys):
    def interrupted(args):
        raise KeyboardInterrupt

    _replace_run(monkeypatch, interrupted)
    assert _run(capsys, ["statics", "--home"]) == (130, "", ["assembler-pin statics: interrupted"])


def test_sigterm_is_one_line_and_exit_143_and_the_handler_is_restored(monkeypatch, capsys):
    def terminated(args):
        os.kill(os.getpid(), signal.SIGTERM)  # the handler raises at the next bytecode
        time.sleep(30)  # not reached
        return 0

    before = signal.getsignal(signal.SIGTERM)
    _replace_run(monkeypatch, terminated)
    code, out, err = _run(capsys, ["statics", "--home"])
    assert code == 128 + signal.SIGTERM and out == ""
    assert err == ["assembler-pin statics: interrupted (stopped by SIGTERM)"]
    assert signal.getsignal(signal.SIGTERM) == before


def test_numpy_warnings_never_reach_stderr():
    """A numpy RuntimeWarning beside a refusal: stderr holds the one line only (run in a fresh
    interpreter: pytest itself records warnings instead of printing them)."""
    script = (
        "import sys, numpy as np\n"
        "import assembler_pin.cli.statics as s\n"
        "from assembler_pin.exceptions import CLIError\n"
        "def run(args):\n"
        "    np.log(np.zeros(3))\n"
        "    np.float64(1.0) / np.float64(0.0)\n"
        "    raise CLIError('the pose is refused')\n"
        "s.run = run\n"
        "from assembler_pin.cli import main\n"
        "sys.exit(main(['statics', '--home']))\n"
    )
    res = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert res.returncode == 2
    assert res.stderr.splitlines() == ["assembler-pin statics: error: the pose is refused"], res.stderr


def test_an_unreachable_goal_is_answered_with_exit_1(capsys):
    code, out, err = _run(capsys, ["solve", "--goal", *UNREACHABLE, "--json"])
    doc = json.loads(out)
    assert code == 1 and err == [] and doc["success"] is False and "out of reach" in doc["message"]
    code, out, _ = _run(capsys, ["solve", "--goal", *UNREACHABLE])  # the text answer as before
    assert code == 1 and "no valid initial condition" in out


def test_no_payload_capacity_is_exit_1(monkeypatch, capsys):
    import assembler_pin.solver.capacity as capacity

    class NoCapacity:
        success, message = False, "no valid internal pose holds any payload here"

        def to_dict(self):
            return {"success": False, "message": self.message}

    monkeypatch.setattr(capacity, "payload_capacity", lambda am, goal, start=None, scene=None: NoCapacity())
    code, out, _ = _run(capsys, ["solve", "--goal", *REACHABLE, "--capacity", "--json"])
    doc = json.loads(out)
    assert code == 1 and doc["success"] is True and doc["capacity"]["success"] is False


def test_reproduce_with_an_unsolved_scenario_is_exit_1(monkeypatch, tmp_path, capsys):
    import assembler_pin.reproduce as reproduce
    from assembler_pin.solver import solve

    def unreachable(am, goal, **kwargs):  # the scenario's goal moved out of reach
        return solve(am, pin.SE3(np.eye(3), np.array([3.0, 0.0, 0.8])), **kwargs)

    monkeypatch.setattr(reproduce, "solve", unreachable)
    code, out, err = _run(capsys, ["reproduce", "--scenario", "translation", "--out", str(tmp_path)])
    assert code == 1 and err == [] and "not solved" in out
    assert "Not solved" in (tmp_path / "report.md").read_text()


# --- atomic outputs -----------------------------------------------------------------------


def _interrupt_fsync(monkeypatch) -> None:
    """Every atomic write is cut short after its data reached the temporary file."""
    import assembler_pin.common.files as files

    def killed(fd):
        raise KeyboardInterrupt

    monkeypatch.setattr(files.os, "fsync", killed)


def test_an_interrupted_export_leaves_the_previous_files(monkeypatch, tmp_path, capsys):
    previous = {"assembler.urdf": "previous urdf", "assembler.yaml": "previous sidecar"}
    for name, text in previous.items():
        (tmp_path / name).write_text(text)
    _interrupt_fsync(monkeypatch)
    code, _, err = _run(capsys, ["export", "--mjcf", "--out", str(tmp_path)])
    assert code == 130 and err == ["assembler-pin export: interrupted"]
    assert {name: (tmp_path / name).read_text() for name in previous} == previous
    assert _leftovers(tmp_path) == [] and not (tmp_path / "helper_arm.urdf").exists()


@pytest.mark.slow
def test_an_interrupted_html_page_leaves_the_previous_page(monkeypatch, tmp_path, capsys):
    page = tmp_path / "page.html"
    page.write_text("<html>previous</html>")
    _interrupt_fsync(monkeypatch)
    code, _, err = _run(capsys, ["view", "--home", "--html", str(page)])
    assert code == 130 and err[-1].startswith("assembler-pin view:"), err
    assert page.read_text() == "<html>previous</html>" and _leftovers(tmp_path) == []


def _half_then_interrupt(monkeypatch, after: int = 0) -> list[str]:
    """``Figure.savefig`` writes half a PNG, then is interrupted (after ``after`` whole figures)."""
    from matplotlib.figure import Figure

    real, written = Figure.savefig, []

    def savefig(self, fname, **kwargs):
        if len(written) < after:
            written.append(str(fname))
            return real(self, fname, **kwargs)
        buf = io.BytesIO()
        real(self, buf, **kwargs)
        Path(fname).write_bytes(buf.getvalue()[: len(buf.getvalue()) // 2])
        raise KeyboardInterrupt

    monkeypatch.setattr(Figure, "savefig", savefig)
    return written


def test_an_interrupted_figure_leaves_the_previous_png(monkeypatch, tmp_path, am):
    from assembler_pin import plots

    target = tmp_path / "views.png"
    target.write_bytes(b"previous png")
    _half_then_interrupt(monkeypatch)
    state = ap.evaluate_state(am, am.home)
    with pytest.raises(KeyboardInterrupt):
        plots.save(plots.pose_views(state), target)
    assert target.read_bytes() == b"previous png" and _leftovers(tmp_path) == []
    monkeypatch.undo()
    plots.save(plots.pose_views(state), tmp_path / "named.anything")  # PNG whatever the name
    assert (tmp_path / "named.anything").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def solved_outcomes(am):
    """One solved scenario, for the report (its reference columns skipped: not the point here)."""
    import assembler_pin.reproduce as reproduce

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(reproduce, "reference", lambda *args, **kwargs: None)
        outcomes = reproduce.run_scenarios(am, ["orientation_transition"])
    assert outcomes[0].optimized is not None
    return outcomes


@pytest.mark.slow
def test_an_interrupted_report_leaves_the_previous_report_and_figures(monkeypatch, tmp_path, am, solved_outcomes):
    from assembler_pin.reproduce import write_report

    name = solved_outcomes[0].scenario.name
    before = {"report.md": b"# previous report"}
    before |= {f"{name}_{kind}.png": b"previous png" for kind in ("views", "forces", "heatmap")}
    for file, data in before.items():
        (tmp_path / file).write_bytes(data)
    written = _half_then_interrupt(monkeypatch, after=2)  # the third figure is cut short
    with pytest.raises(KeyboardInterrupt):
        write_report(am, solved_outcomes, tmp_path)
    assert len(written) == 2  # two whole figures were written, to temporary files...
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before  # ...and none replaced a file


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="watches the child's libraries in /proc")
def test_ctrl_c_in_reproduce_ends_with_one_line_and_no_report(tmp_path):
    out = tmp_path / "report"
    argv = [sys.executable, "-m", "assembler_pin.cli", "reproduce", "--out", str(out)]
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:  # wait until it is solving
            if "pinocchio" in Path(f"/proc/{proc.pid}/maps").read_text():
                break
            time.sleep(0.1)
        time.sleep(1.0)
        assert proc.poll() is None, proc.stderr.read()
        proc.send_signal(signal.SIGINT)
        code = proc.wait(timeout=120)
        err = proc.stderr.read().splitlines()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert code == 130 and err == ["assembler-pin reproduce: interrupted"], err
    assert not (out / "report.md").exists() and (not out.exists() or _leftovers(out) == [])


# --- bounded counts -----------------------------------------------------------------------

HUGE_COUNTS = [
    (["view", "--home", "--animate", "100000000"], "--animate"),
    (["view", "--home", "--frames", "100000000"], "--frames"),
    (["bench", "--repeat", "1000000000", "--quick", "--no-optimize"], "--repeat"),
    (["solve", "--goal", *REACHABLE, "--max-attempts", "1000000000", "--d-step", "1e-12"], "--max-attempts"),
    (["solve", "--goal", *REACHABLE, "--d-step", "1e-12"], "--d-step"),
    (["solve", "--goal", *REACHABLE, "--max-iterations", "1000000000"], "--max-iterations"),
    (["reproduce", "--max-iterations", "1000000000"], "--max-iterations"),
    (["simulate", "--home", "--seconds", "1e9"], "--seconds"),
    (["simulate", "--home", "--samples", "1000000000"], "--samples"),
    (["simulate", "--home", "--drift-tolerance", "0"], "--drift-tolerance"),
]


@pytest.mark.slow
def test_huge_counts_are_refused_at_once():
    """Each is refused in one line, exit 2, before anything is allocated: all of them in one
    fresh interpreter within a minute (each used to hang or exhaust memory)."""
    script = (
        "import contextlib, io, json, sys\n"
        "from assembler_pin.cli import main\n"
        "out = []\n"
        f"for argv, _ in {HUGE_COUNTS!r}:\n"
        "    err = io.StringIO()\n"
        "    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):\n"
        "        code = main(argv)\n"
        "    out.append([code, err.getvalue()])\n"
        "print(json.dumps(out))\n"
    )
    res = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    results = json.loads(res.stdout)
    for (argv, option), (code, err) in zip(HUGE_COUNTS, results, strict=True):
        lines = err.splitlines()
        assert code == 2 and len(lines) == 1 and option in lines[0] and "must be" in lines[0], (argv, err)


def test_the_helper_arm_scan_length_is_bounded(monkeypatch, capsys):
    import assembler_pin.helper_arm as helper_arm

    monkeypatch.setattr(helper_arm, "height_range", lambda cfg: (0.0, 100.0))  # 1e6 steps of 1e-4 m
    code, _, err = _run(capsys, ["solve", "--goal", *REACHABLE, "--d-step", "1e-4"])
    assert code == 2 and len(err) == 1 and "--d-step" in err[0] and "100000" in err[0]


def _hold_pose():
    from assembler_pin.simulate import hold_pose

    return hold_pose


@pytest.mark.parametrize(
    "make",
    [
        lambda am: ap.HelperArmOptions(max_attempts=10**9),
        lambda am: ap.HelperArmOptions(d_step=1e-12),
        lambda am: ap.OptimizeOptions(max_iterations=10**9),
        lambda am: _hold_pose()(am, am.home, seconds=1e9),
        lambda am: _hold_pose()(am, am.home, samples=10**9),
        lambda am: _hold_pose()(am, am.home, drift_tolerance=0.0),
        lambda am: __import__("assembler_pin.bench.calls").bench.calls.run_benchmarks(am, repeat=10**9),
    ],
)
def test_the_api_entries_bound_their_counts(am, make):
    """Refused at once (before a MuJoCo model or a benchmark pose is built)."""
    t0 = time.perf_counter()
    with pytest.raises((OptionsError, SimulationError), match="must be"):
        make(am)
    assert time.perf_counter() - t0 < 2.0


def test_a_singular_mujoco_system_is_a_singular_configuration_error(am, monkeypatch):
    from assembler_pin.simulate import MujocoStack, mujoco_statics

    stack = MujocoStack(am)

    def singular(a, b):
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr(np.linalg, "solve", singular)
    with pytest.raises(SingularConfigurationError, match="singular") as info:
        mujoco_statics(am, am.home, stack=stack)
    assert info.value.condition_number > 1.0 and 0 <= info.value.platform < am.n


# --- the carrier ---------------------------------------------------------------------------

CARRIER_GOAL = ["0.1", "0.2", "1.5", "0", "0", "0"]


def _record_carrier_solve(monkeypatch) -> dict:
    """Replace ``solve_on_carrier`` by a recorder answering "not possible"."""
    import assembler_pin.carrier as carrier_mod

    seen: dict = {}

    def recorder(am, carrier, goal, q0=None, **kwargs):
        seen.update(kwargs, q0=q0)
        rows = [(0.0, q0, math.nan, "stub"), (math.nan, q0, math.nan, "stub")]
        return carrier_mod.CarrierSolveResult(False, "recorded", goal, None, True, rows)

    monkeypatch.setattr(carrier_mod, "solve_on_carrier", recorder)
    return seen


def test_solve_on_a_carrier_passes_every_option(monkeypatch, capsys):
    seen = _record_carrier_solve(monkeypatch)
    argv = ["solve", "--carrier", "ur10", "--goal", *CARRIER_GOAL, "--method", "paper", "--w1", "2"]
    argv += ["--w2", "0.5", "--ee-tolerance", "1e-3", "2e-3", "--max-iterations", "33", "--ftol", "1e-5"]
    argv += ["--d-step", "0.02", "--max-attempts", "7", "--no-optimize", "--fixed-carrier"]
    code, out, _ = _run(capsys, argv)
    assert code == 1 and "recorded" in out
    o, h = seen["options"], seen["helper_options"]
    assert (o.method, o.w1, o.w2, o.max_iterations, o.ftol) == ("paper", 2.0, 0.5, 33, 1e-5)
    assert (o.ee_tolerance.position, o.ee_tolerance.rotation) == (1e-3, 2e-3)
    assert (h.d_step, h.max_attempts) == (0.02, 7)
    assert seen["optimize"] is False and seen["move_carrier"] is False
    # the joint optimization's row is named, not "placement t = nan"
    assert "t = nan" not in out and "joint optimization" in out and "placement t = 0.00" in out


def test_solve_on_a_carrier_refuses_what_cannot_apply(capsys):
    code, out, err = _run(capsys, ["solve", "--carrier", "ur10", "--goal", *CARRIER_GOAL, "--capacity"])
    assert code == 2 and out == "" and len(err) == 1 and "--capacity" in err[0] and "--carrier" in err[0]
    code, _, err = _run(capsys, ["solve", "--goal", *REACHABLE, "--fixed-carrier"])
    assert code == 2 and len(err) == 1 and "--carrier" in err[0]


def test_the_carrier_search_uses_the_given_options(am, monkeypatch):
    """Held carrier: the helper arm and the optimizer get the options; without optimization
    the helper arm's pose is returned as it is, and it reaches the world goal."""
    import assembler_pin.carrier.solve as carrier_solve_mod
    from assembler_pin.carrier import Carrier, carrier_objective, solve_on_carrier

    carrier = Carrier("ur10")
    goal = carrier.base_pose(carrier.upright_q) * ap.scenario("translation").goal
    calls: dict[str, list] = {"solve": [], "optimize": []}
    real_solve, real_opt = carrier_solve_mod.solve, carrier_solve_mod.optimize_internal_poses

    def solve(am_, goal_, optimize=True, options=None, helper_options=None):
        calls["solve"].append((optimize, options, helper_options))
        return real_solve(am_, goal_, optimize=optimize, options=options, helper_options=helper_options)

    def optimize(am_, start, goal_=None, options=None, motion=None):
        calls["optimize"].append(options)
        return real_opt(am_, start, goal_, options)

    monkeypatch.setattr(carrier_solve_mod, "solve", solve)
    monkeypatch.setattr(carrier_solve_mod, "optimize_internal_poses", optimize)
    options = ap.OptimizeOptions(w1=2.0, w2=0.5, max_iterations=150)
    helper = ap.HelperArmOptions(max_attempts=9, d_step=0.02)
    kwargs = {"move_carrier": False, "options": options, "helper_options": helper}
    result = solve_on_carrier(am, carrier, goal, optimize=False, **kwargs)
    assert calls == {"solve": [(False, options, helper)], "optimize": []}
    st = result.statics
    fk = ap.stack_forward_kinematics(am, st.state.leg_lengths, base=carrier.base_pose(st.q), guess=st.state.plates)
    assert fk.success and fk.plates.se3(am.n).isApprox(goal, 1e-6)
    # Ω_c with the given weights, recomputed from its definition
    lam = ap.kinematics.plate_deviation(am, st.state.plates).angles
    expected = 2.0 * np.abs(st.state.forces).max() + 0.5 * np.sqrt(np.sum(lam**2))
    expected += 200.0 * np.max(np.abs(st.torques) / carrier.effort_limit)
    assert carrier_objective(am, st, options=options) == pytest.approx(expected, rel=1e-12)
    assert result.candidates[0][2] == pytest.approx(expected, rel=1e-12)
    calls["solve"].clear()
    result = solve_on_carrier(am, carrier, goal, **kwargs)
    assert calls == {"solve": [(True, options, helper)], "optimize": [options]}
    assert result.success, result.message


@pytest.mark.slow
def test_an_unconverged_joint_optimization_is_never_kept(am, monkeypatch):
    """SLSQP's answer to the joint optimization with its status turned to "iteration limit":
    the best placement is kept, and the message says why."""
    import scipy.optimize

    from assembler_pin.carrier import Carrier, solve_on_carrier

    carrier = Carrier("ur10")
    goal = carrier.base_pose(carrier.upright_q) * ap.scenario("translation").goal
    joint_variables = carrier.model.nq + 6 * (am.n - 1) + 2
    real, said = scipy.optimize.minimize, []

    def unconverged(*args, **kwargs):
        res = real(*args, **kwargs)
        if len(kwargs.get("bounds") or ()) == joint_variables:  # the joint optimization only
            said.append(res.success)
            res.success, res.status, res.message = False, 9, "Iteration limit reached"
        return res

    monkeypatch.setattr(scipy.optimize, "minimize", unconverged)
    result = solve_on_carrier(am, carrier, goal, blends=2)
    placements = [q for t, q, _, _ in result.candidates if not math.isnan(t)]
    assert said == [True] and result.statics is not None  # SLSQP itself had converged
    assert any(np.array_equal(result.statics.q, q) for q in placements)  # a placement, not SLSQP's point
    assert "not kept" in result.message and "did not converge" in result.candidates[-1][3]
    assert result.success == result.statics.within_limits


# --- progress ------------------------------------------------------------------------------


def test_carrier_placements_report_progress(am, monkeypatch):
    import assembler_pin.carrier as carrier_mod
    import assembler_pin.carrier.solve as carrier_solve

    monkeypatch.setattr(carrier_solve, "_stack_on", lambda s, q: (None, "no stack pose (stub)"))
    carrier = carrier_mod.Carrier("ur10")
    goal = carrier.base_pose(carrier.upright_q) * ap.scenario("translation").goal
    stream = io.StringIO()
    calls = []

    def progress(done, total, note):
        calls.append((done, total, note))
        shown(done, total, note)

    shown = TerminalProgress("solve on ur10", enabled=True, stream=stream, min_interval=0.0)
    result = carrier_mod.solve_on_carrier(am, carrier, goal, blends=3, progress=progress)
    assert not result.success
    assert [c[:2] for c in calls] == [(1, 4), (2, 4), (3, 4)] and calls[0][2] == "placement t = 0.00"
    assert "solve on ur10: 3/4 placement t = 1.00" in stream.getvalue()


def test_reproduce_reports_progress_per_scenario(am, monkeypatch):
    import assembler_pin.reproduce as reproduce
    from assembler_pin.scenarios import SCENARIOS

    monkeypatch.setattr(reproduce, "solve", lambda am_, goal, **kw: ap.solve(am_, goal, optimize=False))
    monkeypatch.setattr(reproduce, "reference", lambda *a, **k: None)
    calls = []
    names = list(SCENARIOS)[:2]
    reproduce.run_scenarios(am, names, progress=lambda *c: calls.append(c))
    assert calls == [(k + 1, 2, name) for k, name in enumerate(names)]


def test_bench_reports_progress_per_figure(am, monkeypatch):
    import assembler_pin.bench.calls as bench
    from assembler_pin.bench.calls import run_benchmarks

    monkeypatch.setattr(bench, "BATCH_STACKS", 40)  # the figures' values are not the point here
    monkeypatch.setattr(bench, "benchmark_initial_condition", lambda am, **kw: {"initial_success_rate": 1.0})
    monkeypatch.setattr(bench, "_startup", lambda repeat: {"cli_help_s": 0.0})
    monkeypatch.setattr(bench, "benchmark_default_starts", lambda am, **kw: {"solve_p50_ms": 1.0})
    stream = io.StringIO()
    prog = TerminalProgress("bench", enabled=True, stream=stream, min_interval=0.0)
    calls = []
    results = run_benchmarks(am, repeat=2, optimize=False, quick=True, progress=lambda *c: (calls.append(c), prog(*c)))
    prog.close()
    assert [c[0] for c in calls] == list(range(1, 12)) and {c[1] for c in calls} == {11}
    assert calls[0][2] == "statics_us" and "statics_us" in results and "initial_success_rate" in results
    assert "solve_p50_ms" in results and "bench: 11/11 startup" in stream.getvalue()
    assert stream.getvalue().endswith("\r")


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.mark.slow
def test_the_cli_progress_shows_on_a_terminal_only(am, monkeypatch, capsys):
    import assembler_pin.carrier.solve as carrier_solve

    monkeypatch.setattr(carrier_solve, "_stack_on", lambda s, q: (None, "no stack pose (stub)"))
    argv = ["solve", "--carrier", "ur10", "--goal", *CARRIER_GOAL]
    assert main(argv) == 1
    assert capsys.readouterr().err == ""  # stderr is not a terminal here: no progress text
    captured_stderr = sys.stderr
    for quiet in (False, True):
        terminal = _Terminal()
        sys.stderr = terminal
        try:
            assert main((["-q"] if quiet else []) + argv) == 1
        finally:
            sys.stderr = captured_stderr
        text = terminal.getvalue()
        assert ("placement t = " in text) is not quiet, text
    capsys.readouterr()


def test_no_warning_escapes_the_cli(monkeypatch, capsys):
    """In process too: a warning raised inside a subcommand is logged, not shown."""

    def noisy(args):
        warnings.warn("divide by zero encountered", RuntimeWarning, stacklevel=1)
        return 0

    _replace_run(monkeypatch, noisy)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        assert _run(capsys, ["statics", "--home"]) == (0, "", [])
    assert seen == []


def test_ctrl_c_inside_a_finalizer_interrupts_the_command_without_a_traceback(monkeypatch, capsys):
    """A Ctrl-C that lands while the garbage collector runs a ``__del__`` would be printed as an
    ignored exception (a traceback) and the command would go on; it is raised again in the
    command's own code: one line, exit 130, and the unraisable hook is restored after."""

    class Finalized:
        def __del__(self) -> None:
            raise KeyboardInterrupt

    done = []

    def interrupted_in_a_finalizer(args):
        Finalized()  # its __del__ runs here, its interrupt is unraisable
        for _ in range(1000):  # the re-raised signal interrupts this loop
            time.sleep(0.001)
        done.append(True)
        return 0

    before = sys.unraisablehook
    _replace_run(monkeypatch, interrupted_in_a_finalizer)
    assert _run(capsys, ["statics", "--home"]) == (130, "", ["assembler-pin statics: interrupted"])
    assert not done and sys.unraisablehook is before


def test_an_interrupt_redelivered_after_the_command_unwound_is_dropped():
    """A finalizer's interrupt whose redelivery is still pending when the signal handlers are
    restored does not interrupt what runs next."""
    import types

    from assembler_pin.common.signals import REDELIVERY_DELAY, interrupt_on_signals

    restore = interrupt_on_signals(("SIGTERM",))
    hook = sys.unraisablehook
    hook(types.SimpleNamespace(exc_value=KeyboardInterrupt(), exc_type=KeyboardInterrupt))
    restore()
    time.sleep(20 * REDELIVERY_DELAY)  # a KeyboardInterrupt here would fail the test
    assert sys.unraisablehook is not hook
