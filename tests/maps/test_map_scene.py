"""A map with a scene: every cell's pose keeps its clearance from the obstacles, every cell
records its clearance and pose (held to an independent clearance of the stored pose), a goal
no pose reaches clear of them is a failed cell with its reason, and a map directory computed
with one scene is never mixed with another."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
import yaml
from pages import page_commands

import assembler_pin as ap
from assembler_pin.cli import main
from assembler_pin.collision import clearance, read_scene
from assembler_pin.exceptions import MapError
from assembler_pin.kinematics import PlateArrays
from assembler_pin.maps import cells, parse_grid, read_map, run_map

#: The truss bay's lower strut alone (examples/truss_bay.yaml): the free optimum of the goal
#: (0.5, 0, 0.8), level, passes into it (docs/guides/collisions.md).
STRUT = {
    "obstacles": [
        {
            "name": "lower strut",
            "cylinder": {"radius": 0.015, "length": 0.9, "pose": [0.36, 0.0, 0.52, 1.5707963267948966, 0.0, 0.0]},
        }
    ]
}
GRID = "x=0.45:0.5:2,y=0,z=0.8"  # two cells beside the strut, seconds each


def _plates(row: dict) -> PlateArrays:
    """The stored pose of a row: world poses of plates 0..n from ``plates_xyzquat``."""
    q = np.asarray(row["plates_xyzquat"], dtype=float).reshape(-1, 7)
    return PlateArrays.from_se3([pin.XYZQUATToSE3(v) for v in q])


@pytest.fixture(scope="module")
def maps(tmp_path_factory):
    """(scene file, the map with the strut, the same map without a scene), each computed once."""
    root = tmp_path_factory.mktemp("scene_maps")
    scene_file = root / "strut.yaml"
    scene_file.write_text(yaml.safe_dump(STRUT))
    cfg = [("default", ap.load_config())]
    run_map(parse_grid(GRID), cfg, root / "strut", workers=0, scene=scene_file)
    run_map(parse_grid(GRID), cfg, root / "free", workers=0)
    return scene_file, root / "strut", root / "free"


def test_every_cell_records_the_clearance_of_its_stored_pose(am, maps):
    scene_file, with_scene, free = maps
    scene = read_scene(scene_file)
    grid = parse_grid(GRID)
    for out, obstacles in ((with_scene, scene), (free, None)):
        rows = read_map(out).to_pylist()
        assert len(rows) == 2
        for row in rows:
            assert row["reachable"] and len(row["plates_xyzquat"]) == 7 * (am.n + 1)
            plates = _plates(row)
            near = clearance(am, plates, obstacles)  # independent of the map's own numbers
            assert abs(near.min_distance - row["clearance_m"]) <= 1e-9
            assert list(near.between) == row["clearance_between"]
            assert row["clearance_m"] >= am.config.clearance
            # the stored pose is the cell's answer: at its goal, within every limit, its max|F|
            state = ap.evaluate_state(am, plates, goal=grid.cell(row["cell"]).goal(), scene=obstacles)
            assert state.feasible, state.violations
            assert state.max_abs_force == pytest.approx(row["max_abs_force"], rel=1e-9)
        if obstacles is not None:
            assert all("lower strut" in r["clearance_between"] for r in rows)  # held off by the strut


def test_a_cell_whose_free_optimum_hits_the_strut_is_solved_clear_of_it(am, maps):
    scene_file, with_scene, free = maps
    scene = read_scene(scene_file)
    at = {(r["x"], r["z"]): r for r in read_map(free).to_pylist()}[(0.5, 0.8)]
    held = {(r["x"], r["z"]): r for r in read_map(with_scene).to_pylist()}[(0.5, 0.8)]
    into = clearance(am, _plates(at), scene)
    assert into.min_distance < 0 and "lower strut" in into.between  # the free pose passes into it
    assert held["clearance_m"] == pytest.approx(am.config.clearance, abs=1e-4)  # held at the limit
    assert held["max_abs_force"] > at["max_abs_force"]  # the price of keeping clear


def test_a_rerun_with_another_scene_is_refused_and_the_same_scene_reused(maps, tmp_path):
    scene_file, with_scene, free = maps
    manifest = json.loads((with_scene / "map.json").read_text())
    assert manifest["scene"] == cells.scene_hash(read_scene(scene_file))
    assert json.loads((free / "map.json").read_text())["scene"] is None
    cfg = [("default", ap.load_config())]
    grid = parse_grid(GRID)
    for out, other in ((with_scene, None), (with_scene, "examples/truss_bay.yaml"), (free, STRUT)):
        with pytest.raises(MapError, match=r"holds another map \(its scene differ\)") as info:
            run_map(grid, cfg, out, workers=0, scene=other)
        assert "\n" not in str(info.value)
    # the same content, as a mapping or from the file: the same map, nothing recomputed
    assert run_map(grid, cfg, with_scene, workers=0, scene=STRUT).skipped == 2
    assert run_map(grid, cfg, free, workers=0).skipped == 2
    # a row computed with another scene under this map's manifest is another map's row
    with_scene_rows = sorted(with_scene.glob("part-*.parquet"))
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    (mixed / "map.json").write_text((free / "map.json").read_text())
    (mixed / with_scene_rows[0].name).write_bytes(with_scene_rows[0].read_bytes())
    with pytest.raises(MapError, match="holds a row of another map"):
        run_map(grid, cfg, mixed, workers=0)


def test_the_scene_reaches_the_worker_bit_for_bit():
    scene = read_scene("examples/truss_bay.yaml")
    key = cells.scene_key(scene)
    again = cells.scene_from_key(key)
    assert cells.scene_key(again) == key and cells.scene_from_key("") is None and cells.scene_key(None) == ""
    for a, b in zip(scene.obstacles, again.obstacles, strict=True):
        assert (a.kind, a.name, a.size) == (b.kind, b.name, b.size)
        assert np.array_equal(a.pose.homogeneous, b.pose.homogeneous)
    assert again.floor_z == scene.floor_z and again.standing == scene.standing


def test_a_goal_no_pose_reaches_clear_of_the_scene_is_a_failed_cell(tmp_path):
    sphere = {"obstacles": [{"name": "ball", "sphere": {"radius": 0.03, "center": [0.5, 0.0, 0.8]}}]}
    run_map(parse_grid("x=0.5,y=0,z=0.8"), [("default", ap.load_config())], tmp_path / "m", workers=0, scene=sphere)
    (row,) = read_map(tmp_path / "m").to_pylist()
    assert not row["reachable"] and row["reason"].startswith("collision: ") and "ball" in row["reason"]
    assert row["clearance_m"] is None and row["clearance_between"] == row["plates_xyzquat"] == []
    assert np.isnan(row["max_abs_force"]) and np.isnan(row["capacity_kg"])


def test_cli_map_scene(maps, tmp_path, capsys):
    scene_file, with_scene, _ = maps
    args = ["map", "--grid", GRID, "--workers", "0", "--no-progress", "--out", str(with_scene)]
    assert main([*args, "--scene", str(scene_file), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["computed"] == 0 and doc["already_done"] == 2 and doc["scene"] == str(scene_file)
    lo, hi = doc["clearance_m_range"]
    assert 0.005 <= lo <= hi < 0.006
    assert main([*args, "--scene", str(scene_file)]) == 0
    out = capsys.readouterr().out
    assert "clearance: 5.0 – 5.0 mm (scene " in out
    assert "map: 0 cells computed, 2 already in" in out and "cells/s" not in out  # no rate of nothing
    for extra, says in (([], "its scene differ"), (["--scene", str(tmp_path / "none.yaml")], "none.yaml")):
        assert main([*args, *extra]) != 0
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and says in err[0], err


def test_the_clearance_panel_of_a_map_with_cells_without_a_pose(am, maps):
    """The PNG of stored rows, some without a pose (empty lists): the clearance panel holds
    each reached cell's clearance in mm, the others are marked unreachable."""
    import pyarrow as pa

    from assembler_pin.maps.pictures import map_heatmaps
    from assembler_pin.maps.store import schema

    rows = read_map(maps[2]).to_pylist()
    gone = {"reachable": False, "clearance_m": None, "clearance_between": [], "plates_xyzquat": []}
    far = [r | gone | {"cell": r["cell"] + 2, "iz": 1, "z": 0.9, "max_abs_force": np.nan} for r in rows]
    fig = map_heatmaps(pa.Table.from_pylist(rows + far, schema=schema()), am)
    panel = next(ax for ax in fig.axes if ax.images and ax.get_title().startswith("clearance"))
    shown = np.ma.compressed(panel.images[0].get_array())
    np.testing.assert_allclose(np.sort(shown), np.sort([1e3 * r["clearance_m"] for r in rows]))
    marks = [c for c in panel.collections if c.get_label() == "not reachable"]
    assert marks and len(marks[0].get_offsets()) == 2


