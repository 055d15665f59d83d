"""Any number of platforms: the per-platform statics against an independent whole-stack
solve, stacks of 1..8 platforms solved end to end, and a 64-platform stack."""

from __future__ import annotations

import numpy as np
import pytest
from checks import design_forces, design_problems, home_directions, whole_stack_forces

import assembler_pin as ap
from assembler_pin.bench.timing import random_reachable_plates


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 6])
@pytest.mark.parametrize("whole_stack", [False, True])
def test_per_platform_statics_equal_the_whole_stack(n, whole_stack):
    # both engines of solve_statics: one model per platform, and the whole-stack model on a caller's Data
    am = ap.AssemblerModel.from_config({"platforms": n})
    data = am.create_data() if whole_stack else None
    rng = np.random.default_rng(n)
    for _ in range(4):
        _, plates = random_reachable_plates(am, rng, spread=0.8)
        result = ap.solve_statics(am, plates, data=data)
        np.testing.assert_allclose(result.forces, whole_stack_forces(am, plates), atol=1e-9)


def _total_weight(cfg) -> float:
    """Every mass of the stack from the configuration alone [N]."""
    n = cfg.platforms
    masses = (n + 1) * cfg.plate.mass + 6 * n * (cfg.leg.motor_mass + cfg.leg.shaft_mass) + cfg.payload.mass
    return masses * cfg.gravity


def test_a_64_platform_stack_builds_and_holds_its_weight():
    am = ap.AssemblerModel.from_config({"platforms": 64})
    result = ap.solve_statics(am, am.home)
    assert result.forces.shape == (64, 6) and np.all(np.isfinite(result.forces))
    # the mount carries the whole weight, straight up, with no moment (the home pose is symmetric)
    np.testing.assert_allclose(result.base_wrench[:3], [0.0, 0.0, _total_weight(am.config)], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(result.base_wrench[3:], 0.0, atol=1e-9)
    # at home each platform's six legs share the weight above their top plate equally
    cfg = am.config
    axial_z = home_directions(cfg, 0)[0, 2]
    above = [
        cfg.payload.mass + (64 - j) * cfg.plate.mass + 6 * (63 - j) * (cfg.leg.motor_mass + cfg.leg.shaft_mass)
        for j in range(64)
    ]
    # legs' own weight adds to the compression; bounds: without and with the whole leg weight
    low = -np.array(above) * cfg.gravity / (6 * axial_z)
    legs = (cfg.leg.motor_mass + cfg.leg.shaft_mass) * cfg.gravity / axial_z
    assert np.all(result.forces.max(axis=1) <= low + 1e-9) and np.all(result.forces.min(axis=1) >= low - legs)
    # and exactly: free bodies of the legs and plates (checks.py)
    np.testing.assert_allclose(result.forces, design_forces(cfg, ap.kinematics.plate_arrays(am, am.home)), atol=1e-9)
    with pytest.raises(ap.exceptions.ConfigError, match="gigabytes"):
        _ = am.data


@pytest.mark.parametrize("n", [1, 2, 3, 6, 8])
def test_stacks_of_any_size_solve_their_own_reachable_goals(n):
    am = ap.AssemblerModel.from_config({"platforms": n})
    rng = np.random.default_rng(10 + n)
    _, plates = random_reachable_plates(am, rng, spread=0.5)
    goal = plates.se3(n)
    result = ap.solve(am, goal)
    assert result.success, result.message
    state = result.optimized
    fk = ap.stack_forward_kinematics(am, state.leg_lengths).raise_if_failed()
    np.testing.assert_allclose(fk.as_matrices()[-1], goal.homogeneous, atol=1e-9)
    # every constraint and the forces, from the design anchors and free bodies (checks.py)
    assert design_problems(am.config, state.plates, goal=goal) == []
    np.testing.assert_allclose(state.forces, design_forces(am.config, fk), atol=1e-6)
    if n <= 6:
        np.testing.assert_allclose(state.forces, whole_stack_forces(am, state.plates), atol=1e-9)


def test_batched_statics_equal_the_single_path(am):
    rng = np.random.default_rng(3)
    stacks = [random_reachable_plates(am, rng)[1] for _ in range(5)]
    batch = np.array([s.as_matrices() for s in stacks])
    forces = ap.statics.solve_statics_batch(am, batch)
    assert forces.shape == (5, am.n, 6)
    for b, plates in enumerate(stacks):
        np.testing.assert_allclose(forces[b], whole_stack_forces(am, plates), atol=1e-9)
    with pytest.raises(ap.exceptions.PoseError, match="shape"):
        ap.statics.solve_statics_batch(am, batch[:, :-1])
