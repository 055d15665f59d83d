"""The stack held at both ends: the elastic and the chosen distributions of leg forces, each held
to an independent computation.

The reference is written here from the design alone: the total potential of the free plates
1..n−1 (legs as springs ½k(L−L0)², the weight of plates, motors, shafts and payload placed from
the plate poses and the design anchors of ``checks.py``, as ``conftest.potential_energy`` does),
plates 0 and n fixed, its gradient by complex-step differentiation, minimized by
``scipy.optimize.minimize``. MuJoCo holds the exported MJCF with the EE welded to the world.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from checks import HeldStack, ee_held_reference
from scipy.optimize import linprog

import assembler_pin as ap
from assembler_pin.bench.supports import benchmark_supports
from assembler_pin.supports import held_plates, two_point_statics
from assembler_pin.supports.choice import chosen_distribution
from assembler_pin.supports.two_point import residual_tolerance

_MODELS: dict = {}


def _model(n: int) -> ap.AssemblerModel:
    if n not in _MODELS:
        _MODELS[n] = ap.AssemblerModel.from_config({"platforms": n})
    return _MODELS[n]


def _pose(am, kind: str) -> ap.PlateArrays:
    if kind == "home":
        return ap.kinematics.plate_arrays(am, am.home)
    rng = np.random.default_rng(11 + am.n)
    leg = am.config.leg
    while True:
        fk = ap.stack_forward_kinematics(am, rng.uniform(leg.min_length + 0.02, leg.max_length - 0.02, (am.n, 6)))
        if fk.success:
            return fk.plates


@pytest.fixture(scope="module")
def optimized(am) -> dict:
    """The paper's inchworm and vertical-lift poses, force-optimized by ap.solve."""
    out = {}
    for name in ("inchworm", "vertical_lift"):
        result = ap.solve(am, ap.scenario(name).goal)
        assert result.success, result.message
        out[name] = ap.kinematics.plate_arrays(am, result.optimized.plates)
    return out


# ---------------------------------------------------------------------- (a) the elastic distribution
@pytest.mark.parametrize("n", [2, 4, 8])
@pytest.mark.parametrize("kind", ["home", "random"])
def test_elastic_forces_are_the_independent_minimum_with_both_ends_fixed(n, kind):
    am = _model(n)
    pa = _pose(am, kind)
    rng = np.random.default_rng(n)
    rest = ap.kinematics.leg_state(am, pa).lengths + rng.uniform(-2e-5, 2e-5, (n, 6))  # commanded off the pose
    ours = two_point_statics(am, pa, rest)
    assert ours.success, ours.message
    ref = HeldStack(am.config, pa.R, pa.p, rest)
    x = ref.minimum()
    F = ref.forces(x)
    assert np.abs(ours.forces - F).max() <= 1e-6 * np.abs(F).max(), np.abs(ours.forces - F).max()
    floor = residual_tolerance(am, pa)  # 1e-9 N, or the rounding floor of a tall stack (16 ε k max|p|)
    assert ours.residual <= floor
    # the reference potential is stationary at our plates too, to the same floor (its a-gradient is 2× the moment)
    at_ours = HeldStack(am.config, ours.plates.R, ours.plates.p, rest)
    grad = at_ours.gradient(np.zeros(6 * (n - 1))).reshape(n - 1, 6)
    assert np.abs(grad[:, :3]).max() <= floor and np.abs(grad[:, 3:]).max() <= 2 * floor
    # the two supports carry the whole weight together
    cfg = am.config
    weight = cfg.gravity * (
        (n + 1) * cfg.plate.mass + 6 * n * (cfg.leg.motor_mass + cfg.leg.shaft_mass) + cfg.payload.mass
    )
    np.testing.assert_allclose(ours.base_wrench[:3] + ours.ee_wrench[:3], [0, 0, weight], atol=1e-9)


