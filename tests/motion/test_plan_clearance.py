"""A plan past a strut keeps its clearance at and between its samples, checked by the tests'
own distances (sampled plate surfaces, leg capsules) at stack FK of the interpolated legs."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from checks import strut_distance

import assembler_pin as ap
from assembler_pin.collision import scene_from_dict
from assembler_pin.kinematics import stack_forward_kinematics, taa_to_se3
from assembler_pin.motion import EEPath
from assembler_pin.motion.planner import plan_path

#: A strut under plate 1's rim: the free plan from home to GOAL passes 0.7 mm into it.
STRUT = {"name": "strut", "cylinder": {"radius": 0.015, "length": 0.6, "pose": [0.19, 0, 0.3, np.pi / 2, 0, 0]}}
GOAL = [0.08, 0.0, 0.94, 0.0, 0.0, 0.0]


def _strut_distance(cfg, plates: np.ndarray) -> float:
    length = STRUT["cylinder"]["length"]
    start = np.array([0.19, -0.5 * length, 0.3])
    return strut_distance(cfg, plates, start, np.array([0.0, length, 0.0]), STRUT["cylinder"]["radius"])


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
    """Each pair's bound from the two ends, with each body's move measured here from the
    joint centres and the plates, is at most that pair's distance at stack-FK poses between."""
    from assembler_pin.collision import clearance
    from assembler_pin.collision.sweep import body_moves, swept_bound

    _, kept = plans
    scene = scene_from_dict({"obstacles": [STRUT]})
    cfg = am.config
    rho = np.hypot(cfg.plate.radius, 0.5 * cfg.plate.thickness)
    tight = np.inf
    for a, b in list(zip(kept.states[:-1], kept.states[1:], strict=True))[::3]:
        moves = body_moves(am, a.plates, b.plates)
        ends = [np.concatenate([d.reshape(-1, 3) for d in ap.kinematics.leg_vectors(am, s.plates)[:2]]) for s in (a, b)]
        joint_move = np.linalg.norm(ends[0] - ends[1], axis=1)  # bottoms then tops
        assert np.all(moves[: 6 * am.n] >= np.maximum(joint_move[: 6 * am.n], joint_move[6 * am.n :]) - 1e-15)
        turn = [np.linalg.norm(pin.log3(a.plates.R[k].T @ b.plates.R[k])) for k in range(am.n + 1)]
        want = np.linalg.norm(a.plates.p - b.plates.p, axis=1) + rho * np.array(turn)
        assert np.allclose(moves[6 * am.n :], want, atol=1e-12)
        bound = swept_bound(a.clearance, b.clearance, moves)
        assert bound <= min(a.clearance.min_distance, b.clearance.min_distance)
        for t in np.linspace(0.1, 0.9, 5):
            fk = stack_forward_kinematics(
                am, (1 - t) * a.leg_lengths + t * b.leg_lengths, base=a.plates.se3(0), guess=a.plates.as_se3()
            )
            between = clearance(am, fk.plates, scene)
            assert between.min_distance >= bound - 1e-12
            tight = min(tight, between.min_distance - bound)
    assert tight < 5e-3  # the bound is not vacuous
