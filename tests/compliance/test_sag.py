"""The sag measure of the optimizer (``compliance.sag_and_gradient``): its value against the
kinematics' EE Jacobian and the nonlinear loaded pose, its gradient against central finite
differences of the value in both charts."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import assembler_pin as ap
from assembler_pin.bench.timing import random_reachable_plates
from assembler_pin.compliance import sag_and_gradient
from assembler_pin.exceptions import OptionsError


def _moved(pa: ap.PlateArrays, plate: int, twist: np.ndarray, chart: str) -> ap.PlateArrays:
    poses = [pa.se3(j) for j in range(len(pa.p))]
    move = pin.exp6(twist)
    poses[plate] = move * poses[plate] if chart == "world" else poses[plate] * move
    return ap.PlateArrays.from_se3(poses)


def _central_differences(am, pa, chart: str, h: float = 1e-6) -> np.ndarray:
    fd = np.empty(6 * am.n)
    for col in range(6 * am.n):
        plate, axis = divmod(col, 6)
        e = np.zeros(6)
        e[axis] = h
        up = sag_and_gradient(am, _moved(pa, plate + 1, e, chart)).sag
        down = sag_and_gradient(am, _moved(pa, plate + 1, -e, chart)).sag
        fd[col] = (up - down) / (2 * h)
    return fd


@pytest.mark.parametrize("n", [1, 2, 4])
@pytest.mark.parametrize("chart", ["world", "local"])
def test_sag_gradient_is_the_central_differences_of_the_sag(n, chart):
    am = ap.AssemblerModel.from_config({"platforms": n})
    _, pa = random_reachable_plates(am, np.random.default_rng(10 + n))
    result = sag_and_gradient(am, pa, chart=chart)
    fd = _central_differences(am, pa, chart)
    assert result.gradient.shape == (6 * n,) and result.chart == chart
    assert np.linalg.norm(result.gradient - fd) < 1e-6 * np.linalg.norm(fd)


def test_sag_is_the_ee_jacobian_times_the_legs_stretch(am, random_poses):
    """δp = (J_ee F / k) translation, J_ee the kinematics' EE Jacobian of the 6n lengths."""
    for _, pa in random_poses[:3]:
        result = sag_and_gradient(am, pa)
        forces = ap.solve_statics(am, pa).forces
        twist = ap.kinematics.ee_jacobian_wrt_lengths(am, pa) @ forces.ravel() / am.config.leg.stiffness
        np.testing.assert_allclose(result.translation, twist[:3], rtol=0, atol=1e-12)
        assert result.sag == pytest.approx(np.linalg.norm(twist[:3]), rel=1e-12)


def test_linear_sag_is_close_to_the_nonlinear_loaded_pose(am, random_poses):
    """At 1e6 N/m the loads' own stiffness and the second order move the sag by under 1%."""
    for _, pa in random_poses[:3]:
        linear = sag_and_gradient(am, pa).translation
        loaded = ap.stiffness(am, pa).sag_translation
        assert np.linalg.norm(linear - loaded) < 1e-2 * np.linalg.norm(loaded)


def test_sag_scales_as_the_compliance():
    """Halving the legs' stiffness doubles the linear sag and its gradient."""
    stiff = ap.AssemblerModel.from_config({"leg": {"stiffness": 1e6}})
    soft = ap.AssemblerModel.from_config({"leg": {"stiffness": 5e5}})
    a, b = sag_and_gradient(stiff, stiff.home), sag_and_gradient(soft, soft.home)
    assert b.sag == pytest.approx(2 * a.sag, rel=1e-12)
    np.testing.assert_allclose(b.gradient, 2 * a.gradient, rtol=1e-10, atol=1e-18)


def test_an_unknown_chart_is_refused(am):
    with pytest.raises(OptionsError, match="chart"):
        sag_and_gradient(am, am.home, chart="taa")


def test_a_singular_pose_has_no_sag(am):
    """The octahedral singularity (plates turned 90°): refused, never a huge number."""
    turned = [pin.SE3.Identity()]
    for _ in range(am.n):
        turned.append(turned[-1] * pin.SE3(pin.exp3(np.array([0, 0, np.pi / 2])), np.array([0, 0, 0.24])))
    with pytest.raises(ap.exceptions.SingularConfigurationError, match="platform 0"):
        sag_and_gradient(am, turned)


def test_given_pose_derivatives_give_the_same_answer(am, random_poses):
    from assembler_pin.statics.derivatives import pose_derivatives

    _, pa = random_poses[4]
    own, given = sag_and_gradient(am, pa), sag_and_gradient(am, pa, derivatives=pose_derivatives(am, pa))
    assert own.sag == given.sag and np.array_equal(own.gradient, given.gradient)
