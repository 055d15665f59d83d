"""The compiled pass of the optimizer's points against the numpy reference
(:mod:`assembler_pin.statics.derivatives`), finite differences of the Pinocchio statics and the plain
kinematics, and its fallback."""

from __future__ import annotations

import importlib.util

import numpy as np
import pinocchio as pin
import pytest
from checks import design_plate_deviation, twist_moved

from assembler_pin.bench.timing import random_reachable_plates
from assembler_pin.config import load_config
from assembler_pin.kinematics import PlateArrays, leg_state
from assembler_pin.model import AssemblerModel
from assembler_pin.statics import pose_kernel, pose_loops, solve_statics_pinocchio
from assembler_pin.statics.derivatives import pose_derivatives, pose_values

pytestmark = pytest.mark.skipif(importlib.util.find_spec("numba") is None, reason="no numba")

#: (name of the value, name of its derivative) in :class:`~assembler_pin.gradients.PoseDerivatives`.
PAIRS = (
    ("forces", "d_forces"),
    ("lengths", "d_lengths"),
    ("cos_deflection", "d_cos_deflection"),
    ("rise", "d_rise"),
    ("plate_angles", "d_plate_angles_sq"),
)


def _model(n: int) -> AssemblerModel:
    return AssemblerModel.from_config(load_config().replace(platforms=n))


def _bent_home(am: AssemblerModel, rng: np.random.Generator, scale: float) -> PlateArrays:
    """The home pose with plates 1..n moved by random world twists (legs off their limits)."""
    poses = [am.home[0]] + [pin.exp6(scale * rng.normal(size=6)) * m for m in am.home[1:]]
    return PlateArrays.from_se3(poses)


def _stacks(am: AssemblerModel, seed: int) -> list[PlateArrays]:
    rng = np.random.default_rng(seed)
    return [
        random_reachable_plates(am, rng, spread=0.8)[1],
        random_reachable_plates(am, rng)[1],
        _bent_home(am, rng, 0.03),
    ]


@pytest.mark.parametrize("n", [1, 2, 4, 7, 16])
def test_compiled_pass_equals_the_numpy_reference(n):
    """Values to 1e-10 (forces in N) and every derivative to 1e-10 of its largest entry (forces
    in N per m or rad: a platform near a singularity has large derivatives) on random stacks,
    reachable and not."""
    am = _model(n)
    compiled = pose_kernel.CompiledPass(am)
    for pa in _stacks(am, seed=n):
        ref = pose_derivatives(am, pa)
        values, derivs = compiled.values(pa), compiled.derivatives(pa)
        for value, derivative in PAIRS:
            assert np.abs(getattr(values, value) - getattr(ref, value)).max() <= 1e-10, value
            assert np.array_equal(getattr(derivs, value), getattr(values, value)), value
            expected = getattr(ref, derivative)
            scale = max(1.0, np.abs(expected).max())
            assert np.abs(getattr(derivs, derivative) - expected).max() <= 1e-10 * scale, derivative


def _independent_values(am: AssemblerModel, pa: PlateArrays) -> dict[str, np.ndarray]:
    """Forces by Pinocchio's statics, legs by the plain kinematics, λ² written out."""
    legs = leg_state(am, pa)
    return {
        "forces": solve_statics_pinocchio(am, pa).forces,
        "lengths": legs.lengths,
        "cos_deflection": np.cos(legs.deflection),
        "rise": legs.rise,
        "plate_angles": design_plate_deviation(pa) ** 2,
    }


@pytest.mark.parametrize("n", [1, 3])
def test_compiled_derivatives_match_finite_differences(n):
    """Every compiled derivative against central differences (h = 1e-6) of independent
    computations: Pinocchio's statics, the leg kinematics, the angles of paper eq. 9."""
    am = _model(n)
    pa = _stacks(am, seed=10 + n)[0]
    derivs = pose_kernel.CompiledPass(am).derivatives(pa)
    h = 1e-6
    fd = {name: np.zeros_like(getattr(derivs, d)) for name, d in PAIRS}
    for c in range(6 * n):
        plus, minus = _independent_values(am, twist_moved(pa, c, h)), _independent_values(am, twist_moved(pa, c, -h))
        for name in fd:
            fd[name][..., c] = (plus[name] - minus[name]) / (2 * h)
    for name, d in PAIRS:
        analytic = getattr(derivs, d)
        scale = max(1.0, np.abs(analytic).max())
        assert np.abs(fd[name] - analytic).max() <= 1e-6 * scale, name


def test_interpreted_loops_equal_the_compiled_pass():
    """The loops run as plain Python give the compiled numbers (to rounding)."""
    am = _model(2)
    pa = _stacks(am, seed=3)[1]
    compiled = pose_kernel.CompiledPass(am).derivatives(pa)
    n, C = am.n, 6 * am.n
    out = [np.empty((n, 6)), np.empty((n, 6)), np.empty((n, 6, 2)), np.empty((n, 6)), np.empty(n)]
    d_out = [np.zeros((n, 6, C)), np.zeros((n, 6, C)), np.zeros((n, 6, 2, C)), np.zeros((n, 6, C)), np.zeros((n, C))]
    model = pose_kernel.CompiledPass(am)._model
    assert pose_loops._pose_py(pa.R, pa.p, *model, True, *out, *d_out)
    for (value, derivative), v, dv in zip(PAIRS, out, d_out, strict=True):
        assert np.allclose(v, getattr(compiled, value), rtol=0, atol=1e-12), value
        assert np.allclose(dv, getattr(compiled, derivative), rtol=0, atol=1e-11), derivative


def test_a_singular_platform_gives_nan_forces_and_no_derivatives():
    """Platforms whose system cannot be solved (a NaN plate pose, which the numpy path refuses
    outright: the platforms it joins and, through the weight's moment, those below) give NaN
    forces on the values pass, the others their forces, and the derivatives are refused."""
    am = _model(3)
    pa = _stacks(am, seed=5)[0]
    p = pa.p.copy()
    p[1, 0] = np.nan  # plate 1: platforms 0 and 1 touch it, platform 2 stays defined
    bad = PlateArrays(pa.R.copy(), p)
    compiled = pose_kernel.CompiledPass(am)
    forces = compiled.values(bad).forces
    assert np.isnan(forces[:2]).all()
    assert np.abs(forces[2] - pose_values(am, pa).forces[2]).max() <= 1e-10  # plates 2, 3 and the payload
    with pytest.raises(np.linalg.LinAlgError, match="singular"):
        compiled.derivatives(bad)


def test_the_optimizer_runs_on_the_compiled_pass(monkeypatch):
    """The optimizer of a force objective evaluates its points on the compiled pass: with the
    numpy pass made to fail, a solve still succeeds."""
    import assembler_pin.optimize.problem as problem
    from assembler_pin import solve
    from assembler_pin.kinematics import taa_to_se3

    def refused(*args, **kwargs):
        raise AssertionError("the numpy pass ran")

    monkeypatch.setattr(problem, "pose_values", refused)
    monkeypatch.setattr(problem, "pose_derivatives", refused)
    result = solve(_model(4), taa_to_se3([0.05, 0.0, 0.95, 0.0, 0.1, 0.0]))
    assert result.success and result.optimized.feasible
