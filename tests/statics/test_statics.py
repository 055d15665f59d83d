"""Statics held to independent computations: Jacobian-transpose truss, virtual work, weight."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from checks import design_anchors, design_forces
from conftest import potential_energy, random_se3

from assembler_pin import AssemblerModel, solve_statics, stack_forward_kinematics
from assembler_pin.exceptions import ArgumentError, SingularConfigurationError
from assembler_pin.kinematics import PlateArrays, q_from_plates
from assembler_pin.statics import closure_jacobian_blocks


def test_closure_jacobian_equals_pinocchio_constraint_jacobian(am, random_poses):
    """Our per-platform block Jacobian against Pinocchio's PointAnchorConstraintModel on the
    whole-stack model. Platform j's own model is platform 0 turned by 60°·j, whose universal
    joints are turned about the leg axis too: their (ux, uy) columns span the same plane as
    the whole model's; the actuator and top-plate columns are the same."""
    _, plates = random_poses[1]
    q = q_from_plates(am, plates)
    model, data = am.model, am.data
    pin.computeJointJacobians(model, data, q)
    for cm, cd in zip(am.constraint_models, am.constraint_datas, strict=True):
        cm.calc(model, data, cd)
    reference = pin.getConstraintsJacobian(model, data, am.constraint_models, am.constraint_datas)
    blocks = closure_jacobian_blocks(am, plates)
    for j in range(am.n):
        rows = [
            -data.oMi[int(am.shaft_joint_ids[j, i])].rotation @ reference[3 * (6 * j + i) : 3 * (6 * j + i) + 3]
            for i in range(6)
        ]
        ref = np.vstack(rows)[:, am.platform_rows_v[j]]  # Pinocchio: anchor minus shaft, in the shaft's frame
        ours = blocks[j]
        np.testing.assert_allclose(ours[:, 18:], ref[:, 18:], atol=1e-13)  # top plate's free-flyer
        for i in range(6):
            cols = slice(3 * i, 3 * i + 3)
            np.testing.assert_allclose(ours[:, 3 * i + 2], ref[:, 3 * i + 2], atol=1e-13)  # actuator
            universal = ref[:, cols][:, :2]
            projector = universal @ np.linalg.pinv(universal)
            np.testing.assert_allclose(projector @ ours[:, cols][:, :2], ours[:, cols][:, :2], atol=1e-12)
            assert np.linalg.matrix_rank(ours[:, cols], tol=1e-9) == 3


def _truss_forces(cfg, plates) -> np.ndarray:
    """Massless legs: two-force members. For each SP, the six axial forces balance the
    weight of everything above (Jacobian-transpose wrench), solved with numpy only."""
    n, g = cfg.platforms, cfg.gravity
    out = np.zeros((n, 6))
    for j in range(n):
        # weight and its moment about the world origin, of plates j+1..n and the payload
        force = np.zeros(3)
        moment = np.zeros(3)
        points = [(cfg.plate.mass, plates.p[k]) for k in range(j + 1, n + 1)]
        points.append((cfg.payload.mass, plates.R[n] @ [0, 0, cfg.payload.offset] + plates.p[n]))
        for mass, c in points:
            w = np.array([0, 0, -mass * g])
            force += w
            moment += np.cross(c, w)
        b, t = design_anchors(cfg, j)
        bw = b @ plates.R[j].T + plates.p[j]
        tw = t @ plates.R[j + 1].T + plates.p[j + 1]
        u = (tw - bw) / np.linalg.norm(tw - bw, axis=1, keepdims=True)
        # leg in tension F pulls the top plate along -u at tw
        A = np.vstack([-u.T, -np.cross(tw, u).T])
        out[j] = np.linalg.solve(A, -np.concatenate([force, moment]))
    return out


def test_massless_legs_equal_jacobian_transpose_truss(massless_am):
    am = massless_am
    rng = np.random.default_rng(5)
    leg = am.config.leg
    for _ in range(5):
        lengths = rng.uniform(leg.min_length + 0.02, leg.max_length - 0.02, (am.n, 6))
        plates = stack_forward_kinematics(am, lengths).raise_if_failed()
        ours = solve_statics(am, plates).forces
        reference = _truss_forces(am.config, plates)
        assert np.allclose(ours, reference, rtol=1e-9, atol=1e-9 * np.abs(reference).max())


def test_leg_masses_equal_virtual_work_through_fk(am, random_poses):
    """F_i = -dV/dL_i, V computed from geometry alone, L perturbed through stack FK."""
    lengths, plates = random_poses[2]
    ours = solve_statics(am, plates).forces
    h = 1e-6
    reference = np.zeros((am.n, 6))
    for j in range(am.n):
        for i in range(6):
            dL = np.zeros((am.n, 6))
            dL[j, i] = h
            up = stack_forward_kinematics(am, lengths + dL, guess=plates).raise_if_failed()
            down = stack_forward_kinematics(am, lengths - dL, guess=plates).raise_if_failed()
            reference[j, i] = -(potential_energy(am.config, up) - potential_energy(am.config, down)) / (2 * h)
    assert np.allclose(ours, reference, rtol=1e-6, atol=1e-6 * np.abs(reference).max())