def test_one_platform_held_at_both_ends_carries_nothing_in_its_legs():
    am = _model(1)
    result = two_point_statics(am, am.home)
    assert result.success and result.max_abs_force == 0.0 and result.iterations == 0


# ---------------------------------------------------------------------- (b) the chosen distribution
def _reference_minmax(am, pa, rest_at: np.ndarray) -> float:
    """min max|F| over every 6n force vector the reference potential balances at ``pa`` (plates
    1..n−1 free), within the force limits and the stroke: an LP over the forces themselves, its
    equilibrium matrix from the reference gradient's dependence on the commanded lengths."""
    n, k, leg = am.n, am.config.leg.stiffness, am.config.leg
    L = ap.kinematics.leg_state(am, pa).lengths
    g0 = HeldStack(am.config, pa.R, pa.p, L).gradient(np.zeros(6 * (n - 1)))  # slack legs
    cols = []
    for e in np.eye(6 * n):  # ∂grad/∂F: commanded L − F/k for a unit force
        cols.append(HeldStack(am.config, pa.R, pa.p, L - e.reshape(n, 6) / k).gradient(np.zeros(6 * (n - 1))) - g0)
    A = np.array(cols).T
    m = 6 * n
    c = np.r_[np.zeros(m), 1.0]
    eye, ones = np.eye(m), np.ones((m, 1))
    lo = np.maximum(-leg.max_compression, k * (L - leg.max_length)).ravel()
    hi = np.minimum(leg.max_tension, k * (L - leg.min_length)).ravel()
    res = linprog(
        c,
        A_ub=np.block([[eye, -ones], [-eye, -ones]]),
        b_ub=np.zeros(2 * m),
        A_eq=np.hstack([A, np.zeros((A.shape[0], 1))]),
        b_eq=-g0,
        bounds=[*zip(lo, hi, strict=True), (0, None)],
        method="highs",
    )
    assert res.status == 0, res.message
    return float(res.fun)


def _check_chosen(am, pa) -> None:
    elastic = two_point_statics(am, pa)
    chosen = chosen_distribution(am, pa)
    assert elastic.success and chosen.success, (elastic.message, chosen.message)
    assert chosen.max_abs_force <= elastic.max_abs_force + 1e-6  # HiGHS's feasibility tolerance
    # equilibrium of the chosen forces at every free plate, from the reference potential
    grad = HeldStack(am.config, chosen.plates.R, chosen.plates.p, chosen.commanded).gradient(np.zeros(6 * (am.n - 1)))
    assert np.abs(grad.reshape(-1, 6)[:, :3]).max() <= 1e-9 and np.abs(grad.reshape(-1, 6)[:, 3:]).max() <= 2e-9
    # the offsets, applied through the elastic solve from the pose, give the chosen forces back
    applied = two_point_statics(am, pa, ap.kinematics.leg_state(am, pa).lengths + chosen.length_offsets)
    assert applied.success and np.abs(applied.forces - chosen.forces).max() <= 1e-6
    # and no balanced distribution does better (an LP over the forces, not the null space)
    assert chosen.max_abs_force == pytest.approx(_reference_minmax(am, chosen.plates, chosen.commanded), abs=1e-6)


def test_chosen_distribution_at_home_and_the_optimized_inchworm_and_vertical_lift(am, optimized):
    for pa in (ap.kinematics.plate_arrays(am, am.home), *optimized.values()):
        _check_chosen(am, pa)
    # the optimized poses have legs at their stroke ends: the chosen one stays commandable
    for pa in optimized.values():
        chosen = chosen_distribution(am, pa)
        assert chosen.within_stroke
        assert chosen.max_abs_force < two_point_statics(am, pa).max_abs_force - 0.3


def test_chosen_distribution_on_every_scenario(am):
    for name in ap.SCENARIOS:
        result = ap.solve(am, ap.scenario(name).goal)
        assert result.success, result.message
        for plates in (result.initial.plates, result.optimized.plates):
            _check_chosen(am, ap.kinematics.plate_arrays(am, plates))


