"""Helper arm (paper §III): URDF and limits, arm FK, initial condition, failures, CLI.

Every check is against an independent computation: the arm's FK against a product of
rotations and translations written out in numpy, the returned states against the stack's
own forward kinematics (Newton on the leg lengths) and against the constraints recomputed
here from the design anchors (``conftest.design_anchors``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from checks import check_result, design_anchors, kinematic_problems, sp_legs

from assembler_pin import HelperArmOptions, initial_condition, stack_forward_kinematics
from assembler_pin.cli import main
from assembler_pin.exceptions import PoseError
from assembler_pin.helper_arm import (
    HelperArm,
    cluster_limits,
    height_range,
    helper_arm_urdf,
    perturbed_plates,
    repair_stack,
)
from assembler_pin.helper_arm.initial import CHEAP_SCAN
from assembler_pin.kinematics import PlateArrays, leg_state


# ---------------------------------------------------------------------- independent references
def rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def homogeneous(R: np.ndarray | None = None, p=(0.0, 0.0, 0.0)) -> np.ndarray:
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    T[:3, 3] = p
    return T


def arm_fk_numpy(q: np.ndarray, d: float) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Plates 0..n (4x4) and cluster points of the helper arm: T(d/2) [Rx Ry Rz T(d/2)] ..."""
    n = len(q) // 3
    half = homogeneous(p=(0.0, 0.0, d / 2))
    T = np.eye(4)
    plates, clusters = [T.copy()], []
    for j in range(n):
        T = T @ half @ homogeneous(rot_x(q[3 * j]) @ rot_y(q[3 * j + 1]) @ rot_z(q[3 * j + 2]))
        clusters.append(T[:3, 3].copy())
        T = T @ half
        plates.append(T.copy())
    return plates, clusters


def sp_valid_about_mid(cfg, R: np.ndarray, d: float) -> bool:
    """An SP tilted by R about its mid-height point at height d is valid (all platforms)."""
    half = np.array([0.0, 0.0, d / 2])
    p = half + R @ half
    leg = cfg.leg
    for j in range(cfg.platforms):
        L, db, dt, rise = sp_legs(cfg, j, np.eye(3), np.zeros(3), R, p)
        ok = (
            L.min() >= leg.min_length
            and L.max() <= leg.max_length
            and max(db.max(), dt.max()) <= leg.max_deflection
            and rise.min() > 0
        )
        if not ok:
            return False
    return True


# ---------------------------------------------------------------------- the model
def test_urdf_loads_with_3n_joints_and_derived_limits(am):
    cfg = am.config
    model = pin.buildModelFromXML(helper_arm_urdf(cfg))
    assert model.nq == model.nv == 3 * am.n
    names = [model.names[i] for i in range(1, model.njoints)]
    assert names == [f"sp{j}_r{a}" for j in range(am.n) for a in "xyz"]
    tilt, twist = cluster_limits(cfg, cfg.home_height)
    expected = np.tile([tilt, tilt, twist], am.n)
    np.testing.assert_allclose(model.upperPositionLimit, expected, rtol=0, atol=1e-14)
    np.testing.assert_allclose(model.lowerPositionLimit, -expected, rtol=0, atol=1e-14)
    # the repository file is this model
    repo = pin.buildModelFromUrdf(str(Path(__file__).parents[2] / "urdf" / "helper_arm.urdf"))
    np.testing.assert_allclose(repo.upperPositionLimit, expected, atol=1e-14)


def test_limits_are_the_largest_valid_tilt_and_twist(am):
    """Independently: at the limits every tilt axis (and both twists) is valid; slightly past
    them some axis breaks a leg constraint."""
    cfg, d = am.config, am.config.home_height
    tilt, twist = cluster_limits(cfg, d)
    assert 0.3 < tilt < 1.0 and 0.5 < twist < 1.5  # about 34.5 and 63 degrees
    phis = np.deg2rad(np.arange(24) * 15.0)
    axes = [np.array([np.cos(f), np.sin(f), 0.0]) for f in phis]
    assert all(sp_valid_about_mid(cfg, pin.exp3(tilt * (1 - 1e-6) * a), d) for a in axes)
    assert not all(sp_valid_about_mid(cfg, pin.exp3(tilt * (1 + 1e-6) * a), d) for a in axes)
    z = np.array([0.0, 0.0, 1.0])
    assert sp_valid_about_mid(cfg, pin.exp3(twist * (1 - 1e-6) * z), d)
    assert sp_valid_about_mid(cfg, pin.exp3(-twist * (1 - 1e-6) * z), d)
    assert not (
        sp_valid_about_mid(cfg, pin.exp3(twist * (1 + 1e-6) * z), d)
        and sp_valid_about_mid(cfg, pin.exp3(-twist * (1 + 1e-6) * z), d)
    )


