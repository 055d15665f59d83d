"""The interior-point method (``method="ipopt"``): its answers checked by the independent
free-body forces and design constraints (:mod:`checks`), its Jacobian against central
differences, its optimum against SLSQP's, the ``auto`` rule and a missing CasADi."""

from __future__ import annotations

import json
import sys

import numpy as np
import pinocchio as pin
import pytest
from checks import design_forces, design_problems

from assembler_pin import AssemblerModel, load_config
from assembler_pin.config.options import AUTO_IPOPT_PLATFORMS, resolved_method
from assembler_pin.exceptions import OptionsError
from assembler_pin.kinematics import PlateArrays
from assembler_pin.optimize import OptimizeOptions, optimize_internal_poses

casadi = pytest.importorskip("casadi")

#: Why the tests marked with it fail today (known, open).
OWN_PLATE_RULE = (
    "the check of each leg against its own plates refuses the leaning poses these goals were answered "
    "with (a motor inside a plate); the optimizer does not yet find a clear pose for all of them"
)


IPOPT = OptimizeOptions(method="ipopt")


def bent_stack(n: int, twist=(0.004, 0.0, 0.0, 0.0, 0.01, 0.0)) -> tuple[AssemblerModel, PlateArrays]:
    """A stack of ``n`` platforms, each bent alike from its home pose (a feasible start)."""
    am = AssemblerModel.from_config(load_config().replace(platforms=n))
    step = pin.SE3(np.eye(3), np.array([0.0, 0.0, am.config.home_height])) * pin.exp6(np.array(twist))
    plates = [pin.SE3.Identity()]
    for _ in range(n):
        plates.append(plates[-1] * step)
    return am, PlateArrays.from_se3(plates)


def _independently_feasible(am, result, goal) -> None:
    """Every constraint by the design's own geometry and the free-body forces (checks.py)."""
    assert design_problems(am.config, result.optimized.plates, goal, 1e-9) == []
    forces = design_forces(am.config, result.optimized.plates)
    assert np.abs(forces).max() == pytest.approx(result.optimized.max_abs_force, rel=1e-9)


@pytest.fixture(scope="module")
def stack8():
    return bent_stack(8)


def test_ipopt_answer_meets_every_constraint_at_n4(am, random_poses):
    start = random_poses[7][1]
    result = optimize_internal_poses(am, start, options=IPOPT)
    assert result.success and result.method == "ipopt"
    _independently_feasible(am, result, start.se3(am.n))
    assert result.optimized.max_abs_force < result.initial.max_abs_force
    slsqp = optimize_internal_poses(am, start)
    assert result.optimized.max_abs_force <= slsqp.optimized.max_abs_force * (1 + 1e-3)


def test_ipopt_answer_meets_every_constraint_at_n8(stack8):
    am, start = stack8
    result = optimize_internal_poses(am, start, options=IPOPT)
    assert result.success and result.method == "ipopt"
    _independently_feasible(am, result, start.se3(am.n))
    slsqp = optimize_internal_poses(am, start)
    assert result.optimized.max_abs_force <= slsqp.optimized.max_abs_force * (1 + 1e-3)
    # the independent free-body forces of the start: the optimum is well below them
    assert result.optimized.max_abs_force < 0.8 * np.abs(design_forces(am.config, start)).max()


def test_ipopt_long_stack_hessian_start_keeps_the_optimum():
    """From SCALAR2_PLATFORMS up the limited-memory Hessian starts from IPOPT's ``scalar2``
    scale: at n = 16 the answer meets every constraint by the independent checks and is the
    optimum reached with IPOPT's default ``scalar1`` (to 1e-6 relative)."""
    from assembler_pin.bench.speed import long_stack
    from assembler_pin.optimize import ipopt

    am, start = long_stack(ipopt.SCALAR2_PLATFORMS)
    result = optimize_internal_poses(am, start, options=IPOPT)
    assert result.success
    _independently_feasible(am, result, start.se3(am.n))
    default = ipopt.ipopt_options
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(ipopt, "ipopt_options", lambda pr: {**default(pr), "ipopt.limited_memory_initialization": "scalar1"})
        scalar1 = optimize_internal_poses(am, start, options=IPOPT)
    assert scalar1.success
    assert result.optimized.max_abs_force == pytest.approx(scalar1.optimized.max_abs_force, rel=1e-6)


