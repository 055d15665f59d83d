"""Capability maps held to the package's contract: a rerun reuses a cell only when its goal, its
configuration's content and the solver settings are unchanged; parts are whole or refused in
one line; counts are bounded before anything is allocated; SPECs, scheduler addresses and API
arguments are read strictly; Ctrl-C leaves only whole parts; progress only on a terminal.

Cells far out of reach (x = 3 m) are answered in milliseconds: the tests use them, serially.
"""

from __future__ import annotations

import inspect
import math
import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import assembler_pin as ap
from assembler_pin.cli import main
from assembler_pin.config.bounds import BOUNDS
from assembler_pin.exceptions import AssemblerError, GridError, MapError
from assembler_pin.maps import Grid, parse_grid, parse_orientations, read_map, run_map
from assembler_pin.maps import cells as map_cells
from assembler_pin.maps import cluster as map_cluster

FAR = "x=3:3.2:2,y=0,z=0.8"  # two cells out of reach: answered at once
FUZZ = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
ROOT = Path(__file__).resolve().parents[2]


def _run(out: Path, spec: str = FAR, cfg=None, **kw):
    return run_map(parse_grid(spec), [("default", cfg or ap.load_config())], out, workers=0, **kw)


def _one_line(exc: pytest.ExceptionInfo) -> str:
    text = str(exc.value)
    assert "\n" not in text and len(text) < 400 and "Traceback" not in text
    return text


# ------------------------------------------------------------------ item 4: what a rerun reuses


def test_a_rerun_of_the_same_map_reuses_every_cell(tmp_path):
    first = _run(tmp_path / "m")
    again = _run(tmp_path / "m")
    assert (first.computed, first.skipped) == (2, 0) and (again.computed, again.skipped) == (0, 2)
    rows = read_map(tmp_path / "m").to_pylist()
    assert [r["x"] for r in rows] == [3.0, 3.2] and not any(r["reachable"] for r in rows)
    assert all(len(r["key"]) == 32 for r in rows)


def test_another_grid_in_the_same_directory_is_refused(tmp_path):
    _run(tmp_path / "m")
    with pytest.raises(MapError) as exc:
        _run(tmp_path / "m", "x=3.5:3.7:2,y=0,z=0.8")  # same cell ids, other goals
    text = _one_line(exc)
    assert "another map" in text and "grid" in text and "--out" in text and "delete" in text
    assert read_map(tmp_path / "m").column("x").to_pylist() == [3.0, 3.2]  # nothing was mixed in


def test_an_edited_config_in_the_same_directory_is_refused(tmp_path):
    _run(tmp_path / "m")
    heavier = ap.load_config().replace(payload=ap.config.PayloadConfig(mass=40.0))
    with pytest.raises(MapError) as exc:
        _run(tmp_path / "m", cfg=heavier)
    assert "configuration 'default' content" in _one_line(exc)


def test_other_solver_settings_in_the_same_directory_are_refused(tmp_path, monkeypatch):
    _run(tmp_path / "m")
    monkeypatch.setitem(map_cells.CAPACITY_OPTIONS, "rtol", 2e-3)
    with pytest.raises(MapError) as exc:
        _run(tmp_path / "m")
    assert "solver settings" in _one_line(exc)


def test_a_row_of_another_map_copied_in_is_refused(tmp_path):
    _run(tmp_path / "a", cfg=ap.load_config().replace(payload=ap.config.PayloadConfig(mass=40.0)))
    _run(tmp_path / "b")
    for part in (tmp_path / "b").glob("part-*.parquet"):
        if pq.read_table(part).column("cell").to_pylist() == [1]:
            part.unlink()
    stranger = next(
        p for p in (tmp_path / "a").glob("part-*.parquet") if pq.read_table(p).column("cell").to_pylist() == [1]
    )
    (tmp_path / "b" / stranger.name).write_bytes(stranger.read_bytes())
    with pytest.raises(MapError) as exc:
        _run(tmp_path / "b")
    assert stranger.name in _one_line(exc) and "another map" in str(exc.value)