def test_the_payload_capacity_keeps_its_clearance_from_the_scene(am):
    """The capacity's every optimization has the clearance rows: the pose that certifies the
    capacity at the strut's goal clears the strut, where the free one passes into it."""
    from assembler_pin.solver.capacity import payload_capacity

    goal = pin.SE3(np.eye(3), np.array([0.5, 0.0, 0.8]))
    scene = read_scene(STRUT)
    held, free = payload_capacity(am, goal, scene=scene), payload_capacity(am, goal)
    assert held.success and free.success
    assert clearance(am, held.plates, scene).min_distance >= am.config.clearance
    assert clearance(am, free.plates, scene).min_distance < 0
    assert held.capacity_kg <= free.capacity_kg * (1 + 1e-3)


def test_solve_capacity_with_a_scene_keeps_its_clearance(am, tmp_path, capsys):
    """``solve --capacity --scene``: the capacity is searched among the scene's obstacles (the
    API's capacity with the scene from the same start), below the free capacity where the
    strut binds."""
    from assembler_pin.solver.capacity import payload_capacity

    path = tmp_path / "strut.yaml"
    path.write_text(yaml.safe_dump(STRUT))
    argv = ["solve", "--goal", "0.5", "0", "0.8", "0", "0", "0", "--capacity", "--scene", str(path), "--json"]
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)
    goal = pin.SE3(np.eye(3), np.array([0.5, 0.0, 0.8]))
    scene = read_scene(STRUT)
    start = ap.solve(am, goal, scene=scene).optimized.plates
    held = payload_capacity(am, goal, start=start, scene=scene)
    free = payload_capacity(am, goal, start=start)
    assert doc["capacity"]["capacity_kg"] == pytest.approx(held.capacity_kg, rel=1e-9)
    assert held.capacity_kg < free.capacity_kg * (1 - 1e-3)