@pytest.mark.xfail(reason=OWN_PLATE_RULE, strict=False)
def test_ipopt_matches_slsqp_on_the_scenarios(am):
    """The five scenarios (n = 4) from the helper arm's start: IPOPT's max|F| within 1e-3
    of SLSQP's or below it, its answer feasible by the independent checks."""
    from assembler_pin.helper_arm import initial_condition
    from assembler_pin.scenarios import SCENARIOS

    for name, sc in SCENARIOS.items():
        init = initial_condition(am, sc.goal)
        assert init.success, name
        slsqp = optimize_internal_poses(am, init.state, sc.goal)
        ipopt = optimize_internal_poses(am, init.state, sc.goal, IPOPT)
        assert ipopt.optimized.feasible, name
        _independently_feasible(am, ipopt, sc.goal)
        assert ipopt.optimized.max_abs_force <= slsqp.optimized.max_abs_force * (1 + 1e-3), name


def _problem(am, start, options):
    from assembler_pin.optimize.problem import Problem

    return Problem(am, start, start.se3(am.n), options, True)


def _wrench_case(am, start, case):
    """A moment-variable form of one kind: plain, a free EE, or unequal force limits with a
    motion step (every row family)."""
    import dataclasses

    from assembler_pin.config.options import GoalTolerance
    from assembler_pin.optimize import MotionTerm
    from assembler_pin.optimize.wrench import WrenchForm
    from assembler_pin.state import evaluate_state

    if case == "ee":
        return WrenchForm(_problem(am, start, OptimizeOptions(method="ipopt", ee_tolerance=GoalTolerance(0.01, 0.05))))
    if case == "limits+motion":
        from assembler_pin.optimize.problem import Problem

        leg = dataclasses.replace(am.config.leg, max_tension=450.0, max_compression=380.0)
        am = AssemblerModel.from_config(am.config.replace(leg=leg))
        motion = MotionTerm(evaluate_state(am, start).leg_lengths + 1e-3, max_step=5e-3, w3=10.0)
        problem = Problem(am, start, start.se3(am.n), IPOPT, False, motion)
        assert not problem.force_limits.symmetric and problem.motion_rows is not None
        return WrenchForm(problem)
    return WrenchForm(_problem(am, start, IPOPT))


def _moved_point(form, seed=3):
    """A point off the start: the poses moved, the moment variables moved off the poses'
    moments (so the level rows do not hold), ``s`` = 40 N."""
    rng = np.random.default_rng(seed)
    x = form.x0(np.append(np.zeros(form.nx_pose), 40.0))
    x[: form.nx_pose] += rng.normal(0.0, 0.01, form.nx_pose)
    x[form.nx_pose : -1] += rng.normal(0.0, 0.05, 3 * form.n)
    return x


@pytest.mark.parametrize("case", ["plain", "ee", "limits+motion"])
def test_callback_jacobian_equals_central_differences(am, random_poses, case):
    """The Jacobian IPOPT gets through the CasADi callback (sparse, on the form's banded
    pattern) against central differences of the rows — poses, moment variables and ``s`` —
    and the objective's gradient, at a point where the level rows do not hold."""
    from assembler_pin.optimize.ipopt import values_callback

    form = _wrench_case(am, random_poses[7][1], case)
    cb = values_callback(form)
    X = casadi.MX.sym("x", form.shape[1])
    f, g = cb(X)
    fun = casadi.Function("j", [X], [casadi.jacobian(g, X), casadi.gradient(f, X)])
    x = _moved_point(form)
    assert np.abs(form.cons(x)[-3 * am.n :]).max() > 1e-3  # off the level rows
    J, grad = (np.asarray(casadi.DM(v).full()) for v in fun(x))
    h = 1e-6
    J_fd = np.empty_like(J)
    g_fd = np.empty(x.size)
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h
        J_fd[:, i] = (form.cons(x + e) - form.cons(x - e)) / (2 * h)
        g_fd[i] = (form.fun(x + e) - form.fun(x - e)) / (2 * h)
    assert J.shape == J_fd.shape == form.shape
    pattern = np.zeros(form.shape, dtype=bool)
    pattern[form.rows, form.cols] = True
    # every non-zero of the differences lies on the pattern
    assert np.abs(J_fd[~pattern]).max() < 1e-7 * np.abs(J_fd).max()
    scale = np.abs(J_fd).max(axis=1, keepdims=True) + 1e-12
    assert np.all(np.abs(J - J_fd) <= 1e-6 * scale + 1e-9)
    np.testing.assert_allclose(grad.ravel(), g_fd, rtol=1e-6, atol=1e-6 * np.abs(g_fd).max())


