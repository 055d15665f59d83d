"""A scene in the viewer: its obstacles and floor drawn at their meshcat paths and named in
the legend, the closest pair of bodies marked by two points exactly its clearance apart, on
the two bodies' surfaces (the tests' own point–segment distance), and hostile scene files
refused in one line before a server starts."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from pages import page_commands, page_end_transforms

from assembler_pin import evaluate_state
from assembler_pin.collision import read_scene
from assembler_pin.viz import StackViewer

TRUSS_BAY = Path(__file__).resolve().parents[2] / "examples" / "truss_bay.yaml"
OBSTACLE_PATHS = [f"cylinder_{k}" for k in range(4)] + [f"sphere_{k}" for k in range(4, 8)] + ["box_8", "floor"]


def _point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    t = float(np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + t * (b - a))))


def _drawn_pair(html: str, prefix: str = "assembler") -> tuple[np.ndarray, np.ndarray]:
    """The two marker balls' centres as the page places them, world frame (the framing shift
    of the marker's root undone)."""
    T = page_end_transforms(html)
    root = T[f"/meshcat/{prefix}_closest"]
    a = (root @ T[f"/meshcat/{prefix}_closest/a"])[:3, 3] - root[:3, 3]
    b = (root @ T[f"/meshcat/{prefix}_closest/b"])[:3, 3] - root[:3, 3]
    return a, b


@pytest.fixture(scope="module")
def floor_page(am):
    post = {"name": "post", "sphere": {"radius": 0.05, "center": [0.6, 0.0, 0.5]}}
    scene = {"floor": {"z": 0.01}, "obstacles": [post]}  # above the motors' 0.0229 m to their plate
    with StackViewer(am, scene=scene) as v:
        state = v.display(am.home)
        yield v, state, v.static_html()


def test_obstacles_and_floor_are_drawn_and_named(floor_page):
    viewer, _, html = floor_page
    objects = {c["path"]: c for c in page_commands(html) if c["type"] == "set_object"}
    assert "/meshcat/assembler_obstacles/sphere_0" in objects
    assert "/meshcat/assembler_obstacles/floor" in objects
    assert "obstacles: post" in html and "floor at z = 0.01 m" in html
    assert viewer.closest is not None and viewer.closest.label in html


def test_closest_pair_is_drawn_its_clearance_apart_on_both_surfaces(am, floor_page):
    viewer, state, html = floor_page
    near = evaluate_state(am, am.home, scene=viewer.scene).clearance
    assert near is not None and near.between == ("SP0 leg 0", "floor") == viewer.closest.between
    a, b = _drawn_pair(html)
    assert np.linalg.norm(a - b) == pytest.approx(near.min_distance, abs=1e-9)
    assert b[2] == pytest.approx(0.01, abs=1e-12)  # on the floor plane
    bottom, top = state.legs.bottom_points[0, 0], state.legs.top_points[0, 0]
    u = (top - bottom) / np.linalg.norm(top - bottom)
    leg = am.config.leg  # the motor's capsule beyond the node zone of the bottom joint (on the floor)
    motor = (bottom + leg.node_zone * u, bottom + leg.motor_length * u)
    assert _point_segment(a, *motor) == pytest.approx(leg.motor_radius, abs=1e-9)
    assert "m between SP0 leg 0 and floor" in html


@pytest.mark.parametrize(
    "obstacle",
    [
        {"box": {"size": [0.1, 0.1, 0.1], "pose": [0.25, 0.0, 0.5, 0.3, 0.2, 0.0]}},
        {"cylinder": {"radius": 0.02, "length": 0.6, "pose": [0.2, 0.0, 0.35, 1.5707963267948966, 0.0, 0.0]}},
        {"sphere": {"radius": 0.05, "center": [0.2, 0.05, 0.5]}},
    ],
)
def test_witness_points_are_the_clearance_apart_for_every_kind(am, bent_plates, obstacle):
    scene = read_scene({"obstacles": [obstacle]})
    with StackViewer(am, scene=scene) as v:
        v.display(bent_plates)
        html = v.static_html()
    near = evaluate_state(am, bent_plates, scene=scene).clearance
    a, b = _drawn_pair(html)
    assert np.linalg.norm(a - b) == pytest.approx(abs(near.min_distance), abs=1e-9)
    assert v.closest is not None and v.closest.between == near.between


def test_no_scene_no_obstacles_nor_mark(am):
    with StackViewer(am) as v:
        v.display(am.home)
        html = v.static_html()
    paths = {c.get("path", "") for c in page_commands(html)}
    assert v.closest is None and not any("_obstacles" in p or "_closest" in p for p in paths)


def _view(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "assembler_pin.cli", "view", *args], capture_output=True, text=True, timeout=300
    )


def test_cli_view_scene_page(am, tmp_path):
    page = tmp_path / "scene.html"
    out = _view("--home", "--scene", str(TRUSS_BAY), "--html", str(page))
    assert out.returncode == 0, out.stderr
    html = page.read_text()
    paths = {c.get("path", "") for c in page_commands(html)}
    assert {f"/meshcat/assembler_obstacles/{k}" for k in OBSTACLE_PATHS} <= paths
    assert {"/meshcat/assembler_closest/a", "/meshcat/assembler_closest/b"} <= paths
    near = evaluate_state(am, am.home, scene=TRUSS_BAY).clearance
    assert near is not None
    a, b = _drawn_pair(html)
    assert np.linalg.norm(a - b) == pytest.approx(near.min_distance, abs=1e-9)
    shown = f"{near.min_distance:.4f} m between {near.between[0]} and {near.between[1]}"
    assert shown in html and shown in out.stderr
    assert f"clearance {near.min_distance:.4f} m ({near.between[0]} – {near.between[1]})" in html  # the title
    assert "obstacles: column -y, column +y, lower strut" in html


def test_cli_view_refuses_a_hostile_scene_in_one_line(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("obstacles: [\n")
    unknown = tmp_path / "unknown.yaml"
    unknown.write_text("walls: []\n")
    for scene, words in ((tmp_path / "missing.yaml", "cannot read"), (bad, "not valid YAML"), (unknown, "walls")):
        out = _view("--home", "--scene", str(scene), "--html", str(tmp_path / "x.html"))
        assert out.returncode == 2 and out.stderr.count("\n") == 1 and words in out.stderr, out.stderr
        assert not (tmp_path / "x.html").exists()


def test_cli_view_scenario_solved_clear_of_the_scene(am, tmp_path):
    """The scenario's force-optimal pose passes through the lower strut (examples/truss_bay.yaml):
    with the scene, the pose shown keeps the clearance, and the mark says so."""
    page = tmp_path / "scenario.html"
    out = _view("--scenario", "translation", "--scene", str(TRUSS_BAY), "--html", str(page))
    assert out.returncode == 0, out.stderr
    html = page.read_text()
    a, b = _drawn_pair(html)
    assert np.linalg.norm(a - b) >= am.config.clearance - 1e-6
    assert "closest pair: " in out.stderr and "; clearance " in html
