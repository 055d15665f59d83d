"""The walk in the viewer: the page's animation read back from its embedded meshcat commands.

A small walk is built here in a second without the planner: a reach (plate 0 held) by stack
FK of interpolated lengths, a transfer (both held) at its last pose with the load moved, and a
swing (plate n held) by stack FK on the turned model from plate n, brought back to the
original plates. The page must place plates 0 and n at every sample, draw every foothold, show
the sleeves of each sample's own forces and keep each held foot still through its phase.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from pages import page_commands

import assembler_pin as ap
from assembler_pin.common.naming import names
from assembler_pin.exceptions import ViewerError
from assembler_pin.viz import StackViewer, interpolate_states
from assembler_pin.viz.animation import FORCE_BAND_LEVELS
from assembler_pin.walk import WalkPhase, WalkResult, turned_model
from assembler_pin.walk.footholds import TURN_OVER

FPS = 5.0


def _phase(kind: str, support: str, step: int, plates: list, forces: list) -> WalkPhase:
    F = np.array(forces)
    return WalkPhase(kind, support, step, list(plates), np.zeros_like(F), np.zeros_like(F), F, True)


def _swing(am, start: ap.PlateArrays, steps: int = 4) -> tuple[list, list]:
    """Plates and forces of a swing from ``start``: FK on the turned model, plate n held."""
    tm = turned_model(am)
    turned = tm.plates(start)
    L0 = ap.kinematics.leg_state(tm.model, turned).lengths
    L1 = L0.copy()
    L1[:, ::2] += 0.012
    plates, forces, guess = [], [], turned
    for t in np.linspace(0.0, 1.0, steps):
        fk = ap.stack_forward_kinematics(tm.model, L0 + t * (L1 - L0), base=turned.se3(0), guess=guess)
        guess = fk.raise_if_failed()
        plates.append(tm.original_plates(guess))
        forces.append(tm.original_legs(ap.evaluate_state(tm.model, guess).forces))
    return plates, forces


@pytest.fixture(scope="module")
def walk(am, bent_plates) -> WalkResult:
    reach = interpolate_states(am, am.home, bent_plates, steps=4)
    landed = reach[-1].plates
    load = [s * reach[-1].forces for s in (1.0, 0.4, -0.3)]
    swing_plates, swing_forces = _swing(am, landed)
    feet = (
        pin.SE3.Identity(),
        landed.se3(am.n) * TURN_OVER.inverse(),
        swing_plates[-1].se3(0),
    )
    phases = [
        _phase("reach", "base", 1, [s.plates for s in reach], [s.forces for s in reach]),
        _phase("transfer", "both", 1, [landed] * 3, load),
        _phase("swing", "ee", 2, swing_plates, swing_forces),
    ]
    return WalkResult(True, "reached the last foothold", feet, phases)


@pytest.fixture(scope="module")
def page(am, walk, tmp_path_factory):
    """(viewer, spans, the page's commands, its animation's clips by path, overlay html)."""
    with StackViewer(am) as v:
        spans = v.show_walk(walk, fps=FPS)
        html = v.static_html(tmp_path_factory.mktemp("walk") / "walk.html")
        cmds = page_commands(html)
        anim = [c for c in cmds if c["type"] == "set_animation"][-1]
        clips = {c["path"]: {t["name"]: t["keys"] for t in c["clip"]["tracks"]} for c in anim["animations"]}
        yield v, spans, cmds, clips, v.overlay_html()


def _samples(walk) -> list[tuple[int, ap.PlateArrays, np.ndarray, str, str]]:
    return [(k, pa, p.forces[i], p.kind, p.support) for k, p in enumerate(walk.phases) for i, pa in enumerate(p.plates)]


def _animated_pose(clip: dict, frame: int) -> np.ndarray:
    """The 4x4 pose a clip's keys give at ``frame`` (a key must be set at that frame)."""
    (p,) = [key["value"] for key in clip[".position"] if key["time"] == frame]
    (q,) = [key["value"] for key in clip[".quaternion"] if key["time"] == frame]
    x, y, z, w = q
    T = np.eye(4)
    T[:3, :3] = pin.Quaternion(w, x, y, z).normalized().toRotationMatrix()
    T[:3, 3] = p
    return T


def _plate_clip(viewer: StackViewer, clips: dict, k: int) -> dict:
    """The animation clip of plate k's first visual, whose origin is the plate's frame."""
    (g,) = [g for g in viewer.visual_model.geometryObjects if g.name == f"{names.plate(k)}_0"]
    assert np.allclose(g.placement.homogeneous, np.eye(4), atol=0.0)
    return clips["/meshcat/" + viewer.viz.getViewerNodeName(g, pin.GeometryType.VISUAL)]


