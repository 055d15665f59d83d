"""The optimizer's clearance rows: their Jacobian against central differences, a solve that
keeps its distance from a strut (checked by the tests' own distances) and a goal no pose
reaches without a collision."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from checks import brute_segment_distance, design_anchors

import assembler_pin as ap
from assembler_pin.collision import Scene, read_scene, scene_from_dict
from assembler_pin.common.messages import CAUSES
from assembler_pin.config.options import OptimizeOptions
from assembler_pin.optimize.certificate import optimality
from assembler_pin.optimize.problem import Problem
from assembler_pin.optimize.rows import ClearanceRows
from assembler_pin.scenarios import SCENARIOS
from assembler_pin.solver.pipeline import solve

TRUSS_BAY = Path(__file__).resolve().parents[2] / "examples" / "truss_bay.yaml"


@pytest.fixture(scope="module")
def scene():
    return read_scene(TRUSS_BAY)


@pytest.fixture(scope="module")
def solved(am, scene):
    goal = SCENARIOS["translation"].goal
    return solve(am, goal), solve(am, goal, scene=scene)


def _capsules(cfg, plates: np.ndarray) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
    """Every leg's motor and shaft as (name, start, vector, radius), world frame, from the
    design's anchors (not the package's leg geometry)."""
    out = []
    for j in range(cfg.platforms):
        bottom, top = design_anchors(cfg, j)
        for i in range(6):
            b = plates[j][:3, :3] @ bottom[i] + plates[j][:3, 3]
            t = plates[j + 1][:3, :3] @ top[i] + plates[j + 1][:3, 3]
            u = (t - b) / np.linalg.norm(t - b)
            m = b + cfg.leg.motor_length * u
            out.append((f"SP{j} leg {i} motor", b, m - b, cfg.leg.motor_radius))
            out.append((f"SP{j} leg {i} shaft", m, t - m, cfg.leg.shaft_radius))
    return out


def _distance_to_cylinders(cfg, plates: np.ndarray, scene: Scene) -> tuple[float, str]:
    """The smallest distance of a leg capsule to a cylinder of the scene, through the segment
    distance of the leg's axis to the cylinder's axis minus both radii (exact where the closest
    point on the cylinder's axis lies inside its length, which the test checks)."""
    best = (np.inf, "")
    for o in scene.obstacles:
        if o.kind != "cylinder":
            continue
        radius, length = o.size
        axis = o.pose.rotation[:, 2]
        start = o.pose.translation - 0.5 * length * axis
        for name, p, d, r in _capsules(cfg, plates):
            dist = brute_segment_distance(p, d, start, length * axis) - r - radius
            best = min(best, (dist, f"{name} / {o.name}"))
    return best


def test_clearance_rows_jacobian_against_central_differences(am, scene, solved):
    state = solved[1].best
    opts = OptimizeOptions()
    problem = Problem(am, state.plates, state.plates.se3(am.n), opts, start_feasible=True, scene=scene)
    rows = problem.clearance_rows
    assert isinstance(rows, ClearanceRows)
    rng = np.random.default_rng(7)
    x = 1e-3 * rng.standard_normal(problem.nx_pose)
    p = problem.point(x)
    jac = rows.jacobian(p, problem.derivatives(x))
    base = rows.values(p)
    band = np.flatnonzero(base < ClearanceRows.BAND - 1e-3)
    assert len(band) >= 5  # the strut and the stack's own near pairs
    h = 1e-6
    numeric = np.zeros((len(band), problem.nx_pose))
    for k in range(problem.nx_pose):
        e = np.zeros(problem.nx_pose)
        e[k] = h
        plus = rows.values(problem.point(x + e))[band]
        minus = rows.values(problem.point(x - e))[band]
        numeric[:, k] = (plus - minus) / (2 * h)
    err = np.abs(jac[band] - numeric).max(axis=1)
    assert err.max() < 2e-4, err  # coal's pairs to ~1e-4, the closed forms far better
    held = base >= ClearanceRows.BAND  # beyond the band: constant rows, zero gradients
    assert held.sum() > 30 and not jac[held].any()


def test_far_pairs_share_one_row_that_guards_them_all(am, scene, solved):
    """The pairs far at the start share the last row: the smallest of their values, with the
    nearest one's gradient; the own rows are the full rows of their pairs. A far pair brought
    into the band (the plates moved towards the upper strut) moves the last row, held to
    central differences."""
    from assembler_pin.collision import clearance

    state = solved[1].best
    problem = Problem(am, state.plates, state.plates.se3(am.n), OptimizeOptions(), start_feasible=True, scene=scene)
    rows = problem.clearance_rows
    full = ClearanceRows(am, scene, rows.margin)  # every pair its own row
    assert rows.own is not None and len(rows.own) + len(rows.rest) == len(clearance(am, state.plates, scene).distances)
    assert 10 < len(rows.own) < 0.3 * (len(rows.own) + len(rows.rest))
    x = np.zeros(problem.nx_pose)
    x[2 : problem.nx_pose : 6] = 0.35  # every free plate 0.35 m up the chart's z: near the upper strut
    p, d = problem.point(x), problem.derivatives(x)
    values, jac = rows.values(p), rows.jacobian(p, d)
    every, every_jac = full.values(p), full.jacobian(p, d)
    assert len(values) == len(rows.own) + 1
    assert np.array_equal(values[:-1], every[rows.own]) and np.allclose(jac[:-1], every_jac[rows.own], atol=1e-12)
    last = int(rows.rest[np.argmin(every[rows.rest])])
    assert values[-1] == every[last] and np.allclose(jac[-1], every_jac[last], atol=1e-12)
    if values[-1] < ClearanceRows.BAND - 1e-3:  # a far pair in the band: its gradient by central differences
        h = 1e-6
        numeric = np.array(
            [
                (rows.values(problem.point(x + h * e))[-1] - rows.values(problem.point(x - h * e))[-1]) / (2 * h)
                for e in np.eye(problem.nx_pose)
            ]
        )
        assert np.abs(jac[-1] - numeric).max() < 2e-4


def test_solve_keeps_its_distance_from_the_strut(am, scene, solved):
    plain, kept = solved
    cfg = am.config
    # without the scene the optimum passes through the lower strut (the tests' own distances)
    through, where = _distance_to_cylinders(cfg, plain.best.plates.as_matrices(), scene)
    assert through < -0.01 and "lower strut" in where
    assert kept.success and kept.optimal and kept.optimized is not None
    clear, where = _distance_to_cylinders(cfg, kept.optimized.plates.as_matrices(), scene)
    assert clear >= cfg.clearance - 1e-9, (clear, where)
    assert kept.optimized.clearance.min_distance >= cfg.clearance
    assert kept.optimized.feasible and not kept.optimized.violations
    # the least force that keeps its distance: a little more than the free optimum
    assert plain.best.max_abs_force < kept.optimized.max_abs_force < 1.1 * plain.best.max_abs_force
    # the certificate sees the clearance rows: optimal with them, and with the free problem's
    # rows alone the state is not the optimum (the strut's row is what holds it)
    goal = SCENARIOS["translation"].goal
    assert optimality(am, kept.optimized, goal, OptimizeOptions(), scene=scene).optimal
    assert not optimality(am, kept.optimized, goal, OptimizeOptions()).optimal


def test_a_goal_inside_an_obstacle_is_a_collision(am):
    goal = SCENARIOS["translation"].goal
    ball = scene_from_dict({"obstacles": [{"sphere": {"radius": 0.05, "center": goal.translation.tolist()}}]})
    result = solve(am, goal, scene=ball)
    assert not result.success
    assert result.message.startswith("collision:"), result.message
    assert "collision" in CAUSES
    assert "sphere 0" in result.message and " m apart" in result.message


def test_the_helper_arm_pose_alone_is_checked_in_the_scene(am):
    goal = pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.9]))
    ball = scene_from_dict({"obstacles": [{"sphere": {"radius": 0.05, "center": [0.0, 0.0, 0.9]}}]})
    result = solve(am, goal, optimize=False, scene=ball)
    assert not result.success and result.message.startswith("collision:")
    assert solve(am, goal, optimize=False).success


def test_an_ipopt_run_with_a_scene_runs_slsqp(am, scene):
    goal = SCENARIOS["translation"].goal
    start = ap.AssemblerModel.from_config().home
    start[am.n] = goal
    result = ap.optimize_internal_poses(am, start, goal, OptimizeOptions(method="ipopt"), scene=scene)
    assert result.method.startswith("slsqp")
