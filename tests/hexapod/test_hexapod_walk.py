"""The walk held to independent computations: every leg's force from the tests' own leg lengths
(``k (L − L_cmd)`` at the sample's plates), the whole machine's weight and its moment against
the feet's wrenches, the stability margin from the tests' own convex hull, the feet planted
through their stance, and the forces at lift-off and touch-down from a standing check of the
same poses with the foot on the floor and hanging."""

from __future__ import annotations

import functools

import numpy as np
import pytest

import assembler_pin as ap
from assembler_pin.exceptions import HexapodError
from assembler_pin.hexapod import machine_com, stand, walk
from assembler_pin.kinematics import PlateArrays


def _model(stacks: int = 6, **hexapod) -> ap.AssemblerModel:
    return ap.AssemblerModel.from_config({"platforms": 2, "hexapod": {"stacks": stacks, **hexapod}})


@functools.cache
def _walk(gait: str = "tripod", feet: str = "resting"):
    am = _model()
    return am, walk(am, (0.06, 0.02, 0.05), gait=gait, step=0.05, feet=feet, samples=2)


def _leg_lengths(am, plates):
    """(k, n, 6) every leg's length [m] from the plates' poses and the joints' positions."""
    geo = am.geometry
    R, p = plates[..., :3, :3], plates[..., :3, 3]
    b = p[:, :-1, None, :] + np.einsum("knab,nlb->knla", R[:, :-1], geo.bottom_in_plate)
    t = p[:, 1:, None, :] + np.einsum("knab,nlb->knla", R[:, 1:], geo.top_in_plate)
    return np.linalg.norm(t - b, axis=-1)


def _cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def _hull(points):
    """Counter-clockwise convex hull (Andrew's monotone chain)."""
    pts = sorted(map(tuple, points))
    if len(pts) < 3:
        return np.array(pts)

    def half(seq):
        out = []
        for q in seq:
            while len(out) >= 2 and _cross(np.subtract(out[-1], out[-2]), np.subtract(q, out[-2])) <= 0:
                out.pop()
            out.append(q)
        return out[:-1]

    return np.array(half(pts) + half(pts[::-1]))


def _margin(com_xy, feet_xy, radius):
    """Radius plus the signed distance to the hull of the feet (positive inside), by hand."""
    hull = _hull(feet_xy)
    if len(hull) < 3:
        a, b = hull[0], hull[-1]
        d = b - a
        t = 0.0 if not d.any() else np.clip((com_xy - a) @ d / (d @ d), 0, 1)
        return radius - np.linalg.norm(com_xy - a - t * d)
    dist, inside = np.inf, True
    for a, b in zip(hull, np.roll(hull, -1, axis=0), strict=True):
        e = b - a
        t = np.clip((com_xy - a) @ e / (e @ e), 0, 1)
        dist = min(dist, np.linalg.norm(com_xy - a - t * e))
        inside &= e[0] * (com_xy - a)[1] - e[1] * (com_xy - a)[0] >= 0
    return radius + (dist if inside else -dist)


def test_a_tripod_walk_reaches_its_goal_with_every_sample_feasible():
    am, got = _walk()
    assert got.success and got.reason is None and got.cycles == 2
    assert all(not s.violations for s in got.samples)
    times = [s.t for s in got.samples]
    assert np.all(np.diff(times) >= 0)
    end = got.samples[-1]
    start_com = ap.hexapod.configured_hexapod(am)[2]
    turn = np.array([[np.cos(0.05), -np.sin(0.05), 0], [np.sin(0.05), np.cos(0.05), 0], [0, 0, 1]])
    np.testing.assert_allclose(end.body_pose[:3], turn @ start_com + [0.06, 0.02, 0.0], atol=1e-12)
    np.testing.assert_allclose(end.body_pose[3:], [0, 0, 0.05], atol=1e-12)
    start_feet = ap.hexapod.ring_stacks(am, 6, am.config.hexapod.radius)
    for i, s in enumerate(start_feet):
        np.testing.assert_allclose(end.feet[i, :3, 3], turn @ s.p[0] + [0.06, 0.02, 0.0], atol=1e-12)
    # no foot travels more than a step per cycle
    for i in range(6):
        lands = [s.feet[i, :3, 3] for s in got.samples if s.phase == "load"]
        assert max(np.linalg.norm(lands[j] - lands[j - 1]) for j in range(1, len(lands))) <= 0.05 + 1e-12