def test_height_range_is_where_a_level_platform_stands(am):
    cfg = am.config
    lo, hi = height_range(cfg)
    for h, ok in ((lo * (1 + 1e-6), True), (hi * (1 - 1e-6), True), (lo * 0.999, False), (hi * 1.001, False)):
        assert sp_valid_about_mid(cfg, np.eye(3), h) is ok
    # the stroke alone bounds it: sqrt(L^2 - chord^2) at the stroke ends, chord from the anchors
    bottom, top = design_anchors(cfg, 0)
    chord = np.linalg.norm(top[0] - bottom[0])
    assert lo >= np.sqrt(cfg.leg.min_length**2 - chord**2) - 1e-9
    assert hi <= np.sqrt(cfg.leg.max_length**2 - chord**2) + 1e-9


@pytest.mark.parametrize("d", [None, 0.27])
def test_arm_fk_matches_product_of_rotations(am, d):
    arm = HelperArm(am.config, d)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = rng.uniform(arm.lower, arm.upper)
        plates, points = arm.forward(q)
        ref_plates, ref_clusters = arm_fk_numpy(q, arm.link_length)
        for M, T in zip(plates, ref_plates, strict=True):
            np.testing.assert_allclose(M.homogeneous, T, atol=1e-12)
        assert points.shape == (am.n + 2, 3)
        np.testing.assert_allclose(points[1:-1], ref_clusters, atol=1e-12)
        np.testing.assert_allclose(points[0], 0.0, atol=1e-15)
        np.testing.assert_allclose(points[-1], ref_plates[-1][:3, 3], atol=1e-12)


# ---------------------------------------------------------------------- initial condition
def test_home_goal_is_the_home_pose(am):
    result = initial_condition(am, am.home[-1].homogeneous)
    check_result(am, result)
    assert result.attempts == 1 and result.link_length == pytest.approx(am.config.home_height)
    np.testing.assert_allclose(result.leg_lengths, am.config.leg.mid_length, atol=1e-9)


def test_plates_sit_midway_between_clusters(am):
    goal = pin.SE3(pin.exp3(np.array([0.2, -0.3, 0.4])), np.array([0.15, 0.1, 0.88]))
    result = initial_condition(am, goal)
    check_result(am, result)
    pts, pa, d = result.arm_points, result.state.plates, result.link_length
    for k in range(1, am.n):  # plate k halfway between clusters k-1 and k, link along its z
        np.testing.assert_allclose(pa.p[k], 0.5 * (pts[k] + pts[k + 1]), atol=1e-9)
        np.testing.assert_allclose(pts[k + 1] - pa.p[k], 0.5 * d * pa.R[k][:, 2], atol=1e-9)
    np.testing.assert_allclose(pts[-1], goal.translation, atol=1e-9)
    np.testing.assert_allclose(pts[-1] - pts[-2], 0.5 * d * goal.rotation[:, 2], atol=1e-9)
    assert not result.repaired


