"""The planner on easy steps far inside the workspace: a vertical lift, a short first
segment of a waypoint path, a path from an optimized start. Every sample is held to the
design-based checks of ``tests/checks.py`` (kinematics and free-body forces) and the motion
step between consecutive samples is measured on leg lengths computed here from the plates.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from checks import design_problems, sp_legs

from assembler_pin.kinematics import plate_arrays
from assembler_pin.motion import EEPath, PlanOptions, plan_path
from assembler_pin.motion.guess import spread_start


def _lengths(cfg, plates) -> np.ndarray:
    """(n, 6) leg lengths [m] of plate poses, from the design anchors."""
    return np.array(
        [sp_legs(cfg, j, plates.R[j], plates.p[j], plates.R[j + 1], plates.p[j + 1])[0] for j in range(cfg.platforms)]
    )


def _assert_valid_samples(am, plan, opts: PlanOptions) -> None:
    """Every held sample meets every constraint on the path, and no leg moves more than the
    motion step between consecutive samples."""
    cfg = am.config
    assert len(plan.states) == len(plan.parameters) >= 2
    assert np.all(np.diff(plan.parameters) > 0)
    for u, state in zip(plan.parameters, plan.states, strict=True):
        assert design_problems(cfg, state.plates, goal=plan.path.at(u), tol=1e-9) == [], u
    lengths = np.array([_lengths(cfg, s.plates) for s in plan.states])
    np.testing.assert_allclose(lengths, plan.lengths, atol=1e-9)
    assert np.abs(np.diff(lengths, axis=0)).max() <= opts.max_leg_step + 1e-9


def _pose(x: float, y: float, z: float) -> pin.SE3:
    return pin.SE3(np.eye(3), np.array([x, y, z]))


def test_a_vertical_lift_plans_past_a_quarter_metre(am):
    """Straight up from home towards 1.6 m (beyond reach): the plan holds a valid prefix
    past 25 cm of lift and stops at a limit of the stroke, not at an easy step."""
    opts = PlanOptions(position_step=0.02, max_refinements=1)
    path = EEPath.between(am.home[-1], _pose(0.0, 0.0, 1.6))
    plan = plan_path(am, path, start=am.home, options=opts)
    _assert_valid_samples(am, plan, opts)
    assert plan.parameters[-1] >= 0.4, plan.reason
    lift = plan.states[-1].plates.p[am.n][2] - am.home[-1].translation[2]
    assert lift > 0.25
    assert not plan.success and "stroke" in plan.reason  # the reach limit: legs at full stroke
    # samples held without a converged optimum are named, and were checked as every other
    assert all(0 < i < len(plan.states) for i in plan.not_optimal)


def test_an_ee_step_the_motion_step_cannot_allow_is_shrunk_up_front(am):
    """A 5 cm EE step over 4 platforms needs more than the 10 mm motion step of a leg: the
    step is shrunk before planning and the 10 cm lift plans to the end."""
    opts = PlanOptions(position_step=0.05, max_refinements=1)
    path = EEPath.between(am.home[-1], _pose(0.0, 0.0, am.home[-1].translation[2] + 0.10))
    plan = plan_path(am, path, start=am.home, options=opts)
    assert plan.success, plan.reason
    _assert_valid_samples(am, plan, opts)
    ee = np.array([s.plates.p[am.n] for s in plan.states])
    assert np.linalg.norm(np.diff(ee, axis=0), axis=1).max() <= 0.5 * am.n * opts.max_leg_step + 1e-9


def test_a_short_first_segment_does_not_use_up_the_halvings(am):
    """Home, 1.6 cm down to z = 0.95, then 5 cm sideways, at 5 mm steps (the re-plan of
    ``plan_trajectory``): the short segment's steps are halved on its own spacing."""
    opts = PlanOptions(position_step=0.005, rotation_step=np.radians(1.0), max_leg_step=0.005)
    path = EEPath((am.home[-1], _pose(0.0, 0.0, 0.95), _pose(0.05, 0.0, 0.95)))
    plan = plan_path(am, path, start=am.home, options=opts)
    assert plan.success, plan.reason
    _assert_valid_samples(am, plan, opts)
    assert plan.parameters[-1] == 2.0


def test_a_waypoint_path_from_an_optimized_start(am):
    """As ``plan --waypoints FILE --from 0 0 0.9 0 0 0``: the force-optimal start at
    z = 0.9, then two waypoints; the first step no longer fails."""
    opts = PlanOptions()
    path = EEPath((_pose(0.0, 0.0, 0.9), _pose(0.0, 0.0, 0.95), _pose(0.05, 0.0, 0.95)))
    plan = plan_path(am, path, start=None, options=opts)
    assert plan.success, plan.reason
    _assert_valid_samples(am, plan, opts)


def test_the_shared_move_start_moves_each_plate_by_its_share(am):
    """``spread_start``: a translation d of the EE moves plate k by k/n·d, a turn θ about
    the vertical through the EE turns plate k by k/n·θ; plate 0 stays, plate n is the goal."""
    plates = plate_arrays(am, am.home)
    n, ee = am.n, am.home[-1]
    d = np.array([0.01, -0.02, 0.03])
    moved = spread_start(plates, pin.SE3(ee.rotation, ee.translation + d))
    for k in range(n + 1):
        np.testing.assert_allclose(moved.p[k] - plates.p[k], k / n * d, atol=1e-12)
        np.testing.assert_allclose(moved.R[k], plates.R[k], atol=1e-12)
    theta = 0.2
    turn = np.array([[np.cos(theta), -np.sin(theta), 0.0], [np.sin(theta), np.cos(theta), 0.0], [0.0, 0.0, 1.0]])
    turned = spread_start(plates, pin.SE3(turn @ ee.rotation, ee.translation))
    for k in range(n + 1):
        a = k / n * theta
        share = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
        np.testing.assert_allclose(turned.R[k], share @ plates.R[k], atol=1e-12)
        axis = ee.translation[:2]  # the vertical through the EE
        np.testing.assert_allclose(turned.p[k][:2] - axis, share[:2, :2] @ (plates.p[k][:2] - axis), atol=1e-12)
        assert abs(turned.p[k][2] - plates.p[k][2]) < 1e-12
    np.testing.assert_allclose(turned.p[n], ee.translation, atol=1e-12)