@pytest.mark.parametrize("gait", ["tripod", "wave"])
def test_stance_feet_stay_planted_and_swing_feet_lift(gait):
    _, got = _walk(gait)
    assert got.success
    for i in range(6):
        for a, b in zip(got.samples, got.samples[1:], strict=False):
            if a.stance[i] and b.stance[i]:
                assert np.abs(b.feet[i] - a.feet[i]).max() <= 1e-9, (i, a.phase, b.phase)
                assert np.abs(b.plates[i, 0] - b.feet[i]).max() <= 1e-9
        swings = [s for s in got.samples if not s.stance[i]]
        assert swings and max(s.feet[i, 2, 3] for s in swings) > 0.02
    stances = {tuple(s.stance) for s in got.samples}
    least = 3 if gait == "tripod" else 5
    assert min(sum(s) for s in stances) == least


@pytest.mark.parametrize("feet", ["resting", "welded"])
def test_every_force_is_its_springs_and_the_feet_carry_the_machine(feet):
    am, got = _walk(feet=feet)
    cfg, n = am.config, am.n
    k_leg, g = cfg.leg.stiffness, cfg.gravity
    per_stack = (n + 1) * cfg.plate.mass + 6 * n * (cfg.leg.motor_mass + cfg.leg.shaft_mass) + cfg.payload.mass
    weight = (cfg.hexapod.body_mass + 6 * per_stack) * g
    for s in got.samples:
        np.testing.assert_allclose(s.forces, k_leg * (_leg_lengths(am, s.plates) - s.lengths), atol=1e-6)
        mass, com = machine_com(am, s.plates[..., :3, :3], s.plates[..., :3, 3], cfg.hexapod.body_mass, s.body_pose[:3])
        assert mass * g == pytest.approx(weight, rel=1e-12)
        w = s.foot_wrenches
        assert np.abs(w[~s.stance]).max(initial=0.0) == 0.0
        np.testing.assert_allclose(w[:, :3].sum(axis=0), [0, 0, weight], atol=1e-6 * weight)
        origins = s.plates[:, 0, :3, 3]
        moment = (np.cross(origins, w[:, :3]) + w[:, 3:]).sum(axis=0)
        np.testing.assert_allclose(moment, np.cross(com, [0, 0, weight]), atol=1e-6 * weight)
        # the load shared by point feet: each standing foot pushed straight up at its centre
        assert np.abs(w[s.stance][:, [0, 1, 3, 4, 5]]).max() <= 1e-6 * weight
        assert w[s.stance, 2].min() >= -1e-9 * weight  # zero when unloaded, about to lift


def test_margins_from_the_tests_own_hull():
    am, got = _walk("wave")
    radius = am.config.plate.radius
    for s in got.samples:
        _, com = machine_com(am, s.plates[..., :3, :3], s.plates[..., :3, 3], 20.0, s.body_pose[:3])
        feet = s.plates[s.stance, 0, :2, 3]
        assert s.stability_margin_m == pytest.approx(_margin(com[:2], feet, radius), abs=1e-12)
        assert s.stability_margin_m >= am.config.hexapod.min_margin


def test_forces_are_rechecked_by_stand_and_do_not_jump_at_lift_off_or_touch_down():
    am, got = _walk()
    cfg, edges = am.config.hexapod, 0
    for j, s in enumerate(got.samples):
        again = stand(am, s.plates, cfg.body_mass, s.body_pose[:3], s.lengths, "resting", hanging=~s.stance)
        assert again.feasible
        np.testing.assert_allclose(again.forces, s.forces, atol=1e-6)
        if j and s.phase != got.samples[j - 1].phase and "swing" in (s.phase, got.samples[j - 1].phase):
            edge = got.samples[j - 1]  # the last unloading or swinging: the foot on the floor, unloaded
            on = stand(am, edge.plates, cfg.body_mass, edge.body_pose[:3], edge.lengths, "resting")
            up = ~(s.stance if s.phase == "swing" else got.samples[j - 1].stance)
            off = stand(am, edge.plates, cfg.body_mass, edge.body_pose[:3], edge.lengths, "resting", hanging=up)
            # the same poses with the foot on the floor or hanging: the same forces
            np.testing.assert_allclose(on.forces, off.forces, atol=1e-6)
            assert np.abs(on.foot_wrenches[up]).max() <= 1e-6
            edges += 1
    assert edges == 2 * 2 * got.cycles  # every lift-off and touch-down of both groups


