"""Anchors, home pose and reach bound against the design notes (tests/checks.py)."""

from __future__ import annotations

import numpy as np
import pytest
from checks import design_anchors, home_directions, home_height

import assembler_pin as ap
from assembler_pin.model.geometry import reach_bound


@pytest.mark.parametrize("config", [{}, {"platforms": 3, "plate": {"node_radius": 0.2, "node_spacing_deg": 12.0}}])
def test_anchors_and_home_directions_follow_the_design(config):
    cfg = ap.load_config(config)
    geo = ap.model.geometry.leg_geometry(cfg)
    for j in range(cfg.platforms):
        bottom, top = design_anchors(cfg, j)
        np.testing.assert_allclose(geo.bottom_in_plate[j], bottom, atol=1e-15)
        np.testing.assert_allclose(geo.top_in_plate[j], top, atol=1e-15)
        np.testing.assert_allclose(geo.home_direction[j], home_directions(cfg, j), atol=1e-15)
        # each universal joint's frame has its z axis along the home direction
        np.testing.assert_allclose(geo.leg_base_rotation[j][:, :, 2], home_directions(cfg, j), atol=1e-12)
    assert cfg.home_height == pytest.approx(home_height(cfg), abs=1e-15)


def test_home_pose_puts_every_leg_at_mid_stroke():
    cfg = ap.load_config()
    plates = ap.model.geometry.home_plates(cfg)
    for j in range(cfg.platforms):
        bottom, top = design_anchors(cfg, j)
        b = bottom @ plates[j].rotation.T + plates[j].translation
        t = top @ plates[j + 1].rotation.T + plates[j + 1].translation
        np.testing.assert_allclose(np.linalg.norm(t - b, axis=1), cfg.leg.mid_length, atol=1e-12)


def test_reach_bound_is_reached_by_no_pose_and_is_tight_per_platform():
    cfg = ap.load_config()
    bound = reach_bound(cfg)
    # one platform: anchors on the node circle, so |b| + max_length + |t| = 2r + max_length
    assert bound == pytest.approx(cfg.platforms * (2 * cfg.plate.node_radius + cfg.leg.max_length))
    am = ap.AssemblerModel.from_config(cfg)
    rng = np.random.default_rng(0)
    for _ in range(20):
        lengths = rng.uniform(cfg.leg.min_length, cfg.leg.max_length, (am.n, 6))
        fk = ap.stack_forward_kinematics(am, lengths)
        if fk.success:
            assert np.linalg.norm(fk.plates.p[-1]) < bound