@pytest.mark.parametrize("case", ["plain", "ee", "limits+motion"])
def test_moment_form_is_the_smooth_form_where_the_levels_hold(am, random_poses, case):
    """With the moment variables at the poses' own moments (the independent cumulative sum
    of the closed form), the level rows are zero and every other row and the objective are
    :class:`SmoothForm`'s, bit for bit up to rounding."""
    from assembler_pin.optimize.smooth import SmoothForm
    from assembler_pin.optimize.wrench import MOMENT_SCALE
    from assembler_pin.statics.derivatives import pose_values

    form = _wrench_case(am, random_poses[7][1], case)
    smooth = SmoothForm(form.problem)
    x = _moved_point(form)
    plates = form.problem.chart.plates(x[: form.nx_pose])
    x[form.nx_pose : -1] = pose_values(form.problem.am, plates).eq.up_moment.ravel() / MOMENT_SCALE
    rows = form.cons(x)
    np.testing.assert_allclose(rows[-3 * am.n :], 0.0, atol=1e-12)
    x_smooth = np.append(x[: form.nx_pose], x[-1])
    np.testing.assert_allclose(rows[: -3 * am.n], smooth.cons(x_smooth), rtol=1e-12, atol=1e-9)
    assert form.fun(x) == pytest.approx(smooth.fun(x_smooth), rel=1e-12)
    np.testing.assert_allclose(form.smooth_x(x), x_smooth)


def test_pattern_is_banded_for_long_stacks():
    """No row reads more than two plates' chart columns, two platforms' moments and ``s``,
    and the non-zeros grow linearly with the stack: O(n), where the force rows of the
    poses-only form fill a triangle."""
    from assembler_pin.optimize.wrench import WrenchForm

    counts = {}
    for n in (8, 16, 24):
        am, start = bent_stack(n)
        form = WrenchForm(_problem(am, start, IPOPT))
        per_row = np.bincount(form.rows, minlength=form.shape[0])
        assert per_row.max() <= 12 + 3 + 1
        pose = form.cols < form.nx_pose
        first, last = np.full(form.shape[0], form.nx), np.full(form.shape[0], -1)
        np.minimum.at(first, form.rows[pose], form.cols[pose])
        np.maximum.at(last, form.rows[pose], form.cols[pose])
        assert (last - first)[last >= 0].max() < 12  # two consecutive plates
        counts[n] = form.rows.size
    assert counts[24] - counts[16] == counts[16] - counts[8]  # the same per platform


def test_auto_picks_by_size(am, random_poses, monkeypatch):
    assert resolved_method("auto", AUTO_IPOPT_PLATFORMS - 1) == "slsqp"
    assert resolved_method("auto", AUTO_IPOPT_PLATFORMS) == "ipopt"
    assert resolved_method("slsqp", 64) == "slsqp" and resolved_method("ipopt", 2) == "ipopt"
    result = optimize_internal_poses(am, random_poses[7][1], options=OptimizeOptions(method="auto"))
    assert result.method == "slsqp"
    monkeypatch.setitem(sys.modules, "casadi", None)
    assert resolved_method("auto", 64) == "slsqp"


