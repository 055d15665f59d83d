"""The hexapod's page: each stack drawn where our equilibrium puts it (Pinocchio's kinematics
of the drawn bodies against our plates), and the standalone page with its title and margin."""

from __future__ import annotations

import numpy as np

import assembler_pin as ap
from assembler_pin.hexapod import ring_stacks, stand
from assembler_pin.kinematics.legs import leg_points
from assembler_pin.viz import placements as pl
from assembler_pin.viz.hexapod import HexapodScene


def test_the_page_draws_every_stack_at_its_equilibrium(tmp_path):
    am = ap.AssemblerModel.from_config({"platforms": 2, "payload": {"mass": 0.0}})
    stacks = ring_stacks(am, 3, 0.4)
    com = [0.05, 0.0, stacks[0].p[-1, 2] + 0.1]
    lengths = stand(am, stacks, 20.0, com).lengths + 2e-3 * np.sin(np.arange(36)).reshape(3, 2, 6)
    result = stand(am, stacks, 20.0, com, lengths=lengths, feet="resting")
    scene = HexapodScene(am, result)
    try:
        for i, viz in enumerate(scene.visualizers):
            bottom, top = pl.drawn_joint_centres(viz, am)
            ours = leg_points(am.geometry, result.plates[i, :, :3, :3], result.plates[i, :, :3, 3])
            np.testing.assert_allclose(bottom, ours[0], atol=1e-9)
            np.testing.assert_allclose(top, ours[1], atol=1e-9)
        html = scene.static_html(tmp_path / "page.html")
    finally:
        scene.close()
    assert (tmp_path / "page.html").read_text() == html
    assert f"max|F| {result.max_abs_force:.1f} N" in html and "support polygon: margin" in html