def test_d_scan_finds_a_goal_that_needs_another_link_length(am):
    """The paper's scan with d fixed at each scan value (and no repair): d0 first, then the
    grid d* + k s around d* = |p_goal| / n."""
    d0 = am.config.home_height
    goal = pin.SE3(np.eye(3), np.array([0.50, 0.0, 0.80]))  # beyond the home-height arm
    fixed = HelperArmOptions(free_link_length=False, repair_starts=0)
    result = initial_condition(am, goal, fixed)
    check_result(am, result)
    assert result.attempts > 1 and result.link_length != pytest.approx(d0) and not result.repaired
    k = (result.link_length - np.linalg.norm(goal.translation) / am.n) / 0.01
    assert k == pytest.approx(round(k), abs=1e-9)  # on the scan grid d* + k s
    # with a recursion limit of one the same goal fails, with the reason
    short = initial_condition(am, goal, HelperArmOptions(max_attempts=1, free_link_length=False, repair_starts=0))
    assert not short.success and short.attempts == 1 and "1 attempt" in short.message
    # with d a variable of the arm IK (the default) the first attempt finds its own d
    free = initial_condition(am, goal)
    check_result(am, free)
    assert free.attempts == 1 and not free.repaired
    assert height_range(am.config)[0] < free.link_length < height_range(am.config)[1]


def test_arm_scales_with_link_length(am):
    """The arm of one d gives the arm of any other d by scaling positions (used by the IK)."""
    arm, other = HelperArm(am.config), HelperArm(am.config, 0.27)
    q = np.random.default_rng(5).uniform(0.5 * arm.lower, 0.5 * arm.upper)
    for A, B in zip(arm.forward(q, link_length=0.27)[0], other.forward(q)[0], strict=True):
        np.testing.assert_allclose(A.homogeneous, B.homogeneous, atol=1e-12)
    np.testing.assert_allclose(arm.forward(q, link_length=0.27)[1], other.forward(q)[1], atol=1e-12)
    np.testing.assert_allclose(arm.stack_violation(q, 0.0, 0.27), other.stack_violation(q, 0.0), atol=1e-15)


def leg_state_problems(am, result) -> list[str]:
    """The kinematic constraints recomputed with ``leg_state`` and the configuration's limits."""
    legs = leg_state(am, result.state.plates)
    lim = am.config.leg
    out = []
    if not np.allclose(legs.lengths, result.leg_lengths, atol=1e-12, rtol=0):
        out.append("lengths differ from leg_state")
    if legs.lengths.min() < lim.min_length or legs.lengths.max() > lim.max_length:
        out.append(f"stroke {legs.lengths.min():.4f}..{legs.lengths.max():.4f}")
    if legs.deflection.max() > lim.max_deflection:
        out.append(f"deflection {np.rad2deg(legs.deflection.max()):.2f} deg")
    if legs.rise.min() <= 0.0:
        out.append(f"rise {legs.rise.min():.4g}")
    return out


@pytest.mark.parametrize("z", [0.62, 0.7, 0.9, 1.0, 1.2])
def test_straight_up_goals(am, z):
    """A level EE straight above the base: the straight arm of d = z/n (the old fixed-d grid
    missed these: a straight arm cannot change its length by bending)."""
    goal = pin.SE3(np.eye(3), np.array([0.0, 0.0, z]))
    result = initial_condition(am, goal)
    check_result(am, result)
    assert leg_state_problems(am, result) == []
    assert not result.repaired and result.attempts == 1
    assert result.link_length == pytest.approx(z / am.n, abs=1e-9)
    np.testing.assert_allclose(result.state.plates.p[:, :2], 0.0, atol=1e-4)  # (nearly) a straight stack


@pytest.mark.parametrize(
    "xyz",
    [
        (0.2, 0.0, 0.8),
        (0.3, 0.0, 0.7),
        (0.4, 0.0, 0.8),
        (0.2, 0.0, 0.7),
        (0.4, 0.0, 0.9),
        (0.3999999999999999, 0.0, 0.9),
    ],
)
def test_level_ee_offsets(am, xyz):
    """Level EE moved sideways (formerly near misses of the d grid, and a goal 1 ulp from a
    solved one that failed): the arm's pose, or, when the first CHEAP_SCAN arm solves missed,
    the cheap repair that comes before the rest of the scan."""
    goal = pin.SE3(np.eye(3), np.array(xyz))
    result = initial_condition(am, goal)
    check_result(am, result)
    assert leg_state_problems(am, result) == []
    assert not result.repaired or result.attempts == CHEAP_SCAN