def test_base_wrench_is_the_total_weight(am, random_poses):
    rng = np.random.default_rng(6)
    for _, plates in random_poses[:3]:
        base = random_se3(rng, 0.3)
        R = np.matmul(base.rotation, plates.R)
        p = plates.p @ base.rotation.T + base.translation
        moved = PlateArrays(R, p)
        result = solve_statics(am, moved)
        weight = am.total_mass() * am.config.gravity
        com = pin.centerOfMass(am.model, am.data, q_from_plates(am, moved))
        assert np.allclose(result.base_wrench[:3], [0, 0, weight], rtol=1e-12)
        expected_moment = np.cross(com - moved.p[0], [0, 0, weight])
        assert np.allclose(result.base_wrench[3:], expected_moment, atol=1e-10)


def test_forces_invariant_under_yaw_of_the_whole_stack(am, random_poses):
    """Gravity is along z: turning everything about z and shifting it changes no force."""
    _, plates = random_poses[3]
    yaw = pin.SE3(pin.exp3(np.array([0, 0, 1.1])), np.array([0.3, -0.2, 0.5]))
    R = np.matmul(yaw.rotation, plates.R)
    p = plates.p @ yaw.rotation.T + yaw.translation
    assert np.allclose(solve_statics(am, PlateArrays(R, p)).forces, solve_statics(am, plates).forces, atol=1e-10)


def test_home_pose_forces_are_symmetric_and_compressive(am):
    forces = solve_statics(am, am.home).forces
    assert np.all(forces < 0)
    assert np.allclose(forces, forces[:, :1], atol=1e-12)  # six equal legs per platform
    assert np.all(np.diff(np.abs(forces[:, 0])) < 0)  # lower platforms carry more


def test_singular_platform_is_reported_not_answered(am):
    """A 3-3 platform turned 90° about its axis is the octahedral singularity."""
    plates = [pin.SE3.Identity()]
    turn = pin.SE3(pin.exp3(np.array([0, 0, np.pi / 2])), np.array([0, 0, am.config.home_height]))
    for _ in range(am.n):
        plates.append(plates[-1] * turn)
    result = solve_statics(am, plates)
    assert result.singular and result.condition.max() > 1e8
    with pytest.raises(SingularConfigurationError, match="singular"):
        solve_statics(am, plates, raise_on_singular=True)
    assert not solve_statics(am, am.home).singular


def test_the_statics_never_write_into_a_data_of_the_model(am, random_poses):
    """No computation writes a Data held by the model: after solving, the kept inspection
    Data still holds what the caller put in it."""
    _, plates = random_poses[2]
    data = am.data
    q_home = q_from_plates(am, am.home)
    pin.computeGeneralizedGravity(am.model, data, q_home)
    before = data.g.copy()
    solve_statics(am, plates)
    np.testing.assert_array_equal(data.g, before)


def test_a_caller_data_gives_the_free_body_forces(am, random_poses):
    """The whole-stack path on a Data the caller owns and the per-platform path both give the
    free-body forces of the design (checks.py); the caller's Data holds the pose's gravity."""
    data = am.create_data()
    assert data is not am.create_data()
    for _, plates in random_poses[:3]:
        whole = solve_statics(am, plates, data=data)
        alone = solve_statics(am, plates)
        reference = design_forces(am.config, plates)
        scale = np.abs(reference).max()
        np.testing.assert_allclose(whole.forces, reference, rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(alone.forces, reference, rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(whole.base_wrench, alone.base_wrench, rtol=0, atol=1e-9 * scale)
        g = pin.computeGeneralizedGravity(am.model, am.model.createData(), q_from_plates(am, plates))
        np.testing.assert_allclose(data.g, g, rtol=0, atol=1e-12)


def test_a_data_of_another_model_is_refused(am):
    other = AssemblerModel.from_config({"platforms": am.n + 1})
    for data, match in ((other.create_data(), "another model"), ("data", "pinocchio.Data")):
        with pytest.raises(ArgumentError, match=match):
            solve_statics(am, am.home, data=data)


def test_every_condition_number_is_numpys_one_norm_condition_of_the_leg_lines(am, random_poses):
    """The statics and the elastic truss report the same condition number: numpy's 1-norm
    condition of the 6×6 matrix whose columns are the legs' lines ``[u; r × u]`` (the statics
    in each top plate's axes, the truss in world axes), rebuilt here from the joint centres."""
    from assembler_pin.compliance.elastic import elastic_terms, line_conditions
    from assembler_pin.kinematics import leg_state

    for _, pa in (random_poses[2], random_poses[3]):
        legs = leg_state(am, pa)
        r_world = legs.top_points - pa.p[1:, None, :]  # top joints from each top plate's origin
        statics_cond = solve_statics(am, pa).condition
        truss_cond = line_conditions(elastic_terms(am, pa.R, pa.p, None, 1e5, hessian=False).lines)[1]
        for j in range(am.n):
            R = pa.R[j + 1]
            u_loc, r_loc = legs.directions[j] @ R, r_world[j] @ R
            W_local = np.vstack([u_loc.T, np.cross(r_loc, u_loc).T])
            W_world = np.vstack([legs.directions[j].T, np.cross(r_world[j], legs.directions[j]).T])
            assert statics_cond[j] == pytest.approx(np.linalg.cond(W_local, 1), rel=1e-9)
            assert truss_cond[j] == pytest.approx(np.linalg.cond(W_world, 1), rel=1e-9)