def test_the_page_places_plates_0_and_n_where_every_sample_puts_them(am, walk, page):
    viewer, spans, _, clips, _ = page
    samples = _samples(walk)
    assert len(samples) == 4 + 3 + 4
    for k in (0, am.n):
        clip = _plate_clip(viewer, clips, k)
        assert len(clip[".position"]) == len(samples)
        for frame, (_, pa, *_rest) in enumerate(samples):
            assert np.abs(_animated_pose(clip, frame) - pa.se3(k).homogeneous).max() < 1e-9, (k, frame)
    assert [(s.kind, s.first, s.last) for s in spans] == [("reach", 0, 3), ("transfer", 4, 6), ("swing", 7, 10)]
    assert spans[2].start == pytest.approx(7 / FPS) and spans[2].end == pytest.approx(10 / FPS)


def test_a_foothold_disc_stands_on_each_foothold(walk, page):
    _, _, cmds, _, html = page
    placed = {c["path"]: np.array(c["matrix"]).reshape(4, 4).T for c in cmds if c["type"] == "set_transform"}
    discs = {p: T for p, T in placed.items() if "/assembler_walk/footholds/" in p}
    assert len(discs) == len(walk.footholds)
    for k, f in enumerate(walk.footholds):
        T = discs[f"/meshcat/assembler_walk/footholds/{k}"]
        assert np.abs(T[:3, 3] - f.translation).max() < 1e-12
        assert np.abs(T[:3, 1] - f.rotation[:, 2]).max() < 1e-12  # the disc's axis is the surface normal
    assert "foothold" in html and "phase 2 swing (ee held): frames 7–10, 1.4–2.0 s" in html


def test_each_held_foot_is_marked_and_stays_still_through_its_phase(am, walk, page):
    viewer, spans, _, clips, _ = page
    held = {"base": [0], "ee": [am.n], "both": [0, am.n]}
    for span in spans:
        for k in held[span.support]:
            clip = _plate_clip(viewer, clips, k)
            first = _animated_pose(clip, span.first)
            for frame in range(span.first, span.last + 1):
                assert np.abs(_animated_pose(clip, frame) - first).max() < 1e-9, (span.kind, k, frame)
        for foot, k in (("base", 0), ("ee", am.n)):
            marker = clips[f"/meshcat/assembler_walk/held/{foot}_{span.kind}"]
            for frame in range(span.first, span.last + 1):
                assert marker[".visible"][frame]["value"] is (k in held[span.support])
                if k in held[span.support]:
                    assert np.abs(_animated_pose(marker, frame)[:3, 3] - first_plate(walk, span, k)).max() < 1e-9
            other = [c for c in clips if "/assembler_walk/held/" in c and not c.endswith(f"{foot}_{span.kind}")]
            for path in (p for p in other if p.split("/")[-1].startswith(foot)):
                assert not any(clips[path][".visible"][f]["value"] for f in range(span.first, span.last + 1))


def first_plate(walk, span, k: int) -> np.ndarray:
    return walk.phases[span.phase].plates[0].p[k]


def test_the_sleeves_show_each_samples_own_forces(am, walk, page):
    """Sleeve level of every leg = nearest twentieth of its force over the colour scale, the
    walk's largest force (at least a tenth of the limit), from the phase's forces (a
    transfer's load moves; the pose does not); the colour bar reads that scale."""
    viewer, _, _, clips, html = page
    leg = am.config.leg
    samples = list(_samples(walk))
    peak = max(
        max(float(np.abs(F).max()) for _, _, F, _, _ in samples), 0.1 * min(leg.max_tension, leg.max_compression)
    )
    assert viewer.force_range == pytest.approx((peak, peak))
    assert f"−{peak:.0f}" in html and f"+{peak:.0f}" in html  # the colour bar's ends
    guide = " ".join((Path(__file__).parents[2] / "docs" / "guides" / "walking.md").read_text().split())
    assert "the colour bar runs to the walk's largest force, at least a tenth of the smaller force limit" in guide
    levels = len(FORCE_BAND_LEVELS)
    for frame, (_, _, F, _, _) in enumerate(samples):
        want = np.rint((levels - 1) / 2 * (np.clip(F / peak, -1.0, 1.0) + 1.0)).astype(int)
        for j in range(am.n):
            for i in range(6):
                root = f"/meshcat/assembler_force_bands/{names.leg(j, i)}"
                shown = [lv for lv in range(levels) if clips[f"{root}/level{lv}"][".visible"][frame]["value"]]
                assert shown == [want[j, i]], (frame, j, i)


def test_a_walk_without_a_sample_is_refused(walk, page):
    viewer = page[0]
    empty = WalkResult(False, "step 1: out of reach", walk.footholds, [_phase("reach", "base", 1, [], [])])
    with pytest.raises(ViewerError, match="no sample"):
        viewer.show_walk(empty)
    with pytest.raises(ViewerError, match="fps"):
        viewer.show_walk(walk, fps=float("nan"))