@pytest.mark.parametrize("xyz", [(0.3, 0.0, 0.6), (0.4, 0.0, 0.5)])
def test_low_goals_are_repaired_on_the_stack(am, xyz):
    """Low goals need SPs sheared sideways, which the arm (tilts about mid-height points at one
    height) cannot do: the arm's closest pose, or the even screw pose, is repaired."""
    goal = pin.SE3(np.eye(3), np.array(xyz))
    result = initial_condition(am, goal)
    check_result(am, result)
    assert leg_state_problems(am, result) == []
    assert result.repaired and "repaired" in result.message
    # the result says where the repair started: an arm pose (with its d and q) or a screw pose
    assert (result.link_length is None) == (result.arm_q is None)
    assert ("even screw pose" in result.message) == (result.link_length is None)
    assert not initial_condition(am, goal, HelperArmOptions(repair_starts=0)).success


@pytest.mark.parametrize("xyz", [(0.3, 0.0, 0.6), (0.3, 0.0, 0.5)])
def test_low_goal_is_repaired_before_the_rest_of_the_scan(am, xyz):
    """The tail of the scan: a low goal the arm cannot reach is repaired after CHEAP_SCAN arm
    solves, not after all max_attempts of them (formerly 15 arm solves, then the repair).
    At z = 0.5 m neither the arm's closest pose nor the even screw pose repairs: a perturbed
    copy of the screw pose does, and it too is tried before the rest of the scan."""
    result = initial_condition(am, pin.SE3(np.eye(3), np.array(xyz)))
    check_result(am, result)
    assert leg_state_problems(am, result) == []
    assert result.repaired and result.attempts == CHEAP_SCAN < HelperArmOptions().max_attempts
    assert result.link_length is None or xyz[2] > 0.5  # z = 0.5 m: from a screw pose


def test_repair_jacobian_is_the_derivative_of_the_hinge(am):
    """The repair's analytic Jacobian (leg derivatives through Ad(T)·Jexp6) against central
    differences of the leg-limit hinge it differentiates, at a pose with violated legs."""
    from assembler_pin.helper_arm.repair import _hinge_jacobian, _leg_hinge

    start = perturbed_plates(list(am.home), 1, seed=3)[0]
    x = np.random.default_rng(0).uniform(-0.02, 0.02, 6 * (am.n - 1))

    def plates(x):
        moved = [m.copy() for m in start]
        for k in range(1, am.n):
            moved[k] = start[k] * pin.exp6(x[6 * (k - 1) : 6 * k])
        return PlateArrays.from_se3(moved)

    margin = 0.02  # tightened bounds: some legs past them
    value = _leg_hinge(am, plates(x), margin)
    active = value > 1e-4
    assert active.sum() >= 3
    h = 1e-6
    numeric = np.array(
        [
            (_leg_hinge(am, plates(x + h * e), margin) - _leg_hinge(am, plates(x - h * e), margin)) / (2 * h)
            for e in np.eye(x.size)
        ]
    ).T
    analytic = _hinge_jacobian(am, plates(x), x, margin)
    np.testing.assert_allclose(analytic[active], numeric[active], atol=1e-7)
    assert np.all(analytic[value == 0.0] == 0.0)
    repaired, violation = repair_stack(am, start)
    assert violation == 0.0 and kinematic_problems(am.config, repaired) == []


def test_penalty_jacobian_is_the_forward_difference_of_each_joint(am):
    """The IK penalty's Jacobian (every cluster's three joints and d moved in one batched
    call) equals the forward difference of :meth:`HelperArm.stack_violation` taken joint by
    joint and for d, one pose at a time, at a pose with violated legs."""
    arm = HelperArm(am.config)
    q = np.random.default_rng(1).choice([-1.0, 1.0], arm.nq) * arm.upper
    d, margin, step = 1.05 * arm.link_length, 1e-5, 1e-7
    value = arm.stack_violation(q, margin, d)
    assert (value > 0).sum() >= 3
    jac = arm._penalty_jacobian(q, value, margin, step=step, link_length=d, with_d=True)
    columns = []
    for c in range(q.size):
        moved = q.copy()
        moved[c] += step
        columns.append(((arm.stack_violation(moved, margin, d) - value) / step).ravel())
    columns.append(((arm.stack_violation(q, margin, d + step) - value) / step).ravel())
    np.testing.assert_allclose(jac, np.array(columns).T, rtol=0, atol=1e-9)
    assert np.abs(jac).max() > 1.0