def test_the_slice_draws_each_obstacle_as_its_shadow_filled_where_the_plane_cuts_it(am, maps):
    """The obstacles of a scene on a map's slice (the y = 0 plane here): an axis-aligned box's
    shadow is its rectangle, a cylinder along y casts its disc, a sphere its disc; the plane
    cuts what spans y = 0 (filled), not what stands beside it (dashed). Every panel draws them."""
    from matplotlib.patches import Polygon

    from assembler_pin.collision.scene import scene_from_dict
    from assembler_pin.maps.pictures import map_heatmaps, obstacle_outlines

    scene = scene_from_dict(
        {
            "floor": {"z": 0.0},
            "obstacles": [
                {"name": "block", "box": {"size": [0.1, 0.2, 0.3], "pose": [0.6, 0.05, 0.4, 0, 0, 0]}},
                STRUT["obstacles"][0],
                {"name": "ball", "sphere": {"radius": 0.05, "center": [0.3, 0.2, 0.9]}},
            ],
        }
    )
    outlines = {name: (polygon, cut) for name, polygon, cut in obstacle_outlines(scene, "x", "z", 0.0)}
    block, cut = outlines["block"]
    assert cut and sorted(map(tuple, np.round(block, 12))) == [(0.55, 0.25), (0.55, 0.55), (0.65, 0.25), (0.65, 0.55)]
    for name, centre, radius, spans in (("lower strut", (0.36, 0.52), 0.015, True), ("ball", (0.3, 0.9), 0.05, False)):
        disc, cut = outlines[name]
        r = np.linalg.norm(disc - centre, axis=1)
        assert cut is spans and len(disc) == 48
        assert np.all(r <= radius + 1e-12) and np.all(r >= radius * np.cos(np.pi / 48))
    fig = map_heatmaps(_two_rows(read_map(maps[1])), am, scene="s.yaml", obstacles=scene)
    panels = [ax for ax in fig.axes if ax.images and ax.get_xlabel() == "x [m]"]
    assert len(panels) == 5
    for ax in panels:
        drawn = {p.get_gid(): p for p in ax.patches if isinstance(p, Polygon) and p.get_gid()}
        assert sorted(drawn) == sorted(f"obstacle {name}" for name in outlines)
        for name, (polygon, cut) in outlines.items():
            p = drawn[f"obstacle {name}"]
            np.testing.assert_allclose(p.get_xy()[:-1], polygon)  # matplotlib closes the path
            assert (p.get_fill() and p.get_facecolor()[3] > 0) is cut
        floor = [line for line in ax.lines if line.get_label() == "floor"]
        assert len(floor) == 1 and set(floor[0].get_ydata()) == {0.0}