def test_one_end_held_the_forces_are_the_statics_of_that_end(am):
    """Held at the base alone, the forces are unique: Pinocchio's statics, offsets none."""
    pa = _pose(am, "random")
    base = chosen_distribution(am, pa, "base", loaded=False)
    assert base.success
    np.testing.assert_allclose(base.forces, ap.solve_statics(am, pa).forces, rtol=0, atol=1e-9)
    ee = chosen_distribution(am, pa, "ee")
    assert ee.success and ee.check_error <= 1e-6 and ee.residual <= 1e-9
    np.testing.assert_allclose(ee.ee_wrench[:3], base.base_wrench[:3], atol=1e-9)  # the same weight


# ---------------------------------------------------------------------- MuJoCo, both ends welded
def _welded_mujoco(am):
    mujoco = pytest.importorskip("mujoco")
    from assembler_pin.model.mjcf import assembler_mjcf
    from assembler_pin.simulate import MujocoStack

    stack = MujocoStack(am)
    stack.model = mujoco.MjModel.from_xml_string(assembler_mjcf(am.config, weld_ee=True))
    stack.data = mujoco.MjData(stack.model)
    m = stack.model
    m.opt.timestep = 2e-4
    m.eq_solref[:] = (4e-4, 1.0)
    m.eq_solimp[:, :3] = (0.999, 0.999, 1e-3)
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    return stack


def _settle_welded(stack, pa, ctrl, seconds: float = 0.3) -> np.ndarray:
    """Both ends welded at ``pa``, the legs commanded to ``ctrl``: the settled actuator forces."""
    stack.set_plates(pa)
    ee = pa.se3(len(pa) - 1).inverse()  # the weld's relative pose: the world in the EE's frame
    x, y, z, w = pin.Quaternion(ee.rotation).coeffs()
    stack.model.eq_data[-1, 3:10] = [*ee.translation, w, x, y, z]
    stack.data.ctrl[:] = np.asarray(ctrl).ravel()
    for _ in range(round(seconds / stack.model.opt.timestep)):
        stack.mujoco.mj_step(stack.model, stack.data)
    assert np.abs(stack.data.qvel).max() < 1e-6
    assert np.linalg.norm(stack.plates().p[-1] - pa.p[-1]) < 1e-5  # the weld held
    return stack.actuator_forces()


@pytest.mark.parametrize("pose", ["home", "inchworm", "vertical_lift"])
def test_mujoco_welded_at_both_ends_settles_at_both_distributions(am, optimized, pose):
    pa = ap.kinematics.plate_arrays(am, am.home) if pose == "home" else optimized[pose]
    stack = _welded_mujoco(am)
    elastic = two_point_statics(am, pa)
    chosen = chosen_distribution(am, pa)
    for ours in (elastic, chosen):
        got = _settle_welded(stack, pa, ours.commanded)
        tol = max(0.01 * ours.max_abs_force, 0.5)
        assert np.abs(got - ours.forces).max() <= tol, np.abs(got - ours.forces).max()  # measured: 0.29 N


# ---------------------------------------------------------------------- bad input, CLI, speed
def test_bad_supports_lengths_and_poses(am):
    with pytest.raises(ap.exceptions.SupportError):
        held_plates(am, "middle")
    with pytest.raises(ap.exceptions.SupportError):
        chosen_distribution(am, am.home, "plate 2")
    free = chosen_distribution(am, am.home, "none")
    assert not free.success and "mechanism" in free.message and np.all(np.isnan(free.forces))
    with pytest.raises(ap.exceptions.PoseError):
        two_point_statics(am, am.home, np.full((am.n, 6), np.nan))
    turned = [pin.SE3.Identity()]
    for _ in range(am.n):
        turned.append(turned[-1] * pin.SE3(pin.exp3(np.array([0, 0, np.pi / 2])), np.array([0, 0, 0.24])))
    for result in (two_point_statics(am, turned), chosen_distribution(am, turned)):
        assert not result.success and "singular" in result.message and np.all(np.isnan(result.forces))
    assert "null" in __import__("assembler_pin.cli.common", fromlist=["dumps"]).dumps(result.to_dict())