def test_random_reachable_goals_mostly_succeed(am):
    """EE poses of random leg lengths over the middle 80 % of the stroke (stack FK, seed 0).

    Measured: 40/40 here, 200/200 over 200 goals and over the full stroke (with d fixed at
    the scan values and no repair: 39/40, 197/200 and 189/200)."""
    rng = np.random.default_rng(0)
    leg = am.config.leg
    goals = []
    while len(goals) < 40:
        fk = stack_forward_kinematics(am, rng.uniform(leg.min_length + 0.02, leg.max_length - 0.02, (am.n, 6)))
        if fk.success:
            goals.append(fk.plates.se3(am.n))
    solved = 0
    for goal in goals:
        result = initial_condition(am, goal)
        if result.success:
            solved += 1
            check_result(am, result)
    assert solved == len(goals)


def test_goals_beyond_any_span_are_answered_before_the_arm(am):
    # one platform spans at most |b| + max_length + |t| (both anchors on the node circle)
    cfg = am.config
    span = cfg.platforms * (2 * cfg.plate.node_radius + cfg.leg.max_length)
    for x in (1.01 * span, 5e3):
        result = initial_condition(am, pin.SE3(np.eye(3), np.array([x, 0.0, 0.0])))
        assert not result.success and result.attempts == 0
        assert "out of reach" in result.message and "farther than the stack can span" in result.message
    with pytest.raises(PoseError, match=r"pose\.translation"):  # beyond any pose: refused, not answered
        initial_condition(am, pin.SE3(np.eye(3), np.array([1e200, 0.0, 0.0])))


@pytest.mark.parametrize(
    "xyz, rotvec, reason",
    [
        ((0.0, 0.0, -0.5), (np.pi, 0.0, 0.0), "no valid initial condition"),  # below the base
        ((-0.1, 0.0, 0.3), (0.0, 0.0, 0.0), "no valid initial condition"),  # inside the stack's own body
    ],
)
def test_unreachable_goals_are_answers(am, xyz, rotvec, reason):
    goal = pin.SE3(pin.exp3(np.array(rotvec)), np.array(xyz))
    result = initial_condition(am, goal, HelperArmOptions(max_attempts=5))
    assert not result.success
    assert reason in result.message and result.link_length is None
    assert 1 <= result.attempts <= 5
    np.testing.assert_allclose(result.state.plates.as_matrices(), np.array([m.homogeneous for m in am.home]))
    np.testing.assert_allclose(result.leg_lengths, am.config.leg.mid_length, atol=1e-12)
    assert {"ee_position"} <= {v.kind for v in result.state.violations}


@pytest.mark.parametrize(
    "goal",
    [
        np.full((4, 4), np.nan),
        np.diag([2.0, 1.0, 1.0, 1.0]),  # not a rotation
        np.eye(3),  # wrong shape
    ],
)
def test_malformed_goals_raise(am, goal):
    with pytest.raises(PoseError):
        initial_condition(am, goal)


def test_options_are_checked():
    with pytest.raises(ValueError):
        HelperArmOptions(d_step=0.0)
    with pytest.raises(ValueError):
        HelperArmOptions(max_attempts=0)
    with pytest.raises(ValueError):
        HelperArmOptions(repair_starts=-1)


