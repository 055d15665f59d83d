"""Payload capacity and capability maps: capacity against a bisection with the ordinary solve
and against independent statics at the capacity, the map engine serial, resumed and on a Dask
cluster of separate processes."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time

import numpy as np
import pinocchio as pin
import pytest

import assembler_pin as ap
from assembler_pin.bench.timing import random_reachable_plates
from assembler_pin.cli import main
from assembler_pin.maps import GridError, parse_grid, read_map, run_map
from assembler_pin.maps.pictures import map_heatmaps
from assembler_pin.solver import solve
from assembler_pin.solver.capacity import PayloadModels, payload_capacity

SMALL = "x=0.2:0.45:2,y=0.05,z=0.75:0.9:2"  # four reachable cells away from the symmetric axis


def test_forces_are_affine_in_the_payload_mass(am):
    _, plates = random_reachable_plates(am, np.random.default_rng(3))
    models = PayloadModels(am)
    f = {
        m: ap.solve_statics(ap.AssemblerModel.from_config({"payload": {"mass": m}}), plates).forces
        for m in (0.0, 1.0, 7.3)
    }
    np.testing.assert_allclose(f[7.3], f[0.0] + 7.3 * (f[1.0] - f[0.0]), atol=1e-9)
    np.testing.assert_allclose(ap.solve_statics(models.at(7.3), plates).forces, f[7.3], atol=1e-12)


def test_capacity_matches_a_bisection_with_the_ordinary_solve(am):
    goal = ap.scenario("orientation_transition").goal
    result = payload_capacity(am, goal)
    assert result.success and result.capacity_kg > am.config.payload.mass
    # independent: the statics of a model carrying exactly that payload, at the returned pose
    leg = am.config.leg
    at_cap = ap.evaluate_state(
        ap.AssemblerModel.from_config({"payload": {"mass": result.capacity_kg}}),
        result.plates,
        goal=goal,
        tolerance=ap.constraints.GoalTolerance(1e-6, 1e-6),
    )
    assert at_cap.feasible or all(v.kind in ("tension", "compression") for v in at_cap.violations)
    peak = max(at_cap.forces.max() / leg.max_tension, -at_cap.forces.min() / leg.max_compression)
    assert peak == pytest.approx(1.0, abs=1e-6)  # one leg exactly at its limit
    # the bisection on the payload mass with the ordinary solve
    lo, hi = am.config.payload.mass, 3 * result.capacity_kg
    while hi - lo > 0.002 * lo:
        mid = 0.5 * (lo + hi)
        lo, hi = (
            (mid, hi) if solve(ap.AssemblerModel.from_config({"payload": {"mass": mid}}), goal).success else (lo, mid)
        )
    assert result.capacity_kg == pytest.approx(0.5 * (lo + hi), rel=0.01)
    assert "array(" not in repr(result)


def test_unreachable_goal_has_no_capacity(am):
    result = payload_capacity(am, pin.SE3(np.eye(3), np.array([0.0, 0.0, 1.7])))
    assert not result.success and np.isnan(result.capacity_kg) and "no valid pose" in result.message


def test_grid_specs():
    grid = parse_grid("x=0:0.3:4, z=0.8", "0 0 0; 0 30 0")
    assert grid.shape == (4, 1, 1, 2) and len(grid) == 8 and grid.y == (0.0,)
    cells = grid.cells()
    assert [c.id for c in cells] == list(range(8)) and cells[3].index == (1, 0, 0, 1)
    assert cells[3].rotation == pytest.approx((0.0, np.deg2rad(30.0), 0.0))
    assert cells[3].goal().translation == pytest.approx([0.1, 0.0, 0.8])
    for bad, match in (
        ("w=1", "AXIS"),
        ("x=0:1", "START:STOP:COUNT"),
        ("x=0:1:0", "COUNT"),
        ("x=1,x=2", "twice"),
        ("", "empty"),
    ):
        with pytest.raises(GridError, match=match):
            parse_grid(bad)
    with pytest.raises(GridError, match="three numbers"):
        parse_grid("x=0", "0 30")


def test_map_is_resumable_and_loses_no_finished_cell(tmp_path):
    cfg = ap.load_config()
    grid = parse_grid(SMALL)
    full = run_map(grid, [("default", cfg)], tmp_path / "a", workers=0, batch_size=1)
    assert full.computed == 4 and full.batches == 4 and len(list((tmp_path / "a").glob("part-*.parquet"))) == 4
    whole = read_map(tmp_path / "a")
    # a run stopped after three batches: the fourth part is missing; a rerun computes only it
    shutil.copytree(tmp_path / "a", tmp_path / "b")
    sorted((tmp_path / "b").glob("part-*.parquet"))[-1].unlink()
    again = run_map(grid, [("default", cfg)], tmp_path / "b", workers=0)
    assert (again.computed, again.skipped) == (1, 3)
    numbers = [c for c in whole.column_names if not c.endswith("time_s")]  # timings differ run to run
    assert read_map(tmp_path / "b").select(numbers).equals(whole.select(numbers))
    # every reachable cell's max|F| is that of the ordinary solve of its goal
    am = ap.AssemblerModel.from_config(cfg)
    row = whole.slice(0, 1).to_pylist()[0]
    direct = solve(am, pin.SE3(np.eye(3), np.array([row["x"], row["y"], row["z"]])))
    assert row["reachable"] and row["max_abs_force"] == pytest.approx(direct.optimized.max_abs_force, rel=1e-9)
    # and its sag and weakest stiffness those of the stiffness at that pose
    stiff = ap.stiffness(am, direct.optimized.plates)
    assert row["sag_m"] == pytest.approx(float(np.linalg.norm(stiff.sag_translation)), rel=1e-6)
    assert row["weakest_stiffness_n_per_m"] == pytest.approx(stiff.weakest_stiffness, rel=1e-6)
    fig = map_heatmaps(whole, am)
    assert len([ax for ax in fig.axes if ax.images]) == 5


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


DASK = shutil.which("dask") or os.path.join(os.path.dirname(sys.executable), "dask")


@pytest.mark.skipif(not os.path.exists(DASK), reason="the dask command is not installed")
def test_map_on_a_dask_cluster_of_separate_processes_equals_the_serial_run(tmp_path):
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    dask = DASK
    logs = open(tmp_path / "cluster.log", "w")  # closed in finally
    procs = [
        subprocess.Popen(
            [dask, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
            stdout=logs,
            stderr=subprocess.STDOUT,
        )
    ]
    try:
        for _ in range(2):
            procs.append(
                subprocess.Popen(
                    [dask, "worker", address, "--nthreads", "1", "--nworkers", "1", "--no-dashboard"],
                    stdout=logs,
                    stderr=subprocess.STDOUT,
                )
            )
        from distributed import Client

        with Client(address, timeout="60s") as client:
            client.wait_for_workers(2, timeout=120)
        grid = parse_grid(SMALL)
        cfg = ap.load_config()
        remote = run_map(grid, [("default", cfg)], tmp_path / "remote", scheduler=address, batch_size=1)
        serial = run_map(grid, [("default", cfg)], tmp_path / "serial", workers=0)
        assert remote.workers == 2 and remote.computed == serial.computed == 4
        a, b = read_map(tmp_path / "remote"), read_map(tmp_path / "serial")
        for column in ("cell", "reachable", "binding", "capacity_binding"):
            assert a.column(column).to_pylist() == b.column(column).to_pylist(), column
        for column in ("max_abs_force", "capacity_kg"):
            np.testing.assert_allclose(a.column(column).to_pylist(), b.column(column).to_pylist(), rtol=1e-9)
    finally:
        for proc in reversed(procs):
            proc.terminate()
        for proc in procs:
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()
        logs.close()
        time.sleep(0.1)


def test_cli_map_and_its_errors(tmp_path, capsys):
    assert (
        main(
            [
                "map",
                "--grid",
                "x=0.3,y=0.05,z=0.8:0.85:2",
                "--workers",
                "0",
                "--out",
                str(tmp_path / "m"),
                "--no-progress",
                "--json",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert '"computed": 2' in out and '"reachable": 2' in out
    assert main(["map", "--grid", "q=1", "--out", str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "AXIS" in err[0]
    assert main(["solve", "--goal", "0.2", "0.1", "0.85", "0.5", "0.5", "0.5", "--capacity", "--json"]) == 0
    assert '"capacity_kg"' in capsys.readouterr().out
