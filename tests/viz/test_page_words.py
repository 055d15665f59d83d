"""What a page shows agrees with its data: an animation's colour bar and leg sleeves on the
scale of the whole sequence's forces, every leg recoloured (its sleeve stretched joint to
joint) in every frame; no force legend where the legs carry no force colour; the world axes
in the legend; a camera high enough to show the floor as a floor."""

from __future__ import annotations

import re

import numpy as np
import pytest
from pages import page_commands

from assembler_pin.common.naming import names
from assembler_pin.viz import StackViewer, interpolate_states
from assembler_pin.viz.animation import FORCE_BAND_COVER, FORCE_BAND_LENGTH, FORCE_BAND_LEVELS
from assembler_pin.viz.camera import DEFAULT_ELEVATION_DEG


@pytest.fixture(scope="module")
def animated(am, bent_plates):
    states = interpolate_states(am, am.home, bent_plates, steps=6)
    with StackViewer(am) as v:
        v.animate(states, fps=10, color_forces=True)
        html = v.static_html()
        yield v, states, html


def _clips(html: str) -> dict:
    anim = [c for c in page_commands(html) if c["type"] == "set_animation"][-1]
    return {c["path"]: {t["name"]: t["keys"] for t in c["clip"]["tracks"]} for c in anim["animations"]}


def test_the_colour_bar_reads_the_whole_animations_forces(am, animated):
    viewer, states, html = animated
    peak = max(float(np.abs(st.forces).max()) for st in states)
    floor = 0.1 * min(am.config.leg.max_tension, am.config.leg.max_compression)
    scale = max(peak, floor)
    assert peak > float(np.abs(states[0].forces).max()) + 1.0  # the first frame is not the largest
    assert viewer.force_range == pytest.approx((scale, scale))
    bar = re.search(r'id="assembler-colorbar".*?<span>−(\d+)</span><span>0</span><span>\+(\d+)</span>', html, re.S)
    assert bar and float(bar.group(1)) == pytest.approx(scale, abs=0.5) == float(bar.group(2))


def test_every_leg_is_recoloured_every_frame_on_that_scale(am, animated):
    viewer, states, html = animated
    clips = _clips(html)
    tension, compression = viewer.force_range
    levels = len(FORCE_BAND_LEVELS)
    for frame, st in enumerate(states):
        fraction = np.clip(np.where(st.forces >= 0, st.forces / tension, st.forces / compression), -1, 1)
        want = np.rint((levels - 1) / 2 * (fraction + 1)).astype(int)
        for j in range(am.n):
            for i in range(6):
                root = f"/meshcat/assembler_force_bands/{names.leg(j, i)}"
                shown = [k for k in range(levels) if clips[f"{root}/level{k}"][".visible"][frame]["value"]]
                assert shown == [want[j, i]], (frame, j, i)
                scale = [key for key in clips[f"{root}/level{shown[0]}"][".scale"] if key["time"] == frame]
                length = np.linalg.norm(st.legs.top_points[j, i] - st.legs.bottom_points[j, i])
                assert scale[-1]["value"][1] == pytest.approx(FORCE_BAND_COVER * length / FORCE_BAND_LENGTH)
    used = {int(k) for st in states for k in np.unique(np.rint((levels - 1) / 2 * (st.forces / tension + 1)))}
    assert min(used) <= 2 or max(used) >= levels - 3  # the sleeves use the scale, not a sliver of it


def test_a_page_without_force_colours_has_no_force_legend(am):
    with StackViewer(am) as v:
        v.display(am.home, color_forces=False)
        html = v.overlay_html()
    assert "assembler-colorbar" not in html and "leg in tension" not in html
    assert "world axes at the origin" in html


def test_pages_name_the_world_axes_and_look_down_on_the_floor(am, animated):
    _, _, html = animated
    assert re.search(r"world axes at the origin: .*x.*y.*z", html)
    assert DEFAULT_ELEVATION_DEG >= 30


def test_the_page_camera_looks_down_on_the_floor_from_the_side(am):
    """The camera a page sets (three.js is y-up) looks down on the stack at the default
    elevation, from -y (the paper's side view), and the floor grid lies under the stack."""
    with StackViewer(am) as v:
        v.display(am.home)
        cmds = page_commands(v.static_html())
    (position,) = [
        c["value"] for c in cmds if c["path"] == "/Cameras/default/rotated/<object>" and c.get("property") == "position"
    ][-1:]
    x, up, back = position  # three.js (x, z, -y) of the world
    elevation = np.degrees(np.arctan2(up, np.hypot(x, back)))
    assert elevation == pytest.approx(DEFAULT_ELEVATION_DEG) and elevation >= 30
    assert back > 0 and abs(x) < 1e-9  # from world -y, x to the right
    (grid,) = [c for c in cmds if c["type"] == "set_transform" and c["path"] == "/Grid"][-1:]
    offset = np.array(grid["matrix"]).reshape(4, 4).T[:3, 3]
    assert offset[2] < 0  # the scene is moved down by the stack's centre: the floor is below the target