# ---------------------------------------------------------------------- CLI
def test_cli_solve_json_contract(am, capsys):
    assert main(["solve", "--goal-deg", "0.2", "0.1", "0.85", "20", "-10", "15", "--no-optimize", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert list(doc)[:4] == ["goal", "success", "message", "initial"]
    assert doc["success"] is True
    np.testing.assert_allclose(doc["goal"], [0.2, 0.1, 0.85, *np.deg2rad([20, -10, 15])], atol=1e-12)
    plates = np.array(doc["initial"]["plates"])
    goal = pin.SE3(pin.exp3(np.deg2rad([20.0, -10.0, 15.0])), np.array([0.2, 0.1, 0.85]))
    np.testing.assert_allclose(plates[-1], goal.homogeneous, atol=1e-9)
    fk = stack_forward_kinematics(am, np.array(doc["initial"]["leg_lengths"]))
    np.testing.assert_allclose(fk.plates.as_matrices(), plates, atol=1e-9)


def test_cli_solve_unreachable_and_errors(capsys):
    args = ["solve", "--goal", "3", "0", "0.8", "0", "0", "0", "--no-optimize", "--json", "--max-attempts", "2"]
    assert main(args) == 1  # answered: not possible
    doc = json.loads(capsys.readouterr().out)
    assert doc["success"] is False and "reach" in doc["message"]
    assert main(["solve", "--goal", "nan", "0", "0.8", "0", "0", "0", "--no-optimize"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "NaN" in err[0]
    assert main(["solve", "--goal", "0", "0", "0.9", "0", "0", "0", "--w1", "-1"]) == 2
    assert "w1 must be a finite number >= 0" in capsys.readouterr().err
    assert main(["solve", "--no-optimize"]) == 2
    assert main(["solve", "--goal", "0", "0", "0.9", "0", "0", "0", "--no-optimize", "--d-step", "-1"]) == 2


def test_cli_solve_table(capsys):
    assert main(["solve", "--goal", "0", "0", "0.95", "0", "0", "0.1", "--no-optimize"]) == 0
    out = capsys.readouterr().out
    assert "valid" in out and "max |F|" in out and "SP3 F [N]" in out  # platforms SP0..SP3


def test_the_helper_arms_belong_to_the_caller_not_to_the_model(am):
    """The arms are kept off the stack model: a caller's cache is the one filled, the default
    is one per thread and configuration content (payload aside), never the model's."""
    import dataclasses
    import threading

    from assembler_pin.helper_arm import ArmCache, arm_cache

    mine = ArmCache(am.config)
    res = initial_condition(am, am.home[-1], arms=mine)
    assert res.success and len(mine) >= 1
    assert not hasattr(am, "helper_arms")
    same = dataclasses.replace(am.config)  # equal content, another object
    heavier = dataclasses.replace(am.config, payload=dataclasses.replace(am.config.payload, mass=7.0))
    assert arm_cache(same) is arm_cache(am) is arm_cache(heavier)
    assert arm_cache(dataclasses.replace(am.config, platforms=am.n + 1)) is not arm_cache(am)
    other: list[ArmCache] = []
    worker = threading.Thread(target=lambda: other.append(arm_cache(am)))
    worker.start()
    worker.join()
    assert other[0] is not arm_cache(am)


def test_the_cluster_limits_use_the_one_set_of_leg_measures():
    from assembler_pin.helper_arm import limits
    from assembler_pin.kinematics import legs

    assert limits.relative_leg_measures is legs.relative_leg_measures


def test_an_arm_cache_stays_bounded_and_a_rebuilt_arm_gives_the_same_answer(am, monkeypatch):
    """Goals far apart start the scan at link lengths of their own: the cache keeps the
    KEPT_ARMS most recent arms, and a goal solved again once its arms were dropped gets the
    same internal pose, bit for bit (an arm holds no state between solves)."""
    from assembler_pin.helper_arm import cache as cache_module

    monkeypatch.setattr(cache_module, "KEPT_ARMS", 3)
    arms = cache_module.ArmCache(am.config)
    home = am.home[-1]
    goal = pin.SE3(home.rotation @ pin.exp3(np.array([0.0, 0.2, 0.0])), home.translation + np.array([0.1, 0.0, -0.05]))
    first = initial_condition(am, goal, arms=arms)
    assert first.success
    for d in np.linspace(0.1, 0.3, 10):  # other goals' link lengths push the goal's arms out
        arms.get(d)
    assert len(arms) == 3 and arms.get(0.3) is arms.get(0.3)
    again = initial_condition(am, goal, arms=arms)
    assert again.state.plates.p.tobytes() == first.state.plates.p.tobytes()
    assert again.state.plates.R.tobytes() == first.state.plates.R.tobytes()