def test_too_few_stance_feet_for_the_load_stop_the_walk_with_why():
    am = _model(stacks=3)
    got = walk(am, (0.05, 0.0, 0.0), gait="tripod", step=0.05, samples=1)
    assert not got.success
    assert got.reason.startswith("step 1 (unload") and "cannot carry the machine" in got.reason
    assert got.samples[-1].violations and all(not s.violations for s in got.samples[:-1])


def test_a_step_too_long_for_the_stroke_is_refused_with_why():
    am = _model()
    got = walk(am, (0.6, 0.0, 0.0), gait="tripod", step=0.6, samples=1)
    assert not got.success and got.reason.startswith("step 1 (swing")
    assert "a commanded length is outside the stroke" in got.reason


@pytest.mark.parametrize(
    "kwargs",
    [
        {"to": (0.1, 0.0)},
        {"to": (np.nan, 0.0, 0.0)},
        {"to": (0.1, 0.0, 4.0)},
        {"gait": "gallop"},
        {"gait": 3},
        {"feet": "flying"},
        {"step": 0.0},
        {"step": 2.5},
        {"step": True},
        {"step": float("inf")},
        {"samples": 0},
        {"samples": 51},
        {"samples": 2.0},
        {"lift": -0.01},
        {"min_margin": 1e3},
        {"to": (100.0, 0.0, 0.0), "step": 0.01},
    ],
)
def test_malformed_walks_are_refused(kwargs):
    args = {"to": (0.1, 0.0, 0.0), **kwargs}
    with pytest.raises(HexapodError):
        walk(_model(), **args)


def test_stand_refuses_malformed_hanging_feet():
    am = _model()
    stacks, mass, com = ap.hexapod.configured_hexapod(am)
    for bad in ([True] * 5, np.ones(6), "yes"):
        with pytest.raises(HexapodError, match="hanging"):
            stand(am, stacks, mass, com, hanging=bad)
    with pytest.raises(HexapodError, match="at least one foot"):
        stand(am, stacks, mass, com, feet="resting", hanging=np.ones(6, bool))
    low = [PlateArrays(s.R.copy(), s.p - [0.0, 0.0, 0.01]) if i == 0 else s for i, s in enumerate(stacks)]
    with pytest.raises(HexapodError, match="below the floor"):
        stand(am, low, mass, com, feet="resting", hanging=np.eye(6, dtype=bool)[0])


def test_a_turning_foot_steps_at_most_step_along_its_chord():
    """A pure turn: each cycle moves every foot along the same chord, 2 r sin(yaw / 2m) ≤ step
    (the whole turn's chord over m would undercount: 24 cycles instead of 36 here)."""
    am = _model(stacks=3)  # three stacks stop at once: the count is all this needs
    got = walk(am, (0.0, 0.0, 3.0), step=0.05, samples=1)
    radius, step = am.config.hexapod.radius, 0.05
    assert got.cycles == int(np.ceil(3.0 / (2.0 * np.arcsin(step / (2.0 * radius)))))
    assert 2 * radius * np.sin(3.0 / (2 * got.cycles)) <= step < 2 * radius * np.sin(3.0 / (2 * (got.cycles - 1)))


def test_the_configured_min_margin_stops_a_walk_that_comes_closer_to_tipping():
    am = _model(min_margin=0.45)  # the tripod's swing comes to about 0.38 m
    got = walk(am, (0.04, 0.0, 0.0), step=0.05, samples=1)
    last = got.samples[-1]
    assert not got.success and last.phase == "swing" and "min_margin 0.45 m" in got.reason
    assert last.stability_margin_m < 0.45 <= min(s.stability_margin_m for s in got.samples[:-1])
    assert walk(am, (0.04, 0.0, 0.0), step=0.05, samples=1, min_margin=0.3).success
