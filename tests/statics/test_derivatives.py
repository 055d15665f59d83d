"""Every derivative of the differentiable statics against finite differences of the
Pinocchio statics and of the plain kinematics."""

from __future__ import annotations

import numpy as np
import pytest
from checks import twist_moved

from assembler_pin.kinematics import PlateArrays, leg_state
from assembler_pin.statics import solve_statics_pinocchio
from assembler_pin.statics.derivatives import pose_derivatives


def _paper_lambda(am, pa: PlateArrays) -> np.ndarray:
    """Paper eq. 9, written out: angle between p_i - p_{i-1} and p_i^rest - p_{i-1}."""
    h = am.config.home_height
    out = []
    for i in range(1, am.n + 1):
        a = pa.p[i] - pa.p[i - 1]
        rest = pa.R[i - 1] @ [0, 0, h]
        out.append(np.arccos(np.clip(a @ rest / np.linalg.norm(a) / np.linalg.norm(rest), -1, 1)))
    return np.array(out)


@pytest.mark.parametrize("pose", [0, 5])
def test_values_equal_pinocchio_statics_and_kinematics(am, random_poses, pose):
    _, pa = random_poses[pose]
    d = pose_derivatives(am, pa)
    legs = leg_state(am, pa)
    assert np.allclose(d.forces, solve_statics_pinocchio(am, pa).forces, atol=1e-10)
    assert np.allclose(d.lengths, legs.lengths, atol=1e-15)
    assert np.allclose(d.cos_deflection, np.cos(legs.deflection), atol=1e-12)
    assert np.allclose(d.rise, legs.rise, atol=1e-15)
    assert np.allclose(d.plate_angles, _paper_lambda(am, pa), atol=1e-7)


@pytest.mark.parametrize("pose", [1, 6])
def test_derivatives_match_finite_differences(am, random_poses, pose):
    _, pa = random_poses[pose]
    d = pose_derivatives(am, pa)
    h = 1e-6
    C = 6 * am.n
    fd = {
        k: np.zeros((*v.shape, C))
        for k, v in {
            "forces": d.forces,
            "lengths": d.lengths,
            "cos": d.cos_deflection,
            "rise": d.rise,
            "lam_sq": d.plate_angles,
        }.items()
    }
    for c in range(C):
        plus, minus = twist_moved(pa, c, h), twist_moved(pa, c, -h)
        lp, lm = leg_state(am, plus), leg_state(am, minus)
        forces_plus, forces_minus = solve_statics_pinocchio(am, plus).forces, solve_statics_pinocchio(am, minus).forces
        fd["forces"][..., c] = (forces_plus - forces_minus) / (2 * h)
        fd["lengths"][..., c] = (lp.lengths - lm.lengths) / (2 * h)
        fd["cos"][..., c] = (np.cos(lp.deflection) - np.cos(lm.deflection)) / (2 * h)
        fd["rise"][..., c] = (lp.rise - lm.rise) / (2 * h)
        fd["lam_sq"][..., c] = (_paper_lambda(am, plus) ** 2 - _paper_lambda(am, minus) ** 2) / (2 * h)
    pairs = {
        "forces": d.d_forces,
        "lengths": d.d_lengths,
        "cos": d.d_cos_deflection,
        "rise": d.d_rise,
        "lam_sq": d.d_plate_angles_sq,
    }
    for name, analytic in pairs.items():
        scale = np.abs(fd[name]).max()
        assert np.abs(analytic - fd[name]).max() <= 1e-6 * scale + 1e-8, name


def test_gravity_free_stack_carries_no_force(random_poses):
    from assembler_pin import AssemblerModel, load_config

    am = AssemblerModel.from_config(load_config({"gravity": 0.0}))
    _, pa = random_poses[2]
    d = pose_derivatives(am, pa)
    assert np.abs(d.forces).max() < 1e-12 and np.abs(d.d_forces).max() < 1e-12


@pytest.mark.parametrize("pose", [3, 4])
def test_one_pass_values_are_the_free_body_statics_and_feed_the_derivatives(am, random_poses, pose):
    """``pose_values``: forces equal to free bodies from the design (checks.py), λ to eq. 9;
    derivatives extending that pass equal the ones computed from scratch."""
    from checks import design_forces, design_plate_deviation

    from assembler_pin.statics.derivatives import pose_values

    _, pa = random_poses[pose]
    values = pose_values(am, pa)
    np.testing.assert_allclose(values.forces, design_forces(am.config, pa), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(values.plate_angles, design_plate_deviation(pa), atol=1e-9)
    extended, fresh = pose_derivatives(am, pa, values), pose_derivatives(am, pa)
    for name in ("d_forces", "d_lengths", "d_cos_deflection", "d_rise", "d_plate_angles_sq"):
        assert np.array_equal(getattr(extended, name), getattr(fresh, name)), name
