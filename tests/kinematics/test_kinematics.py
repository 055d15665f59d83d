"""Kinematics: closed-form q, IK, deflections, SP/stack FK, EE Jacobian."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from checks import design_anchors, sp_legs
from conftest import random_se3

from assembler_pin import stack_forward_kinematics
from assembler_pin.exceptions import ConvergenceError, PoseError
from assembler_pin.kinematics import (
    PlateArrays,
    ee_jacobian_wrt_lengths,
    leg_state,
    plate_arrays,
    plates_from_q,
    q_from_plates,
    sp_forward_kinematics,
)


def _closure_residuals(am, q) -> np.ndarray:
    pin.forwardKinematics(am.model, am.data, q)
    pin.updateFramePlacements(am.model, am.data)
    return np.array(
        [
            np.linalg.norm(
                am.data.oMi[int(am.shaft_joint_ids[j, i])].translation
                - am.data.oMf[int(am.anchor_frame_ids[j, i])].translation
            )
            for j in range(am.n)
            for i in range(6)
        ]
    )


def test_q_from_plates_closes_every_loop(am, random_poses):
    rng = np.random.default_rng(1)
    for _, plates in random_poses:
        base = random_se3(rng, 0.5)
        moved = PlateArrays(*_rigid(plates, base))
        q = q_from_plates(am, moved)
        assert _closure_residuals(am, q).max() < 1e-12
        back = plates_from_q(am, q)
        assert np.allclose(back.R, moved.R, atol=1e-14) and np.allclose(back.p, moved.p, atol=1e-14)
        assert np.allclose(q[am.leg_idx_q[:, :, 2]], leg_state(am, moved).lengths, atol=1e-15)


def _rigid(plates, M):
    R = np.matmul(M.rotation, plates.R)
    p = plates.p @ M.rotation.T + M.translation
    return R, p


def test_leg_lengths_are_the_paper_ik(am, random_poses):
    """L_i = ||p_top - p_bottom|| from anchors written out independently."""
    assert np.allclose(leg_state(am, am.home).lengths, am.config.leg.mid_length, atol=1e-15)
    for _, plates in random_poses:
        legs = leg_state(am, plates)
        for j in range(am.n):
            b, t = design_anchors(am.config, j)
            bw = b @ plates.R[j].T + plates.p[j]
            tw = t @ plates.R[j + 1].T + plates.p[j + 1]
            assert np.allclose(legs.lengths[j], np.linalg.norm(tw - bw, axis=1), atol=1e-15)
            assert np.allclose(legs.bottom_points[j], bw) and np.allclose(legs.top_points[j], tw)


def test_deflections(am, random_poses):
    home = leg_state(am, am.home)
    assert np.abs(home.deflection).max() < 1e-7
    rng = np.random.default_rng(2)
    for _, plates in random_poses:
        legs = leg_state(am, plates)
        for j in range(am.n):  # both joints' deflections and the rise from the design anchors
            _, bottom, top, rise = sp_legs(am.config, j, plates.R[j], plates.p[j], plates.R[j + 1], plates.p[j + 1])
            np.testing.assert_allclose(legs.deflection[j], np.stack([bottom, top], axis=-1), atol=1e-7)
            np.testing.assert_allclose(legs.rise[j], rise, atol=1e-14)
        # second method for the bottom joint: the universal joint's two angles
        q = q_from_plates(am, plates)
        ux, uy = q[am.leg_idx_q[:, :, 0]], q[am.leg_idx_q[:, :, 1]]
        assert np.allclose(np.cos(legs.deflection[..., 0]), np.cos(ux) * np.cos(uy), atol=1e-12)
        # both angles are measured in plate frames: invariant under a rigid motion of everything
        moved = leg_state(am, PlateArrays(*_rigid(plates, random_se3(rng))))
        assert np.allclose(moved.deflection, legs.deflection, atol=1e-7)
        assert np.allclose(moved.rise, legs.rise, atol=1e-14)
    # top joint: tilting only the top plate about its own centre deflects its ball joints
    plates = plate_arrays(am, am.home)
    tilt = pin.exp3(np.array([0.2, 0.0, 0.0]))
    R = plates.R.copy()
    R[1:] = tilt @ R[1:]
    p = plates.p.copy()
    p[2:] = (p[2:] - p[1]) @ tilt.T + p[1]
    legs = leg_state(am, PlateArrays(R, p))
    expected = sp_legs(am.config, 0, R[0], p[0], R[1], p[1])[2]  # top deflections from the design anchors
    assert np.allclose(legs.deflection[0, :, 1], expected) and expected.max() > 0.05


def test_sp_fk_round_trip(am, random_poses):
    for lengths, plates in random_poses:
        for j in range(am.n):
            res = sp_forward_kinematics(am, j, lengths[j])
            assert res.success and res.residual <= 1e-12 and res.iterations <= 10
            expected = plates.se3(j).actInv(plates.se3(j + 1))
            assert np.allclose(res.pose.homogeneous, expected.homogeneous, atol=1e-10)
            # FK from the converged pose: zero iterations needed
            again = sp_forward_kinematics(am, j, lengths[j], guess=res.pose)
            assert again.success and again.iterations == 0


def test_fk_failure_is_explicit(am):
    res = sp_forward_kinematics(am, 0, [0.02] * 6)  # shorter than the node spacing allows
    assert not res.success and res.residual > 1e-3 and "did not converge" in res.message
    with pytest.raises(ConvergenceError) as info:
        res.raise_if_failed()
    assert info.value.residual == res.residual
    stack = stack_forward_kinematics(am, np.full((am.n, 6), 0.02))
    assert not stack.success
    with pytest.raises(ConvergenceError):
        stack.raise_if_failed()
    with pytest.raises(PoseError, match="finite"):
        sp_forward_kinematics(am, 0, [0.3, 0.3, np.nan, 0.3, 0.3, 0.3])
    with pytest.raises(PoseError, match="shape"):
        sp_forward_kinematics(am, 0, [0.3] * 5)
    with pytest.raises(PoseError, match="platform index"):
        sp_forward_kinematics(am, 9, [0.3] * 6)


def test_stack_fk_round_trip_with_moved_base(am, random_poses):
    rng = np.random.default_rng(3)
    for lengths, plates in random_poses:
        base = random_se3(rng, 0.3)
        res = stack_forward_kinematics(am, lengths, base=base.homogeneous)
        assert res.success
        R, p = _rigid(plates, base)
        assert np.allclose(res.plates.R, R, atol=1e-10) and np.allclose(res.plates.p, p, atol=1e-10)
        assert np.abs(leg_state(am, res.plates).lengths - lengths).max() < 1e-12


def test_ee_jacobian_matches_finite_differences(am, random_poses):
    lengths, plates = random_poses[0]
    jac = ee_jacobian_wrt_lengths(am, plates)
    ee0 = plates.se3(am.n)
    h = 1e-6
    fd = np.zeros_like(jac)
    for c in range(6 * am.n):
        dL = np.zeros(6 * am.n)
        dL[c] = h
        ee_p = stack_forward_kinematics(am, lengths + dL.reshape(am.n, 6)).raise_if_failed().se3(am.n)
        ee_m = stack_forward_kinematics(am, lengths - dL.reshape(am.n, 6)).raise_if_failed().se3(am.n)
        # twist in world-aligned axes at the EE origin: [dp, dθ_world]
        dp = (ee_p.translation - ee_m.translation) / (2 * h)
        dtheta = pin.log3(ee_p.rotation @ ee_m.rotation.T) / (2 * h)
        fd[:, c] = np.concatenate([dp, dtheta])
    assert np.allclose(jac, fd, atol=1e-7 * np.abs(jac).max())
    assert ee0.translation[2] > 0


@pytest.mark.parametrize(
    ("plates", "needle"),
    [
        ([np.eye(4)] * 4, "expected 5 plate poses"),
        ([np.eye(4)] * 4 + [np.full((4, 4), np.nan)], "NaN"),
        ([np.eye(4)] * 4 + [np.eye(3)], "4x4"),
        ([np.eye(4)] * 4 + [np.diag([2.0, 1, 1, 1])], "not a rotation"),
        ([np.eye(4)] * 4 + [np.diag([-1.0, 1, 1, 1])], "not a rotation"),
        ([np.eye(4)] * 4 + [[["a"] * 4] * 4], "4x4"),
        ("plates", "list"),
    ],
)
def test_bad_plate_input(am, plates, needle):
    with pytest.raises(PoseError, match=needle):
        plate_arrays(am, plates)


def test_taa_round_trip_and_errors():
    from assembler_pin.kinematics import se3_to_taa, taa_to_se3

    x = np.array([0.1, -0.2, 0.9, 0.3, -0.4, 0.5])
    M = taa_to_se3(x)
    assert np.allclose(M.rotation, pin.exp3(x[3:])) and np.allclose(se3_to_taa(M), x)
    assert np.allclose(taa_to_se3([0, 0, 0, 90, 0, 0], degrees=True).rotation, pin.exp3(np.array([np.pi / 2, 0, 0])))
    with pytest.raises(PoseError, match="six numbers"):
        taa_to_se3([1, 2, 3])
    with pytest.raises(PoseError, match="NaN"):
        taa_to_se3([0, 0, np.nan, 0, 0, 0])


def test_the_leg_measures_batched_and_relative_equal_the_design(am, random_poses):
    """kinematics.legs over a batch of stacks (leading axis), and from relative plate poses
    (the helper arm's form), against the legs recomputed from the design (checks.py)."""
    from assembler_pin.kinematics import legs

    cfg, geo = am.config, am.geometry
    R = np.stack([plates.R for _, plates in random_poses])  # (B, n+1, 3, 3)
    p = np.stack([plates.p for _, plates in random_poses])
    bottom, top = legs.leg_points(geo, R, p)
    vec = top - bottom
    lengths = legs.leg_lengths(vec)
    in_bottom, in_top = legs.directions_in_plates(vec / lengths[..., None], R[:, :-1], R[:, 1:])
    cos = legs.deflection_cosines(in_bottom, in_top, geo.home_direction)
    rise = legs.leg_rise(in_bottom, lengths)
    rel_R = np.matmul(np.swapaxes(R[:, :-1], -1, -2), R[:, 1:])
    rel_p = np.matmul(np.swapaxes(R[:, :-1], -1, -2), (p[:, 1:] - p[:, :-1])[..., None])[..., 0]
    rel_lengths, rel_cos, rel_rise = legs.relative_leg_measures(geo, rel_R, rel_p)
    for b in range(R.shape[0]):
        for j in range(am.n):
            L, defl_b, defl_t, h = sp_legs(cfg, j, R[b, j], p[b, j], R[b, j + 1], p[b, j + 1])
            expected_cos = np.stack([np.cos(defl_b), np.cos(defl_t)], axis=-1)
            for got_L, got_cos, got_rise in ((lengths, cos, rise), (rel_lengths, rel_cos, rel_rise)):
                np.testing.assert_allclose(got_L[b, j], L, rtol=0, atol=1e-14)
                np.testing.assert_allclose(got_cos[b, j], expected_cos, rtol=0, atol=1e-13)
                np.testing.assert_allclose(got_rise[b, j], h, rtol=0, atol=1e-14)


def test_the_compiled_leg_state_is_the_numpy_composition(am, random_poses):
    """Every field of the compiled leg state against the numpy functions composed
    (:func:`~assembler_pin.kinematics.legs.reference_leg_state`): 1e-12 m and 1e-12 on unit
    vectors; the deflections 1e-12 rad away from θ = 0, where arccos amplifies rounding (its
    cosine agrees to 1e-15 there); coincident joint centres refused by both in one message."""
    import dataclasses

    from assembler_pin.kinematics.legs import reference_leg_state

    rng = np.random.default_rng(7)
    for _, plates in random_poses:
        moved = PlateArrays(*_rigid(plates, random_se3(rng, 0.5)))
        ours, ref = leg_state(am, moved), reference_leg_state(am, moved)
        for field in dataclasses.fields(ours):
            tol = 1e-12 if field.name != "deflection" else 1e-7
            np.testing.assert_allclose(getattr(ours, field.name), getattr(ref, field.name), atol=tol, rtol=0)
        np.testing.assert_allclose(np.cos(ours.deflection), np.cos(ref.deflection), atol=1e-15, rtol=0)
        away = ref.deflection > 1e-3
        np.testing.assert_allclose(ours.deflection[away], ref.deflection[away], atol=1e-12, rtol=0)
    p = am.config.home_height * np.arange(am.n + 1.0)[:, None] * np.array([0.0, 0.0, 1.0])
    p[1] = am.geometry.bottom_in_plate[0, 0] - am.geometry.top_in_plate[0, 0]  # leg 0's two joints meet
    collapsed = PlateArrays(np.repeat(np.eye(3)[None], am.n + 1, axis=0), p)
    for fn in (leg_state, reference_leg_state):
        with pytest.raises(PoseError, match="joint centres on top of each other"):
            fn(am, collapsed)


def test_plate_arrays_index_and_iterate_as_the_list_of_poses(am, bent_plates):
    """``PlateArrays`` reads as the list of ``pin.SE3`` it was made from: every index, negative
    ones included, each slice, iteration, and the same errors for an index out of range or not
    an integer."""
    poses = bent_plates.as_se3()
    plates = plate_arrays(am, poses)
    n1 = len(poses)
    for k in range(-n1 - 1, n1 + 1):
        if -n1 <= k < n1:
            assert plates[k].isApprox(poses[k], 0.0), k
            assert plates[np.int64(k)].isApprox(poses[k], 0.0), k
        else:
            with pytest.raises(IndexError):
                poses[k]
            with pytest.raises(IndexError):
                plates[k]
    for cut in (slice(1, 3), slice(None, None, -1), slice(-2, None), slice(3, 1)):
        part = plates[cut]
        assert isinstance(part, PlateArrays) and len(part) == len(poses[cut])
        assert all(a.isApprox(b, 0.0) for a, b in zip(part, poses[cut], strict=True))
    assert all(a.isApprox(b, 0.0) for a, b in zip(plates, poses, strict=True)) and len(list(plates)) == n1
    for bad in (1.0, "1", None):
        with pytest.raises(TypeError):
            poses[bad]
        with pytest.raises(TypeError):
            plates[bad]
    plates[-1].translation[:] = 0.0  # a copy: the arrays are not changed through it
    assert np.array_equal(plates.p[-1], poses[-1].translation)