def test_cli_support_json_text_and_refusals(capsys, tmp_path, am):
    from assembler_pin.cli import main

    assert main(["support", "--home", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(doc["forces"], two_point_statics(am, am.home).forces)
    assert set(doc["chosen"]) >= {"forces", "length_offsets", "max_abs_force"}
    assert main(["support", "--home"]) == 0
    text = capsys.readouterr().out
    assert "chosen" in text and max(map(len, text.splitlines())) <= 100
    turned = [pin.SE3.Identity()]
    for _ in range(am.n):
        turned.append(turned[-1] * pin.SE3(pin.exp3(np.array([0, 0, np.pi / 2])), np.array([0, 0, 0.24])))
    plates = tmp_path / "p.json"
    plates.write_text(json.dumps({"plates": [p.homogeneous.tolist() for p in turned]}))
    assert main(["support", "--plates", str(plates), "--json"]) == 1
    doc = json.loads(capsys.readouterr().out, parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))
    assert doc["success"] is False and doc["forces"][0][0] is None
    for argv in (["support"], ["support", "--plates", str(tmp_path / "missing.json")]):
        assert main(argv) == 2
        assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_benchmark_supports_reports_positive_times():
    figures = benchmark_supports(_model(2), repeat=2)
    assert set(figures) == {"two_point_statics", "chosen_distribution", "chosen_distribution_unchecked"}
    assert all(0 < t < 1 for t in figures.values())


@pytest.mark.parametrize("n", [1, 2, 4, 8])
def test_ee_held_statics_are_the_virtual_work_balance_with_plate_0_free(n):
    from assembler_pin.supports import ee_held_statics

    am = _model(n)
    for kind in ("home", "random"):
        pa = _pose(am, kind)
        held = ee_held_statics(am, pa)
        ref = ee_held_reference(am, pa)
        assert np.abs(held.forces - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max()), np.abs(held.forces - ref).max()
        # the EE support carries the whole weight, the payload's included
        cfg = am.config
        weight = cfg.gravity * (
            (n + 1) * cfg.plate.mass + 6 * n * (cfg.leg.motor_mass + cfg.leg.shaft_mass) + cfg.payload.mass
        )
        np.testing.assert_allclose(held.ee_wrench[:3], [0, 0, weight], atol=1e-9)


@pytest.mark.parametrize("n", [2, 4])
def test_turned_model_is_the_same_stack_held_at_both_ends(n):
    """The turned model at the same physical pose: the same joint centres, and held at both ends
    (the same physical support) the same elastic forces, to 1e-9 N."""
    from assembler_pin.walk import turned_model

    am = _model(n)
    tm = turned_model(am)
    pa = _pose(am, "random")
    ta = tm.plates(pa)
    b, t = ap.kinematics.leg_state(am, pa).bottom_points, ap.kinematics.leg_state(am, pa).top_points
    tb, tt = ap.kinematics.leg_state(tm.model, ta).bottom_points, ap.kinematics.leg_state(tm.model, ta).top_points
    for jp in range(n):  # turned bottoms are the original tops, leg for leg
        np.testing.assert_allclose(tb[jp], t[n - 1 - jp][tm.permutation[jp]], atol=1e-12)
        np.testing.assert_allclose(tt[jp], b[n - 1 - jp][tm.permutation[jp]], atol=1e-12)
    ours, turned = two_point_statics(am, pa), two_point_statics(tm.model, ta)
    assert ours.success and turned.success
    assert np.abs(tm.original_legs(turned.forces) - ours.forces).max() <= 1e-9
    np.testing.assert_allclose(tm.original_plates(ta).p, pa.p, atol=1e-15)


def test_mujoco_holding_the_ee_plate_gives_the_ee_held_forces(am):
    """The turned model's MJCF (its fixed base the physical EE plate) under MuJoCo's own
    gravity and constraint Jacobian (simulate.mujoco_statics): the EE-held forces."""
    pytest.importorskip("mujoco")
    from assembler_pin.simulate import mujoco_statics
    from assembler_pin.supports import ee_held_statics
    from assembler_pin.walk import turned_model

    tm = turned_model(am)
    for pa in (ap.kinematics.plate_arrays(am, am.home), _pose(am, "random")):
        got = tm.original_legs(mujoco_statics(tm.model, tm.plates(pa)).forces)
        ours = ee_held_statics(am, pa).forces
        assert np.abs(got - ours).max() <= 1e-6, np.abs(got - ours).max()


def test_chosen_distribution_ee_is_checked_by_the_ee_held_elastic_solve(am):
    """Formerly unchecked (check_error NaN): the EE-held forces now come back from the elastic
    solve with plate 0 free, and they are the virtual-work ones."""
    pa = _pose(am, "random")
    ee = chosen_distribution(am, pa, "ee")
    assert ee.success and ee.check_error <= 1e-6, ee
    ref = ee_held_reference(am, ee.plates)
    assert np.abs(ee.forces - ref).max() <= 1e-9 * np.abs(ref).max()


def test_cli_statics_support_ee_and_both(capsys, am):
    from assembler_pin.cli import main
    from assembler_pin.supports import ee_held_statics

    assert main(["statics", "--home", "--support", "ee", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(doc["forces"], ee_held_reference(am, ap.kinematics.plate_arrays(am, am.home)), atol=1e-9)
    assert doc["support"] == "ee" and doc["feasible"] is True
    assert np.allclose(doc["forces"], ee_held_statics(am, am.home).forces)
    assert main(["statics", "--home", "--support", "both", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(doc["forces"], two_point_statics(am, am.home).forces)
    assert main(["statics", "--home", "--support", "ee"]) == 0
    assert max(map(len, capsys.readouterr().out.splitlines())) <= 100
    assert main(["statics", "--home"]) == 0 and "Statics of 4 platforms" in capsys.readouterr().out
    for argv in (
        ["statics", "--home", "--support", "plate2"],
        ["statics", "--home", "--support", "ee", "--carrier", "ur5"],
    ):
        assert main(argv) == 2
        assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_small_simplex_matches_highs_or_declines():
    """The chosen distribution's own simplex against HiGHS on random minimax programs of its
    shape (degenerate ties and infeasible bounds among them): the same optimum, or None."""
    from assembler_pin.supports.choice import _small_simplex

    rng = np.random.default_rng(3)
    answered = 0
    for trial in range(60):
        N, Fp = rng.normal(size=(24, 6)), rng.normal(scale=50, size=24)
        if trial % 5 == 0:
            Fp[:] = 10.0  # every force tied, as at home
        bound = np.full(24, 200.0) if trial % 3 == 0 else rng.uniform(10, 200, 24)
        ones, zeros = np.ones((24, 1)), np.zeros((24, 1))
        A = np.block([[N, -ones], [-N, -ones], [N, zeros], [-N, zeros]])
        b = np.concatenate([-Fp, Fp, bound - Fp, Fp + bound])
        c = np.r_[np.zeros(6), 1.0]
        z = _small_simplex(A, b, c)
        ref = linprog(c, A_ub=A, b_ub=b, bounds=[(None, None)] * 6 + [(0, None)], method="highs")
        if z is None:
            assert ref.status != 0, trial  # declined only where HiGHS finds no optimum either
            continue
        answered += 1
        assert ref.status == 0 and abs(z[-1] - ref.fun) <= 1e-7 * max(1.0, ref.fun), trial
        assert np.all(A @ z <= b + 1e-7)
    assert answered >= 30