def test_parts_without_a_manifest_are_refused(tmp_path):
    _run(tmp_path / "m")
    (tmp_path / "m" / "map.json").unlink()
    with pytest.raises(MapError, match="without a manifest") as exc:
        _run(tmp_path / "m")
    _one_line(exc)


def _damage(part: Path, how: str) -> None:
    if how == "garbage":
        part.write_bytes(b"PAR1 this is not parquet")
    elif how == "empty":
        part.write_bytes(b"")
    elif how == "truncated":
        part.write_bytes(part.read_bytes()[:40])
    elif how == "columns":
        pq.write_table(pa.table({"a": [1]}), part)
    elif how == "types":
        table = pq.read_table(part)
        pq.write_table(table.set_column(1, "cell", pa.array([str(c) for c in table.column("cell").to_pylist()])), part)
    elif how == "no rows":
        pq.write_table(pq.read_table(part).slice(0, 0), part)


@pytest.mark.parametrize("how", ["garbage", "empty", "truncated", "columns", "types", "no rows"])
def test_a_damaged_part_is_named_in_one_line(tmp_path, how, capsys):
    _run(tmp_path / "m")
    part = sorted((tmp_path / "m").glob("part-*.parquet"))[0]
    _damage(part, how)
    for call in (lambda: read_map(tmp_path / "m"), lambda: _run(tmp_path / "m")):
        with pytest.raises(MapError) as exc:
            call()
        assert part.name in _one_line(exc) and "delete it" in str(exc.value)
    assert main(["map", "--grid", FAR, "--workers", "0", "--out", str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and part.name in err[0]


def test_a_part_is_written_atomically(tmp_path, monkeypatch):
    real = pq.write_table

    def killed_mid_write(table, where, *args, **kwargs):
        Path(where).write_bytes(b"PAR1 half a file")
        raise KeyboardInterrupt

    _run(tmp_path / "m", "x=3,y=0,z=0.8")
    monkeypatch.setattr(pq, "write_table", killed_mid_write)
    with pytest.raises(KeyboardInterrupt):
        _run(tmp_path / "n")
    monkeypatch.setattr(pq, "write_table", real)
    assert sorted(os.listdir(tmp_path / "n")) == ["map.json"]  # no partial part, no temporary file
    assert _run(tmp_path / "n").computed == 2


# ------------------------------------------------------------------ item 7: bounds before allocation


@pytest.mark.parametrize(
    "spec, key",
    [
        ("x=0:1:1000000000000", "map.axis_count"),
        ("x=0:1:10001", "map.axis_count"),
        ("x=0:1:10000,y=0:1:10000", "map.cells"),
        ("x=0:1:300,y=0:1:300,z=0:1:300", "map.cells"),
    ],
)
def test_grid_counts_are_bounded_before_the_axes_are_built(spec, key, monkeypatch):
    def no_allocation(*args, **kwargs):
        raise AssertionError("an axis array was built")

    monkeypatch.setattr(np, "linspace", no_allocation)
    t0 = time.perf_counter()
    with pytest.raises(GridError, match=r"must be an integer in \[1, ") as exc:
        parse_grid(spec)
    assert time.perf_counter() - t0 < 0.5 and BOUNDS[key].why in _one_line(exc)


def test_orientation_and_config_counts_are_bounded():
    many = "; ".join(f"0 0 {k * 0.01:.2f}" for k in range(10_001))
    with pytest.raises(GridError, match="orientations"):
        parse_orientations(many)
    with pytest.raises(GridError, match="map's number of cells"):
        parse_grid("x=0:1:1000,y=0:1:1000", configs=11)
    with pytest.raises(GridError, match="orientations"):
        Grid((0.0,), (0.0,), (0.0,), ((0.0, 0.0, 0.0),) * 10_001)


def test_cli_bounds_workers_and_batch_size(tmp_path, capsys):
    for option, value in (
        ("--workers", "100000"),
        ("--workers", "-1"),
        ("--batch-size", "0"),
        ("--batch-size", "10001"),
    ):
        assert main(["map", "--grid", FAR, option, value, "--out", str(tmp_path / "m")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and option in err[0] and "[" in err[0]
    assert not (tmp_path / "m").exists()  # refused before anything was written


# ------------------------------------------------------------------ item 8: strict SPEC readers

_TOKENS = [
    "0",
    "0.5",
    "-1e-3",
    "3",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e400",
    "1_000",
    "１",
    "٣",
    "0x10",
    "",
    "1e12",
    "2.5",
    "+3",
    "1e3",
    "²",
    "0:1:2",
    ":",
    "1.2.3",
    "1e",
    ".",
    "-",
    "10000",
    "10001",
]
_AXES = ["x", "y", "z", "X", "w", "xy", "ｘ", "", "x "]


def _check_grid_or_refusal(text: str, orientations: str | None = None) -> None:
    try:
        grid = parse_grid(text, orientations)
    except GridError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 300
        return
    values = [*grid.x, *grid.y, *grid.z, *(v for r in grid.orientations for v in r)]
    assert all(math.isfinite(v) for v in values) and 1 <= len(grid) <= BOUNDS["map.cells"].high
    for axis in ("x", "y", "z"):
        assert 1 <= len(getattr(grid, axis)) <= BOUNDS["map.axis_count"].high
    assert len(set(grid.orientations)) == len(grid.orientations)


@FUZZ
@given(st.text(max_size=60))
def test_any_text_is_a_grid_or_a_one_line_refusal(text):
    _check_grid_or_refusal(text)
    _check_grid_or_refusal("x=0", text)


@FUZZ
@given(
    st.lists(st.tuples(st.sampled_from(_AXES), st.lists(st.sampled_from(_TOKENS), min_size=1, max_size=3)), max_size=4)
)
def test_hostile_grid_specs_are_refused_in_one_line(items):
    spec = ",".join(f"{a}={':'.join(t)}" for a, t in items)
    _check_grid_or_refusal(spec)


@pytest.mark.parametrize(
    "spec",
    [
        "x=nan",
        "x=inf",
        "x=1e400",
        "x=1_000",
        "x=１",
        "x=٣",
        "x=0x10",
        "x=0:1:2.5",
        "x=0:1:1e3",
        "x=0:1:1_0",
        "x=0:1:-2",
        "x=0:1:0",
        "x=1,X=2",
        "w=1",
        "x=1,,z=2",
        "x=1,",
        ",x=1",
        "x=0.5:0.5:3",
        "x=2000",
        "x=0:1:2:3",
        "x=\u00a01",
        "x==1",
    ],
)
def test_each_hostile_grid_spec_is_refused(spec):
    with pytest.raises(GridError) as exc:
        parse_grid(spec)
    _one_line(exc)


@pytest.mark.parametrize(
    "text",
    [
        "0 0 nan",
        "0 0 inf",
        "0 0",
        "0 0 0 0",
        "0 0 0;;0 30 0",
        "0 0 0;",
        "0 0 0; 0 0 0",
        "0 0 ٣",
        "0 0 1_0",
        "0 0 400",
        "a b c",
    ],
)
def test_each_hostile_orientation_spec_is_refused(text):
    with pytest.raises(GridError) as exc:
        parse_orientations(text)
    _one_line(exc)


def test_valid_specs_give_the_documented_values():
    grid = parse_grid("x=0.2:0.7:6, z=-1e-1", "0 0 0; 0 30 0")
    assert grid.x == pytest.approx([0.2, 0.3, 0.4, 0.5, 0.6, 0.7]) and grid.y == (0.0,) and grid.z == (-0.1,)
    assert grid.orientations[1] == pytest.approx((0.0, math.pi / 6, 0.0))
    assert grid.cell(7).position == pytest.approx((0.5, 0.0, -0.1)) and grid.cell(7).index == (3, 0, 0, 1)


@pytest.mark.parametrize(
    "address",
    [
        "foo://h:1",
        "http://h:8786",
        "tcp://h",
        "tcp://h:0",
        "tcp://h:99999",
        "tcp://h:1/x",
        "",
        " tcp://h:1",
        "tcp://hé:1",
        "tcp://-h:1",
        "tcp://h:1\n",
    ],
)
def test_scheduler_addresses_are_refused_before_connecting(tmp_path, address, capsys, monkeypatch):
    monkeypatch.setattr(map_cluster, "client_for", lambda *a: pytest.fail("a connection was tried"))
    with pytest.raises(MapError) as exc:
        run_map(parse_grid(FAR), [("d", ap.load_config())], tmp_path / "m", scheduler=address)
    _one_line(exc)
    assert main(["map", "--grid", FAR, "--scheduler", address, "--out", str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--scheduler" in err[0]


@pytest.mark.parametrize(
    "address",
    [
        "tcp://10.0.0.5:8786",
        "10.0.0.5:8786",
        "tls://sched.example.org:8786",
        "ws://h:1",
        "wss://h:1",
        "ucx://h:1",
        "tcp://[::1]:8786",
        "inproc://10.0.0.5/1234/1",
    ],
)
def test_dask_addresses_are_accepted(address):
    assert map_cluster.check_scheduler(address) == address


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_an_unreachable_scheduler_is_one_line_within_the_timeout(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(map_cluster, "CONNECT_TIMEOUT_S", 1.0)
    address = f"tcp://127.0.0.1:{_free_port()}"
    t0 = time.perf_counter()
    assert main(["map", "--grid", FAR, "--scheduler", address, "--out", str(tmp_path / "m")]) == 2
    assert time.perf_counter() - t0 < 15
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot reach the Dask scheduler" in err[0]


def test_a_scheduler_without_workers_is_one_line_not_a_hang(tmp_path, monkeypatch):
    from distributed import LocalCluster

    monkeypatch.setattr(map_cluster, "WORKERS_TIMEOUT_S", 1.0)
    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        assert cluster.scheduler_address.startswith("inproc://")
        t0 = time.perf_counter()
        with pytest.raises(MapError, match="has no worker") as exc:
            run_map(parse_grid(FAR), [("d", ap.load_config())], tmp_path / "m", scheduler=cluster.scheduler_address)
        assert time.perf_counter() - t0 < 15
    _one_line(exc)


# ------------------------------------------------------------------ item 9: API arguments


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"workers": -1}, "workers"),
        ({"workers": True}, "workers"),
        ({"workers": 2.5}, "workers"),
        ({"workers": "2"}, "workers"),
        ({"workers": 10**6}, "workers"),
        ({"batch_size": 0}, "batch_size"),
        ({"batch_size": -3}, "batch_size"),
        ({"batch_size": False}, "batch_size"),
        ({"batch_size": 1.5}, "batch_size"),
        ({"scheduler": 8786}, "scheduler"),
        ({"progress": True}, "progress"),
        ({"progress": "yes"}, "progress"),
    ],
)
def test_run_map_refuses_bad_arguments_naming_them(tmp_path, kwargs, name):
    with pytest.raises(MapError, match=name) as exc:
        run_map(parse_grid(FAR), [("d", ap.load_config())], tmp_path / "m", **kwargs)
    _one_line(exc)
    assert not (tmp_path / "m").exists()


@pytest.mark.parametrize(
    "configs",
    [
        ap.load_config(),
        [ap.load_config()],
        [("a", {"payload": {"mass": 1}})],
        [],
        "default",
        None,
        [("a", ap.load_config()), ("a", ap.load_config())],
        [("", ap.load_config())],
        [(3, ap.load_config())],
    ],
)
def test_run_map_refuses_bad_configs(tmp_path, configs):
    with pytest.raises(MapError, match="configs") as exc:
        run_map(parse_grid(FAR), configs, tmp_path / "m", workers=0)
    _one_line(exc)


def test_run_map_refuses_a_file_as_out_and_a_grid_that_is_not_one(tmp_path):
    (tmp_path / "f").write_text("x")
    with pytest.raises(MapError, match=r"out .* is a file"):
        run_map(parse_grid(FAR), [("d", ap.load_config())], tmp_path / "f", workers=0)
    with pytest.raises(MapError, match="grid must be a Grid"):
        run_map(FAR, [("d", ap.load_config())], tmp_path / "m", workers=0)
    for bad in ((math.nan,), (), ("0.1",), (True,), (1e4,)):
        with pytest.raises(GridError):
            Grid(bad, (0.0,), (0.8,))
    assert issubclass(MapError, AssemblerError) and issubclass(GridError, AssemblerError)


# ------------------------------------------------------------------ item 11: interrupts

_INTERRUPTIBLE = """
import sys, time
import assembler_pin as ap
from assembler_pin.maps import cells, parse_grid, run_map

real = cells.compute_cell


def slow_second_cell(models, cell, name="", scene=None):
    if cell.id == 1:
        time.sleep(120)  # interrupted here
    return real(models, cell, name, scene)


cells.compute_cell = slow_second_cell
if __name__ == "__main__":
    if "{cli}" == "yes":
        from assembler_pin.cli import main

        sys.exit(main(["map", "--grid", "{spec}", "--workers", "{workers}", "--batch-size", "1", "--out", sys.argv[1]]))
    try:
        run_map(parse_grid("{spec}"), [("default", ap.load_config())], sys.argv[1], workers={workers}, batch_size=1)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        sys.exit(130)
"""


def _interrupt(tmp_path: Path, script: str, ready, limit: float = 90.0) -> tuple[subprocess.CompletedProcess, float]:
    """Run ``script``, send SIGINT to its process group (as Ctrl-C does) once ``ready()``."""
    (tmp_path / "run.py").write_text(script)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, str(tmp_path / "run.py"), str(tmp_path / "m")],
        cwd=tmp_path,
        env=env,
        start_new_session=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        t0 = time.monotonic()
        while not ready() and proc.poll() is None and time.monotonic() - t0 < limit:
            time.sleep(0.1)
        assert proc.poll() is None, proc.communicate()[1][-2000:]
        os.killpg(proc.pid, signal.SIGINT)
        t1 = time.monotonic()
        out, err = proc.communicate(timeout=60)
        return subprocess.CompletedProcess(proc.args, proc.returncode, out, err), time.monotonic() - t1
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def test_ctrl_c_in_a_serial_map_leaves_whole_parts_and_a_rerun_resumes(tmp_path):
    out = tmp_path / "m"
    script = textwrap.dedent(_INTERRUPTIBLE).format(spec=FAR, workers=0, cli="no")
    done, took = _interrupt(tmp_path, script, lambda: any(out.glob("part-*.parquet")))
    assert done.returncode == 130 and done.stderr.strip() == "interrupted", done.stderr[-2000:]
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith("part-")) == ["map.json"]
    assert read_map(out).column("cell").to_pylist() == [0] and took < 10
    again = _run(out)
    assert (again.computed, again.skipped) == (1, 1)


REACHABLE = "x=0.3,y=0.05,z=0.8:0.85:2"  # two cells of seconds each


def _ignores_sigint(pid: int) -> bool:
    """Whether a process ignores SIGINT (the map's process does while its workers start)."""
    line = next(x for x in Path(f"/proc/{pid}/status").read_text().splitlines() if x.startswith("SigIgn:"))
    return bool(int(line.split()[1], 16) & (1 << (signal.SIGINT - 1)))


@pytest.mark.slow
def test_ctrl_c_stops_the_local_dask_cluster_at_once(tmp_path):
    psutil = pytest.importorskip("psutil")
    pytest.importorskip("distributed")
    script = textwrap.dedent(_INTERRUPTIBLE).format(spec=REACHABLE, workers=1, cli="no")
    seen: dict = {}

    def ready() -> bool:
        proc = seen.setdefault(
            "proc", next(p for p in psutil.process_iter(["cmdline"]) if "run.py" in " ".join(p.info["cmdline"] or []))
        )
        seen.setdefault("children", set()).update(proc.children(recursive=True))
        if not (tmp_path / "m" / "map.json").exists():
            return False
        start = seen.setdefault("manifest", time.monotonic())
        workers = [c for c in seen["children"] if "spawn_main" in _cmdline(c)]
        return bool(workers) and time.monotonic() - start > 1 and not _ignores_sigint(proc.pid)

    done, took = _interrupt(tmp_path, script, ready, limit=120)
    assert done.returncode == 130 and done.stderr.strip() == "interrupted", done.stderr[-2000:]
    assert took < 15
    time.sleep(1)
    alive = [p for p in seen["children"] if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
    assert not alive and not any((tmp_path / "m").glob(".*.tmp"))
    assert read_map(tmp_path / "m").num_rows <= 2


def _app_handles_interrupts() -> bool:
    from assembler_pin.cli import app

    return "KeyboardInterrupt" in inspect.getsource(app)


@pytest.mark.skipif(not _app_handles_interrupts(), reason="the CLI's interrupt handler is not in cli/app.py")
def test_ctrl_c_in_the_map_command_is_one_line_and_exit_130(tmp_path):
    out = tmp_path / "m"
    script = textwrap.dedent(_INTERRUPTIBLE).format(spec=FAR, workers=0, cli="yes")
    done, _ = _interrupt(tmp_path, script, lambda: any(out.glob("part-*.parquet")))
    assert done.returncode == 130 and len(done.stderr.strip().splitlines()) == 1, done.stderr[-2000:]
    assert read_map(out).num_rows == 1


# ------------------------------------------------------------------ item 12: progress


def test_run_map_reports_progress_through_its_callback(tmp_path):
    calls: list[tuple[int, int, str]] = []
    run = run_map(
        parse_grid("x=3:3.3:4,y=0,z=0.8"),
        [("d", ap.load_config())],
        tmp_path / "m",
        workers=0,
        batch_size=1,
        progress=lambda *a: calls.append(a),
    )
    assert run.computed == 4 and [c[:2] for c in calls] == [(0, 4), (1, 4), (2, 4), (3, 4), (4, 4)]


class _Terminal:
    def __init__(self) -> None:
        self.text = ""

    def write(self, s: str) -> int:
        self.text += s
        return len(s)

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return True


def test_the_map_command_shows_progress_only_on_a_terminal_unless_quiet(tmp_path, capsys, monkeypatch):
    assert main(["map", "--grid", FAR, "--workers", "0", "--out", str(tmp_path / "a")]) == 0
    assert capsys.readouterr().err == ""  # not a terminal: no progress text at all
    for argv, shown in ((["map"], True), (["-q", "map"], False), (["map", "--no-progress"], False)):
        terminal = _Terminal()
        monkeypatch.setattr(sys, "stderr", terminal)
        out = str(tmp_path / f"t{len(argv)}{shown}")
        assert main([*argv, "--grid", FAR, "--workers", "0", "--out", out]) == 0
        monkeypatch.undo()
        assert ("map: 2/2 cells" in terminal.text) is shown, terminal.text


# ------------------------------------------------------------------ the exit status of a map


def test_a_map_of_unreachable_cells_is_an_answer_exit_0(tmp_path, capsys):
    assert main(["map", "--grid", FAR, "--workers", "0", "--out", str(tmp_path / "m"), "--json"]) == 0
    out = capsys.readouterr().out
    assert '"computed": 2' in out and '"reachable": 0' in out


def test_png_of_a_map_without_two_axes_is_refused_before_computing(tmp_path, capsys):
    assert (
        main(["map", "--grid", FAR, "--workers", "0", "--out", str(tmp_path / "m"), "--png", str(tmp_path / "m.png")])
        == 2
    )
    assert "--png" in capsys.readouterr().err and not (tmp_path / "m").exists()


def _cmdline(process) -> str:
    """A process's command line, "" once it has exited (a zombie or gone: no line to read)."""
    import psutil

    try:
        return " ".join(process.cmdline())
    except psutil.Error:
        return ""