def test_cli_walk_html_refusals_and_a_walk_with_nothing_to_draw(tmp_path, capsys):
    from assembler_pin.cli import main

    page = tmp_path / "walk.html"
    assert main(["walk", "--floor", "0.5", "3", "--fps", "0", "--html", str(page)]) == 2
    assert main(["walk", "--floor", "0.5", "3", "--html", str(tmp_path / "no" / "walk.html")]) == 2
    assert main(["walk", "--floor", "0.5", "3", "--fps", "5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and "--fps" in err[0] and "does not exist" in err[1] and "needs --html" in err[2]
    assert main(["-q", "walk", "--floor", "5", "2", "--html", str(page)]) == 1  # out of reach at once
    assert "not written" in capsys.readouterr().err and not page.exists()


def test_the_phase_is_named_frame_by_frame(walk, page):
    _, _, cmds, clips, _ = page
    kinds = [kind for _, _, _, kind, _ in _samples(walk)]
    for kind in ("reach", "transfer", "swing"):
        shown = [key["value"] for key in clips[f"/meshcat/assembler_walk/labels/{kind}"][".visible"]]
        assert shown == [k == kind for k in kinds], kind
    labels = [c for c in cmds if c["type"] == "set_object" and "/assembler_walk/labels/" in c["path"]]
    assert len(labels) == 3 and all(c["object"]["textures"] for c in labels)  # the name is an image


def test_a_walk_among_obstacles_draws_them(am, walk, tmp_path):
    """``walk --scene ... --html``: the page draws the scene the walk was planned among."""
    import dataclasses

    from assembler_pin.cli.walk import view_walk
    from assembler_pin.collision import scene_from_dict

    post = {"name": "post", "box": {"size": [0.1, 0.1, 0.4], "pose": [0.9, 0.4, 0.2, 0.0, 0.0, 0.0]}}
    among = dataclasses.replace(walk, scene=scene_from_dict({"floor": {"z": 0.0}, "obstacles": [post]}))
    page = tmp_path / "walk.html"
    view_walk(am, among, str(page), FPS)
    html = page.read_text()
    objects = {c["path"]: c for c in page_commands(html) if c["type"] == "set_object"}
    assert "/meshcat/assembler_obstacles/box_0" in objects and "/meshcat/assembler_obstacles/floor" in objects
    assert "obstacles: post" in html
    assert any(c["type"] == "set_animation" for c in page_commands(html))


def test_a_stack_without_a_tool_is_drawn_without_the_payload_cube(am, bent_plates):
    """A walking stack carries no tool (``walk``'s default ``--payload 0``): its page draws no
    payload. A payload of mass but no radius (the default: a point mass) is drawn as the rod to
    its centre only; one with a radius as that sphere too, the body the clearance checks,
    centred at its offset above the EE plate."""
    import dataclasses

    from assembler_pin.cli.walk import walking_config

    bare = ap.AssemblerModel.from_config(walking_config(am.config, 0.0))
    tool = ap.AssemblerModel.from_config(am.config.replace(payload=dataclasses.replace(am.config.payload, radius=0.05)))
    objects = {}
    for key, model in (("tool", tool), ("point", am), ("bare", bare)):
        with StackViewer(model) as v:
            v.display(bent_plates)
            cmds = page_commands(v.static_html())
            objects[key] = {c["path"] for c in cmds if c["type"] == "set_object"}
            payload = [g for g in v.visual_model.geometryObjects if g.name.startswith(names.payload)]
            assert len(payload) == (1 if key == "tool" else 0)
            if payload:
                assert payload[0].geometry.radius == pytest.approx(0.05)
                path = "/meshcat/" + v.viz.getViewerNodeName(payload[0], pin.GeometryType.VISUAL)
                placed = [c for c in cmds if c["type"] == "set_transform" and c["path"] == path]
                T = np.array(placed[-1]["matrix"]).reshape(4, 4).T
                ee = ap.kinematics.plate_arrays(am, bent_plates)
                expected = ee.p[-1] + am.config.payload.offset * ee.R[-1][:, 2]
                np.testing.assert_allclose(T[:3, 3], expected, atol=1e-9)
    assert am.config.payload.mass > 0 and am.config.payload.radius == 0
    extra = objects["tool"] - objects["bare"]
    assert sorted(p.rsplit("/", 2)[-2] for p in extra) == ["assembler_payload_rod", "visuals"]  # the sphere, its rod
    assert all(names.payload in p for p in extra)
    assert sorted(p.rsplit("/", 2)[-2] for p in objects["point"] - objects["bare"]) == ["assembler_payload_rod"]