def test_missing_casadi_is_one_line_options_error(monkeypatch, capsys):
    from assembler_pin.cli.app import main

    monkeypatch.setitem(sys.modules, "casadi", None)
    with pytest.raises(OptionsError, match=r"pip install 'casadi"):
        OptimizeOptions(method="ipopt")
    OptimizeOptions(method="auto")  # auto falls back to slsqp
    assert main(["solve", "--goal", "0.1", "0", "0.8", "0", "0", "0", "--method", "ipopt"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "pip install 'casadi" in err


def test_cli_method_ipopt(capsys):
    from assembler_pin.cli.app import main

    assert main(["solve", "--goal", "0.1", "0", "0.8", "0", "0", "0", "--method", "ipopt", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["success"]
    assert doc["optimizer"]["method"] == "ipopt"


def test_ipopt_sag_limit_and_motion_rows(am, random_poses):
    """The rows of the other smooth options reach IPOPT too: a sag limit below the force
    optimum's sag is met (by the package's independent sag of the returned state), and a
    motion step holds every leg within it of the previous sample."""
    from assembler_pin.compliance import sag_and_gradient
    from assembler_pin.optimize import MotionTerm
    from assembler_pin.state import evaluate_state

    start = random_poses[7][1]
    free = optimize_internal_poses(am, start, options=IPOPT)
    limit = 0.9 * sag_and_gradient(am, free.optimized.plates).sag
    capped = optimize_internal_poses(am, start, options=OptimizeOptions(method="ipopt", max_sag=limit))
    assert capped.success
    assert sag_and_gradient(am, capped.optimized.plates).sag <= limit
    _independently_feasible(am, capped, start.se3(am.n))
    previous = evaluate_state(am, start).leg_lengths
    motion = MotionTerm(previous, max_step=2e-3)
    stepped = optimize_internal_poses(am, start, options=IPOPT, motion=motion)
    assert stepped.optimized.feasible
    assert np.abs(stepped.optimized.leg_lengths - previous).max() <= 2e-3 + 1e-12


def test_long_stack_figure_and_its_bench_row(monkeypatch, capsys):
    """The scaling figure on two tiny stacks: every key, IPOPT's optimum no worse than
    SLSQP's; ``bench --speed`` prints it as its ``long_stacks`` group."""
    from assembler_pin.bench import speed as bench_speed
    from assembler_pin.cli.app import main

    row = bench_speed.benchmark_long_stacks(sizes=(2, 3))
    for n in (2, 3):
        for method in ("slsqp", "ipopt"):
            assert row[f"n{n}_{method}_success"], (n, method)
            assert row[f"n{n}_{method}_s"] > 0 and row[f"n{n}_{method}_iterations"] >= 1
        assert row[f"n{n}_ipopt_max_abs_force_N"] <= row[f"n{n}_slsqp_max_abs_force_N"] * (1 + 1e-3)
        _, plates = bench_speed.long_stack(n)
        am = AssemblerModel.from_config(load_config().replace(platforms=n))
        assert np.abs(design_forces(am.config, plates)).max() >= row[f"n{n}_ipopt_max_abs_force_N"] - 1e-9
    assert "ipopt_per_iteration_exponent" in row and row["per_iteration_exponent_target"] == 1.5
    stub = {"x": 1.0}
    for name in (
        "benchmark_threads",
        "benchmark_solve_starts",
        "benchmark_statics_kernel",
        "benchmark_capacity_memory",
    ):
        monkeypatch.setattr(bench_speed, name, lambda *a, **k: stub)
    monkeypatch.setattr(bench_speed, "benchmark_single_statics", lambda *a, **k: stub)
    monkeypatch.setattr(bench_speed, "benchmark_startup", lambda *a, **k: stub)
    monkeypatch.setattr(bench_speed, "benchmark_long_stacks", lambda *a, **k: {"n32_ipopt_s": 1.5})
    assert main(["bench", "--speed", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["long_stacks"] == {"n32_ipopt_s": 1.5}


def test_ctrl_c_inside_ipopt_reaches_the_caller(am, random_poses, monkeypatch):
    """A Ctrl-C in an evaluation is not taken for a failed evaluation: it is raised again
    once IPOPT returns."""
    from assembler_pin.optimize.wrench import WrenchForm

    real, calls = WrenchForm.cons, []

    def interrupted(self, x):
        calls.append(1)
        if len(calls) == 4:
            raise KeyboardInterrupt
        return real(self, x)

    monkeypatch.setattr(WrenchForm, "cons", interrupted)
    with pytest.raises(KeyboardInterrupt):
        optimize_internal_poses(am, random_poses[7][1], options=IPOPT)


def test_auto_finishes_an_ipopt_run_that_stopped_unconverged_with_slsqp():
    """``method="auto"`` on a 16-platform stack: where IPOPT alone stops without converging,
    auto's result is SLSQP's, converged from IPOPT's best state (``ipopt+slsqp``, both runs'
    iterations), no worse in max|F| and feasible by the design's own geometry and free-body
    forces; where IPOPT converges, auto is IPOPT's run. At least one of the two goals (the EE
    moved 0.2 m aside, or 0.32 m aside and 0.2 m down) exercises the first case."""
    from assembler_pin.helper_arm import initial_condition

    am16 = AssemblerModel.from_config({"platforms": 16})
    polished = 0
    for offset in ([0.2, 0.0, -0.08], [0.32, 0.0, -0.2]):
        goal = pin.SE3(np.eye(3), am16.home[-1].translation + np.array(offset))
        start = initial_condition(am16, goal).plates_if_valid()
        alone = optimize_internal_poses(am16, start, goal, IPOPT)
        auto = optimize_internal_poses(am16, start, goal, OptimizeOptions(method="auto"))
        assert alone.method == "ipopt"
        if alone.optimal:
            assert auto.method == "ipopt" and auto.objective_optimized == alone.objective_optimized
            continue
        polished += 1
        assert auto.success and auto.method == "ipopt+slsqp" and auto.iterations > alone.iterations
        assert auto.optimized.max_abs_force <= alone.optimized.max_abs_force + 1e-9
        _independently_feasible(am16, auto, goal)
    assert polished >= 1