def _two_rows(table):
    """The map's row of cells and a copy of it 0.1 m higher: a slice for the heatmaps."""
    import pyarrow as pa

    from assembler_pin.maps.store import schema

    rows = table.to_pylist()
    up = [r | {"cell": r["cell"] + len(rows), "iz": 1, "z": r["z"] + 0.1} for r in rows]
    return pa.Table.from_pylist(rows + up, schema=schema())


def test_cli_map_png_draws_the_scene(maps, tmp_path):
    """``map --scene ... --png``: the PNG holds the stone of the strut the slice cuts; the
    heatmaps of the same map drawn without the scene have none of it."""
    from matplotlib.image import imread

    from assembler_pin.common.palette import OBSTACLE
    from assembler_pin.maps.pictures import map_heatmaps
    from assembler_pin.plots.figures import save

    def stone(png) -> int:
        rgb = imread(str(png))[..., :3]
        return int((np.abs(rgb - np.asarray(OBSTACLE)).max(axis=2) < 2 / 255).sum())

    out = tmp_path / "m"
    grid = "x=0.45:0.5:2,y=0,z=0.8:0.85:2"
    args = ["map", "--grid", grid, "--workers", "0", "--no-progress", "--out", str(out), "--png", str(out) + ".png"]
    assert main([*args, "--scene", str(maps[0]), "--html", str(out) + ".html"]) == 0
    bare = save(map_heatmaps(read_map(out), ap.AssemblerModel.from_config()), tmp_path / "bare.png")
    assert stone(str(out) + ".png") > 20 and stone(bare) == 0, (stone(str(out) + ".png"), stone(bare))
    # the 3D page draws the strut among the cells, named in its legend
    html = (tmp_path / "m.html").read_text(encoding="utf-8")
    drawn = [c["path"] for c in page_commands(html) if c["type"] == "set_object"]
    assert any(p.startswith("/meshcat/assembler_obstacles/") for p in drawn) and "obstacles: lower strut" in html


def test_the_maps_guide_quotes_the_cell_beside_the_strut(am, maps):
    """docs/guides/maps.md's figures for the cell (0.5, 0, 0.8): its clearance from the strut
    and max|F| with the scene, and without it, max|F| and how far its pose passes into the strut."""
    from pathlib import Path

    scene_file, with_scene, free = maps
    strut = read_scene(scene_file)
    kept, loose = (next(r for r in read_map(d).to_pylist() if r["x"] == pytest.approx(0.5)) for d in (with_scene, free))
    into = clearance(am, _plates(loose), strut).min_distance
    guide = " ".join((Path(__file__).resolve().parents[2] / "docs/guides/maps.md").read_text(encoding="utf-8").split())
    assert (
        f"the cell (0.5, 0, 0.8) holds {1e3 * kept['clearance_m']:.4f} mm from the strut at max|F| "
        f"{kept['max_abs_force']:.2f} N; the same cell without a scene, {loose['max_abs_force']:.2f} N, "
        f"passes {-into:.4f} m into it"
    ) in guide
