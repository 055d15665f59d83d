"""A plan past a strut keeps its clearance at and between its samples, checked by the tests'
own distances (sampled plate surfaces, leg capsules) at stack FK of the interpolated legs."""

from __future__ import annotations

import numpy as np
import pytest
from checks import design_anchors

import assembler_pin as ap
from assembler_pin.collision import scene_from_dict
from assembler_pin.kinematics import stack_forward_kinematics, taa_to_se3
from assembler_pin.motion import EEPath
from assembler_pin.motion.planner import plan_path

#: A strut under plate 1's rim: the free plan from home to GOAL passes 0.7 mm into it.
STRUT = {"name": "strut", "cylinder": {"radius": 0.015, "length": 0.6, "pose": [0.19, 0, 0.3, np.pi / 2, 0, 0]}}
GOAL = [0.08, 0.0, 0.94, 0.0, 0.0, 0.0]


def _points_to_axis(points: np.ndarray, start: np.ndarray, vec: np.ndarray) -> np.ndarray:
    s = np.clip((points - start) @ vec / (vec @ vec), 0.0, 1.0)
    return np.linalg.norm(points - (start + s[:, None] * vec), axis=1)


def _strut_distance(cfg, plates: np.ndarray) -> float:
    """The smallest distance from the strut to a plate (its rims and faces sampled every
    ~1 mm) or a leg (its axis sampled every 0.5 mm, minus the capsule's radius)."""
    radius, length = STRUT["cylinder"]["radius"], STRUT["cylinder"]["length"]
    start = np.array([0.19, -0.5 * length, 0.3])
    vec = np.array([0.0, length, 0.0])
    angles = np.linspace(0.0, 2 * np.pi, 1080, endpoint=False)
    rings = np.linspace(0.0, cfg.plate.radius, 60)
    disc = np.array(
        [[r * np.cos(a), r * np.sin(a)] for r in rings for a in angles[::6]]
        + [[cfg.plate.radius * np.cos(a), cfg.plate.radius * np.sin(a)] for a in angles]
    )
    best = np.inf
    for T in plates:
        for z in (-0.5 * cfg.plate.thickness, 0.5 * cfg.plate.thickness):
            local = np.column_stack([disc, np.full(len(disc), z)])
            world = local @ T[:3, :3].T + T[:3, 3]
            best = min(best, float(_points_to_axis(world, start, vec).min()) - radius)
    for j in range(cfg.platforms):
        bottom, top = design_anchors(cfg, j)
        for i in range(6):
            b = plates[j][:3, :3] @ bottom[i] + plates[j][:3, 3]
            t = plates[j + 1][:3, :3] @ top[i] + plates[j + 1][:3, 3]
            L = np.linalg.norm(t - b)
            sigma = np.linspace(0.0, L, int(L / 5e-4) + 2)
            pts = b + sigma[:, None] * (t - b) / L
            r = np.where(sigma <= cfg.leg.motor_length, cfg.leg.motor_radius, cfg.leg.shaft_radius)
            best = min(best, float((_points_to_axis(pts, start, vec) - r).min()) - radius)
    return best


@pytest.fixture(scope="module")
def plans(am):
    path = EEPath((am.home[-1], taa_to_se3(np.array(GOAL))), "linear")
    scene = scene_from_dict({"obstacles": [STRUT]})
    return plan_path(am, path, am.home), plan_path(am, path, am.home, scene=scene)


def test_a_plan_past_a_strut_keeps_its_clearance_between_samples(am, plans):
    free, kept = plans
    cfg = am.config
    assert min(_strut_distance(cfg, s.plates.as_matrices()) for s in free.states) < 0.0  # the free plan hits it
    assert kept.success, kept.reason
    assert all(s.clearance is not None and s.clearance.min_distance >= cfg.clearance for s in kept.states)
    worst = np.inf
    for a, b in zip(kept.states[:-1], kept.states[1:], strict=True):
        guess = a.plates
        for t in np.linspace(0.0, 1.0, 9):
            fk = stack_forward_kinematics(
                am, (1 - t) * a.leg_lengths + t * b.leg_lengths, base=a.plates.se3(0), guess=guess.as_se3()
            )
            assert fk.success
            guess = fk.plates
            worst = min(worst, _strut_distance(cfg, fk.plates.as_matrices()))
    assert worst >= cfg.clearance - 2e-4, worst  # the sampled surfaces are within ~1e-4 m of the exact


def test_the_sweep_bound_holds_on_the_plan(am, plans):
    from assembler_pin.collision.sweep import body_move, swept_bound

    _, kept = plans
    for a, b in zip(kept.states[:-1], kept.states[1:], strict=True):
        move = body_move(am, a.plates, b.plates)
        assert 0.0 < move < 0.02
        assert swept_bound(a.clearance.min_distance, b.clearance.min_distance, move) <= min(
            a.clearance.min_distance, b.clearance.min_distance
        )
    assert ap.collision.sweep.swept_bound(0.01, 0.01, 0.0) == 0.01
