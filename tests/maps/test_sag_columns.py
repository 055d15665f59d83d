"""A map's sag and weakest-stiffness columns: computed per cell, stored, pictured, never mixed
with the rows of a map without them."""

from __future__ import annotations

import json

import numpy as np
import pytest

import assembler_pin as ap
from assembler_pin.exceptions import MapError
from assembler_pin.maps import cells, parse_grid, run_map
from assembler_pin.maps.pictures import map_heatmaps, map_slice
from assembler_pin.maps.store import read_parts, schema, write_part
from assembler_pin.state import evaluate_state

NEW = ("sag_m", "weakest_stiffness_n_per_m")
POSE = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.24, 0.0, 0.0, 0.0, 1.0]  # two plates, x y z qx qy qz qw


def test_cell_stiffness_is_the_stiffness_of_the_pose(am, random_poses):
    for _, pa in random_poses[:2]:
        sag, weakest = cells.cell_stiffness(am, evaluate_state(am, pa))
        result = ap.stiffness(am, pa)
        assert sag == np.linalg.norm(result.sag_translation) and 0 < sag < 1e-2
        assert weakest == result.translational_stiffness.min() > 0


def test_cell_stiffness_of_a_singular_pose_is_nan(am):
    import pinocchio as pin

    turned = [pin.SE3.Identity()]
    for _ in range(am.n):
        turned.append(turned[-1] * pin.SE3(pin.exp3(np.array([0, 0, np.pi / 2])), np.array([0, 0, 0.24])))
    state = evaluate_state(am, turned)
    assert all(np.isnan(v) for v in cells.cell_stiffness(am, state))


def _rows(n: int) -> list[dict]:
    rows = []
    for k in range(n):
        ix, iz = k % 2, k // 2
        row = {c: 0.0 for c in cells.COLUMNS}
        row |= {"config": "default", "cell": k, "ix": ix, "iy": 0, "iz": iz, "io": 0, "reachable": True}
        row |= {"x": 0.2 + 0.1 * ix, "y": 0.0, "z": 0.8 + 0.1 * iz, "reason": "", "key": f"k{k}"}
        row |= {"capacity_binding": "", "binding": "", "sag_m": 1e-4 * (k + 1), "weakest_stiffness_n_per_m": 3e4 - k}
        row |= {"clearance_m": 0.02, "clearance_between": ["SP0 leg 0", "SP0 leg 1"], "plates_xyzquat": POSE}
        rows.append(row)
    return rows


def test_the_new_columns_are_stored_and_pictured(tmp_path, am):
    assert set(NEW) <= set(cells.COLUMNS)
    assert all(str(schema().field(c).type) == "double" for c in NEW)
    write_part(tmp_path, _rows(4), "t")
    [(_, table)] = read_parts(tmp_path)
    _, _, grid = map_slice(table)
    np.testing.assert_allclose(np.sort(grid["sag_m"].ravel()), [1e-4, 2e-4, 3e-4, 4e-4])
    assert np.nanmin(grid["weakest_stiffness_n_per_m"]) == 3e4 - 3
    fig = map_heatmaps(table, am)
    titles = [ax.get_title() for ax in fig.axes if ax.images]
    assert len(titles) == 5 and any("sag" in t for t in titles) and any("stiffness" in t for t in titles)


def test_a_part_without_the_new_columns_is_refused(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    old = [{c: v for c, v in row.items() if c not in NEW} for row in _rows(2)]
    fields = [f for f in schema() if f.name not in NEW]
    pq.write_table(pa.Table.from_pylist(old, schema=pa.schema(fields)), tmp_path / "part-old-000000000.parquet")
    with pytest.raises(MapError, match=r"missing.*sag_m"):
        read_parts(tmp_path)


def test_a_map_directory_of_the_old_columns_is_refused(tmp_path):
    """A manifest written before the columns (version 2, other solver settings) is another map."""
    grid = parse_grid("x=0.2,y=0.05,z=0.8")
    out = tmp_path / "m"
    out.mkdir()
    old_columns = tuple(c for c in cells.COLUMNS if c not in NEW)
    from assembler_pin.maps.store import manifest_for

    shas = {"default": cells.config_hash(ap.load_config())}
    manifest = manifest_for(grid, shas, "0" * 64) | {"version": 2}
    (out / "map.json").write_text(json.dumps(manifest))
    with pytest.raises(MapError, match=r"another map.*version.*solver settings"):
        run_map(grid, [("default", ap.load_config())], out, workers=0)
    assert cells.solver_hash() != _solver_hash_with(old_columns)


def _solver_hash_with(columns: tuple) -> str:
    saved = cells.COLUMNS
    try:
        cells.COLUMNS = columns
        return cells.solver_hash()
    finally:
        cells.COLUMNS = saved
