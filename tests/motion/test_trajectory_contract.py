"""Trajectories and waypoint files held to the package's contract.

Every written row is recomputed independently (stack FK from the neutral home guess, the
design-based leg lengths and limits of ``tests/checks.py``, ``solve_statics``); files are
attacked by truncation, edits and hostile content; bounds are checked before any work.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time

import numpy as np
import pinocchio as pin
import pytest
from checks import kinematic_problems, sp_legs
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from assembler_pin import AssemblerModel, solve_statics, stack_forward_kinematics
from assembler_pin.cli import main
from assembler_pin.exceptions import PathError, PoseError, SimulationError, TrajectoryError
from assembler_pin.motion import EEPath, PlanOptions, plan_path, read_waypoints
from assembler_pin.motion.result import verify_trajectory
from assembler_pin.motion.rows import check_trajectory
from assembler_pin.motion.timing import plan_trajectory, read_trajectory, time_parametrize, trajectory_states
from assembler_pin.motion.trajfile import VERSION, rows_digest

HYPO = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@pytest.fixture(scope="module")
def short(am):
    """A short planned motion from the home pose: 3 cm along x, 1 cm down, 3.4° about x."""
    home = am.home[-1]
    goal = pin.SE3(
        home.rotation @ pin.exp3(np.array([0.06, 0.0, 0.0])), home.translation + np.array([0.03, 0.0, -0.01])
    )
    plan = plan_path(am, EEPath.between(home, goal), start=am.home)
    assert plan.success and len(plan.states) >= 4
    return plan


@pytest.fixture(scope="module")
def traj(am, short):
    return time_parametrize(am, short, rate=20.0)


def _prefix(plan, m):
    return dataclasses.replace(
        plan, states=plan.states[:m], parameters=plan.parameters[:m], solve_times_s=plan.solve_times_s[:m]
    )


def _rows_match_fresh_fk_and_statics(am, back) -> None:
    """Every row: FK of its lengths from the neutral guess gives its EE (1e-9 m / rad), the
    design lengths of those plates are its lengths, its max|F| is their statics (1e-6 N)."""
    cfg, leg = am.config, am.config.leg
    for k in range(len(back.times)):
        fk = stack_forward_kinematics(am, back.lengths[k], base=am.home[0])  # default guess: home
        assert fk.success, k
        pa = fk.plates
        for j in range(am.n):
            lengths = sp_legs(cfg, j, pa.R[j], pa.p[j], pa.R[j + 1], pa.p[j + 1])[0]
            np.testing.assert_allclose(lengths, back.lengths[k, j], atol=1e-9)
        assert np.linalg.norm(pa.p[-1] - back.ee[k, :3]) <= 1e-9, (k, back.times[k])
        assert np.linalg.norm(pin.log3(pin.exp3(back.ee[k, 3:]).T @ pa.R[-1])) <= 1e-9, k
        forces = solve_statics(am, pa).forces
        assert abs(np.abs(forces).max() - back.max_abs_force[k]) <= 1e-6, k
        assert kinematic_problems(cfg, pa, tol=1e-9) == [], k
        assert forces.max() <= leg.max_tension and forces.min() >= -leg.max_compression


# ---------------------------------------------------------------------- 1. rows vs their lengths
@pytest.mark.parametrize(
    ("rate", "samples"), [(10.0, None), (50.0, None), pytest.param(1000.0, 2, marks=pytest.mark.slow)]
)
def test_every_written_row_equals_fresh_fk_and_statics_of_its_lengths(am, short, tmp_path, rate, samples):
    plan = short if samples is None else _prefix(short, samples)
    out = time_parametrize(am, plan, rate=rate)
    assert len(out.times) >= rate * out.duration
    for name in ("t.csv", "t.json"):
        back = read_trajectory(out.write(tmp_path / name))
        assert np.array_equal(back.lengths, out.lengths) and np.array_equal(back.ee, out.ee)
    _rows_match_fresh_fk_and_statics(am, back)


@pytest.mark.slow
def test_readme_chain_plan_simulate_view(tmp_path, monkeypatch, capsys):
    pytest.importorskip("mujoco")
    monkeypatch.chdir(tmp_path)
    assert main(["plan", "--to", "0.2", "0.1", "0.85", "0.5", "0.5", "0.5", "--out", "traj.csv"]) == 0
    assert main(["simulate", "--trajectory", "traj.csv"]) == 0
    assert main(["view", "--trajectory", "traj.csv", "--html", "page.html"]) == 0
    captured = capsys.readouterr()
    assert "followed: yes" in captured.out and (tmp_path / "page.html").stat().st_size > 0
    assert "Error" not in captured.err


# ---------------------------------------------------------------------- 2. a failed plan
def test_a_failed_plan_keeps_its_valid_prefix_and_says_so(am, tmp_path):
    goal = pin.SE3(np.eye(3), np.array([0.0, 0.0, 1.6]))  # above the stack's reach
    t0 = time.perf_counter()
    motion = plan_trajectory(
        am,
        EEPath.between(am.home[-1], goal),
        start=am.home,
        options=PlanOptions(position_step=0.02, max_refinements=1),
        rate=20.0,
    )
    took = time.perf_counter() - t0
    assert not motion.success and "no valid sample" in motion.reason and not motion.complete
    doc = motion.to_dict()
    assert doc["success"] is False and doc["complete"] is False and doc["path_reached"] < 1.0
    traj = motion.trajectory
    assert traj is not None and traj.meta["complete"] is False and traj.meta["reason"] == motion.reason
    back = read_trajectory(traj.write(tmp_path / "prefix.csv"))
    assert back.meta["complete"] is False and "no valid sample" in back.meta["reason"]
    _rows_match_fresh_fk_and_statics(am, back)  # every written row valid, independently
    # the prefix ends at the last valid planned sample (the time law is rest to rest)
    np.testing.assert_allclose(back.lengths[-1], motion.plan.states[-1].leg_lengths, atol=1e-12)
    assert took < 60  # planned once: a failed plan is not planned again with half steps


def test_a_vertical_plan_from_home_ends_at_the_stacks_full_height(am):
    """Straight up from the home pose, past the reach: the plan goes on until the legs are at
    their longest, not a few centimetres above home. The bound is geometry alone: a level
    platform whose six legs are all L long stands sqrt(L^2 - c^2) tall, with c the chord
    between a leg's two ends (60 deg - spacing apart on the node circle); with the plan's
    margin, L = max_length - limit_margin. No sample can be above n of those, and the plan
    must end within one position step of it."""
    cfg, opts = am.config, PlanOptions()
    chord = 2 * cfg.plate.node_radius * math.sin(math.radians(60 - cfg.plate.node_spacing_deg) / 2)
    longest = cfg.leg.max_length - opts.limit_margin
    top_z = am.home[0].translation[2] + am.n * math.sqrt(longest**2 - chord**2)
    goal = pin.SE3(np.eye(3), np.array([0.0, 0.0, 1.6]))
    plan = plan_path(am, EEPath.between(am.home[-1], goal), start=am.home)
    assert not plan.success and "no valid sample" in plan.reason
    last_z = plan.states[-1].plates.p[-1, 2]
    assert top_z - opts.position_step <= last_z <= top_z + 1e-9, (last_z, top_z)
    assert all(state.feasible for state in plan.states)


def test_a_yaw_at_home_height_is_planned_to_its_end(am):
    """A 1.2 rad yaw of the EE about the stack's axis (0.95 m up): every sample's leg lengths,
    by the stack FK from home, put the EE on the path and the stack within every limit, and
    the last one at the goal (1e-6 m / rad). Planned from the previous plates with the EE
    moved alone, the top platform took the whole twist and the plan stopped at a third of it."""
    goal = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, 1.2), np.array([0.0, 0.0, 0.95]))
    path = EEPath.between(am.home[-1], goal)
    plan = plan_path(am, path, start=am.home)
    assert plan.success, plan.reason
    for u, state in zip(plan.parameters, plan.states, strict=True):
        fk = stack_forward_kinematics(am, state.leg_lengths, base=am.home[0], guess=state.plates)
        assert fk.success and kinematic_problems(am.config, fk.plates, tol=1e-9) == []
        target = path.at(u)
        assert np.linalg.norm(fk.plates.p[-1] - target.translation) <= 1e-6
        assert np.linalg.norm(pin.log3(target.rotation.T @ fk.plates.R[-1])) <= 1e-6
    assert plan.parameters[-1] == pytest.approx(path.segments)


def test_cli_plan_exits_1_on_a_failed_plan_with_the_prefix_written(am, tmp_path, monkeypatch, capsys):
    import assembler_pin.motion as motion_pkg

    cheap = lambda w3: PlanOptions(w3=w3, position_step=0.02, max_refinements=1)  # noqa: E731
    monkeypatch.setattr(motion_pkg, "PlanOptions", cheap)
    out = tmp_path / "t.json"
    code = main(["plan", "--to", "0", "0", "1.6", "0", "0", "0", "--rate", "10", "--out", str(out), "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert code == 1 and doc["success"] is False and doc["complete"] is False and doc["out"] == str(out)
    back = read_trajectory(out)
    assert back.meta["complete"] is False and back.meta["reason"] == doc["reason"]
    check_trajectory(am, back)


# ---------------------------------------------------------------------- 3. atomic, checked files
@pytest.mark.parametrize("name", ["t.csv", "t.json"])
def test_truncated_or_edited_files_are_refused_in_one_line(traj, tmp_path, name):
    path = traj.write(tmp_path / name)
    data = path.read_bytes()
    for cut in np.unique(np.linspace(1, len(data) - 2, 25).astype(int)):  # (the last byte is a newline)
        bad = tmp_path / f"cut_{cut}{path.suffix}"
        bad.write_bytes(data[:cut])
        with pytest.raises(TrajectoryError) as err:
            read_trajectory(bad)
        assert str(bad) in str(err.value) and "\n" not in str(err.value)
    text = data.decode()
    first = repr(float(traj.lengths[3, 1, 2]))
    edited = tmp_path / f"edited{path.suffix}"
    edited.write_text(text.replace(first, repr(float(traj.lengths[3, 1, 2]) + 1e-6), 1))
    with pytest.raises(TrajectoryError, match="sha256"):
        read_trajectory(edited)


@pytest.mark.parametrize("name", ["t.csv", "t.json"])
def test_an_interrupted_write_leaves_the_old_file_and_no_temporary(traj, tmp_path, monkeypatch, name):
    import assembler_pin.common.files as files

    target = tmp_path / name
    target.write_text("previous")

    def interrupted(fd):
        raise KeyboardInterrupt

    monkeypatch.setattr(files.os, "fsync", interrupted)
    with pytest.raises(KeyboardInterrupt):
        traj.write(target)
    assert target.read_text() == "previous" and sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_ctrl_c_while_plan_writes_leaves_no_file(am, traj, short, tmp_path, monkeypatch):
    import assembler_pin.common.files as files
    import assembler_pin.motion.timing as timing
    from assembler_pin.motion.result import MotionResult

    done = MotionResult(True, "reached the end of the path", short, traj, [], 0.0)
    monkeypatch.setattr(timing, "plan_trajectory", lambda *a, **k: done)
    monkeypatch.setattr(files.os, "fsync", lambda fd: (_ for _ in ()).throw(KeyboardInterrupt()))
    out = tmp_path / "t.csv"
    try:
        code = main(
            ["plan", "--to", "0", "0", "0.9", "0", "0", "0", "--out", str(out), "--plot", str(tmp_path / "p.png")]
        )
    except KeyboardInterrupt:
        code = 130
    assert code == 130 and list(tmp_path.iterdir()) == []


def test_plan_plot_is_written_atomically(am, traj, short, tmp_path, monkeypatch, capsys):
    import assembler_pin.common.files as files
    import assembler_pin.motion.timing as timing
    from assembler_pin.motion.result import MotionResult

    seen = []
    real = files.atomic_path

    def spy(path):
        seen.append(str(path))
        return real(path)

    monkeypatch.setattr(files, "atomic_path", spy)
    done = MotionResult(True, "reached the end of the path", short, traj, [], 0.0)
    monkeypatch.setattr(timing, "plan_trajectory", lambda *a, **k: done)
    png = tmp_path / "p.png"
    assert main(["plan", "--to", "0", "0", "0.9", "0", "0", "0", "--plot", str(png)]) == 0
    assert str(png) in seen and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# ---------------------------------------------------------------------- 4. bounds before work
@pytest.mark.parametrize("rate", ["1e5", "0", "nan", "inf", "-5", "0.5"])
def test_plan_rate_out_of_bounds_is_refused_before_planning(rate, capsys):
    t0 = time.perf_counter()
    assert main(["plan", "--to", "0.2", "0.1", "0.85", "0.5", "0.5", "0.5", "--rate", rate]) == 2
    err = capsys.readouterr().err.strip()
    assert "--rate" in err and "[1, 1000]" in err and len(err.splitlines()) == 1
    assert time.perf_counter() - t0 < 5


def _looped(plan, times: int):
    """The plan's samples forth and back ``times`` times (more leg travel, same poses)."""
    states = list(plan.states)
    for k in range(1, times):
        states += list(plan.states[::-1] if k % 2 else plan.states)[1:]
    return dataclasses.replace(
        plan, states=states, parameters=np.linspace(0.0, 1.0, len(states)), solve_times_s=np.zeros(len(states))
    )


def test_durations_and_row_counts_out_of_bounds_are_refused_before_allocating(am, short, monkeypatch):
    import assembler_pin.motion.timing as timing_module
    from assembler_pin.config import load_config

    looped = _looped(short, 5)  # 5 x 827 s at 1e-4 m/s and m/s^2
    t0 = time.perf_counter()
    with pytest.raises(TrajectoryError, match=r"would take .* over the 3600 s"):
        time_parametrize(am, looped, rate=10.0, max_speed=1e-4, max_acceleration=1e-4)
    with pytest.raises(TrajectoryError, match=r"output samples .* over the 1,000,000"):
        time_parametrize(am, _looped(short, 2), rate=1000.0, max_speed=1e-4, max_acceleration=1e-4)  # 1654 s
    with pytest.raises(TrajectoryError, match="max_speed must be"):
        time_parametrize(am, short, max_speed=1e-12)
    with pytest.raises(TrajectoryError, match="rate must be"):
        time_parametrize(am, short, rate=1e7)
    waited = dataclasses.replace(short, path=dataclasses.replace(short.path, times=(0.0, 5000.0)))
    with pytest.raises(TrajectoryError, match="would take 5000 s"):
        time_parametrize(am, waited)
    assert time.perf_counter() - t0 < 3  # no row was allocated or evaluated
    # a config whose legs are this slow: the planner answers success false, with no trajectory
    cfg = load_config()
    slow = AssemblerModel.from_config(
        cfg.replace(leg=dataclasses.replace(cfg.leg, max_speed=1e-4, max_acceleration=1e-4))
    )
    longer = _looped(short, 12)  # long enough for the time-optimal law too to pass the 3600 s
    monkeypatch.setattr(timing_module, "plan_path", lambda *a, **k: longer)
    t0 = time.perf_counter()
    motion = plan_trajectory(slow, longer.path, start=slow.home, rate=10.0)
    assert not motion.success and motion.trajectory is None and "would take" in motion.reason
    assert time.perf_counter() - t0 < 30  # refused from the laws' durations, no row evaluated
    assert motion.to_dict()["complete"] is False
    with pytest.raises(PathError, match=r"plan.path_samples"):
        EEPath.between(am.home[-1], pin.SE3(np.eye(3), np.array([5e3, 0, 0]))).parameters(0.01, 0.03)
    with pytest.raises(PoseError, match=r"pose.translation"):  # farther than any pose may be
        EEPath.between(am.home[-1], pin.SE3(np.eye(3), np.array([1e9, 0, 0])))


def _doc(traj, **changes):
    """The JSON document of ``traj`` with ``changes`` applied (to meta or rows), its checksum
    recomputed so that the reader's other checks are reached."""
    rows = traj.rows()
    meta = {"complete": True, "reason": "", "waypoint_times": None, **traj.meta, "platforms": traj.platforms}
    for key, value in changes.items():
        if key == "rows":
            rows = value
        else:
            meta[key] = value
    rows = np.asarray(rows, dtype=float)
    meta.update(rows=len(rows), sha256=rows_digest(rows))
    return {
        "format": "assembler-pin trajectory",
        "version": VERSION,
        "meta": meta,
        "columns": traj.columns(),
        "rows": rows.tolist(),
    }


def test_simulate_and_view_refuse_absurd_times_and_frames(traj, tmp_path, capsys):
    rows = traj.rows()
    for label, times in (("long", rows[:, 0] * 1e6), ("inf", np.r_[rows[:-1, 0], math.inf])):
        r = rows.copy()
        r[:, 0] = times
        path = tmp_path / f"{label}.json"
        path.write_text(json.dumps(_doc(traj, rows=r)))  # json writes inf as Infinity
        assert main(["simulate", "--trajectory", str(path)]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and str(path) in err
    good = traj.write(tmp_path / "good.csv")
    for frames in ("100000",):
        assert main(["view", "--trajectory", str(good), "--frames", frames, "--html", str(tmp_path / "p.html")]) == 2
        assert "--frames" in capsys.readouterr().err


def test_follow_trajectory_refuses_a_duration_over_the_simulation_bound(am, traj):
    pytest.importorskip("mujoco")
    from assembler_pin.simulate import follow_trajectory

    slow = dataclasses.replace(traj, times=traj.times * 1000.0)
    with pytest.raises(SimulationError, match="duration"):
        follow_trajectory(am, slow)


# ---------------------------------------------------------------------- 5. strict readers
HOSTILE_TRAJECTORIES = {
    "non-utf8": b"\xff\xfe\x00garbage",
    "empty": b"",
    "not json": b"hello",
    "truncated": b'{"format": "assembler-pin trajectory", "version": 2, "meta": {',
    "nested": b"[" * 50_000,
    "huge int": b'{"format": "assembler-pin trajectory", "version": 2, "rows": [' + b"9" * 6000 + b"]}",
    "nan constant": b'{"format": "assembler-pin trajectory", "version": NaN}',
    "duplicate keys": b'{"format": "assembler-pin trajectory", "format": "x"}',
    "old format": b'{"platforms": 4, "columns": ["t"], "rows": [[0.0]], "meta": {}}',
    "list": b"[1, 2, 3]",
}


@pytest.mark.parametrize("case", sorted(HOSTILE_TRAJECTORIES))
def test_hostile_trajectory_files_are_refused_in_one_line(tmp_path, case):
    path = tmp_path / "t.json"
    path.write_bytes(HOSTILE_TRAJECTORIES[case])
    with pytest.raises(TrajectoryError) as err:
        read_trajectory(path)
    assert "\n" not in str(err.value) and len(str(err.value)) < 300 and str(path) in str(err.value)


def test_old_format_files_are_refused_with_a_way_out(tmp_path):
    (tmp_path / "old.csv").write_text("t,L_sp0_leg0\n0.0,0.3\n")
    for name in ("old.csv",):
        with pytest.raises(TrajectoryError, match=r"older version.*plan it again"):
            read_trajectory(tmp_path / name)
    (tmp_path / "old.json").write_bytes(HOSTILE_TRAJECTORIES["old format"])
    with pytest.raises(TrajectoryError, match="older version"):
        read_trajectory(tmp_path / "old.json")


def _mutations(traj):
    """(what, document) pairs, each with one defect behind a valid checksum."""
    rows = traj.rows()
    n = traj.platforms
    back = rows.copy()
    back[5, 0] = back[4, 0]
    late = rows.copy()
    late[:, 0] += 1.0
    nan = rows.copy()
    nan[3, 2] = math.nan
    infeasible = rows.copy()
    infeasible[4, -1] = 0.0
    yield "increase strictly", _doc(traj, rows=back)
    yield "start at 0", _doc(traj, rows=late)
    yield "NaN", _doc(traj, rows=nan)
    yield "not marked feasible", _doc(traj, rows=infeasible)
    yield "meta.base", _doc(traj, base=[[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    yield "meta.base", _doc(traj, base="identity")
    yield "meta keys", _doc(traj, extra=1)
    yield "meta.complete", _doc(traj, complete="false")
    yield "meta.rate_hz", _doc(traj, rate_hz=1e9)
    yield "meta.platforms", _doc(traj, platforms=True)
    yield "meta.path_kind", _doc(traj, path_kind="spline")
    doc = _doc(traj)
    doc["columns"] = [*doc["columns"][:-1], "valid"]
    yield "columns", doc
    doc = _doc(traj)
    doc["columns"] = doc["columns"][:-1]
    yield "columns", doc
    doc = _doc(traj)
    doc["rows"][2][1] = "0.3"
    yield "list of numbers", doc
    doc = _doc(traj)
    doc["rows"][2][1] = True
    yield "list of numbers", doc
    doc = _doc(traj)
    doc["rows"][2] = doc["rows"][2][:-1]
    yield "row 2 has", doc
    doc = _doc(traj)
    doc["rows"] = doc["rows"][:-1]
    yield "meta says", doc
    doc = _doc(traj)
    doc["version"] = 1
    yield "version", doc
    doc = _doc(traj)
    doc["meta"]["platforms"] = n + 1
    yield "columns", doc


@pytest.mark.parametrize("kind", ["stroke", "deflection", "rise", "force", "force_dynamic", "path_position"])
def test_a_negative_margin_column_is_refused_whatever_its_kind(traj, tmp_path, kind):
    """A file holds valid rows only: a margin column saying a row breaks a limit is refused by
    the reader (the checksum recomputed, so the columns themselves are what is read)."""
    from assembler_pin.motion.trajfile import MARGIN_KINDS

    r = traj.rows()
    r[len(r) // 2, 8 + 12 * traj.platforms + MARGIN_KINDS.index(kind)] = -1e-3
    path = tmp_path / "m.json"
    path.write_text(json.dumps(_doc(traj, rows=r)))
    with pytest.raises(TrajectoryError, match=f"negative {kind} margin"):
        read_trajectory(path)


def test_every_format_defect_is_named(traj, tmp_path):
    for k, (what, doc) in enumerate(_mutations(traj)):
        path = tmp_path / f"m{k}.json"
        path.write_text(json.dumps(doc))
        with pytest.raises(TrajectoryError, match=what) as err:
            read_trajectory(path)
        assert "\n" not in str(err.value), what


def test_every_row_is_held_to_the_model_not_only_the_ends(am, traj, tmp_path):
    mid = len(traj.times) // 2
    leg = am.config.leg
    cases = []
    r = traj.rows()
    r[mid, 1] = leg.max_length + 0.01  # a leg out of its stroke in the middle
    cases.append(("stroke", r))
    r = traj.rows()
    r[mid, 1 + 6 * traj.platforms] += 1e-4  # the EE written 0.1 mm off FK of its lengths
    cases.append(("lengths put the EE", r))
    r = traj.rows()
    r[mid, 1] += 0.5 * (leg.max_length - r[mid, 1])  # a jump: speed over the limit
    cases.append(("leg.max_speed", r))
    r = traj.rows()
    r[mid, 8 + 6 * traj.platforms] = 1e6  # a dynamic-force column of 1e6 N (checksum recomputed)
    cases.append(("leg force is outside the limits", r))
    for what, rows in cases:
        path = tmp_path / "m.json"
        path.write_text(json.dumps(_doc(traj, rows=rows)))
        back = read_trajectory(path)  # the format is fine ...
        with pytest.raises(TrajectoryError, match=what):  # ... the model is not
            check_trajectory(am, back)
    # a file planned with another payload: its forces disagree with this model's statics
    from assembler_pin.config import load_config

    cfg = load_config()
    heavy = AssemblerModel.from_config(cfg.replace(payload=dataclasses.replace(cfg.payload, mass=cfg.payload.mass + 1)))
    with pytest.raises(TrajectoryError, match="another config"):
        trajectory_states(heavy, traj, frames=3)


@HYPO
@given(data=st.data())
def test_random_damage_to_a_file_is_refused_or_harmless(traj, tmp_path, data):
    name = data.draw(st.sampled_from(["t.csv", "t.json"]))
    raw = traj.write(tmp_path / name).read_bytes()
    pos = data.draw(st.integers(0, len(raw) - 1))
    kind = data.draw(st.sampled_from(["cut", "byte", "delete", "duplicate line"]))
    if kind == "cut":
        bad = raw[:pos]
    elif kind == "byte":
        bad = raw[:pos] + bytes([data.draw(st.integers(0, 255))]) + raw[pos + 1 :]
    elif kind == "delete":
        bad = raw[:pos] + raw[pos + 1 :]
    else:
        lines = raw.split(b"\n")
        k = pos % len(lines)
        bad = b"\n".join([*lines[:k], lines[k], *lines[k:]])
    path = tmp_path / f"bad{name[-5:]}"
    path.write_bytes(bad)
    try:
        back = read_trajectory(path)
    except TrajectoryError as exc:
        assert "\n" not in str(exc)
        return
    # accepted only when the numbers are the written ones (e.g. a changed byte in the reason text)
    assert np.array_equal(back.rows(), traj.rows())


# ---------------------------------------------------------------------- waypoint files
WAYPOINTS = [[0, 0, 0.9, 0, 0, 0], [0.1, 0, 0.9, 0, 0, 0]]


@pytest.mark.parametrize(
    ("content", "what"),
    [
        (json.dumps({"waypoints": WAYPOINTS, "degrees": "false"}), "degrees"),
        (json.dumps({"waypoints": WAYPOINTS, "degrees": 1}), "degrees"),
        (json.dumps({"waypoints": WAYPOINTS, "degree": True}), "unknown keys"),
        ('{"waypoints": [[0, 0, 0.9, 0, 0, 0]], "waypoints": []}', "duplicate key"),
        ('{"waypoints": [[0, 0, NaN, 0, 0, 0], [0, 0, 0.9, 0, 0, 0]]}', "NaN"),
        ('{"waypoints": [[0, 0, 1e999, 0, 0, 0], [0, 0, 0.9, 0, 0, 0]]}', "infinite"),
        (json.dumps({"waypoints": [[[0, 0, 0.9, 0, 0, 0]], WAYPOINTS[1]]}), "6 numbers"),
        (json.dumps({"waypoints": [["0", 0, 0.9, 0, 0, 0], WAYPOINTS[1]]}), "6 numbers"),
        (json.dumps({"waypoints": {"a": 1}}), "list"),
        (json.dumps({"waypoints": WAYPOINTS, "times": [0, "2"]}), "times"),
        (json.dumps({"waypoints": WAYPOINTS, "times": [0, 1e7]}), "last waypoint time"),
        (json.dumps({"waypoints": WAYPOINTS, "times": [1, 2]}), "starting at 0"),
        ('{"waypoints": [[0, 0, 0.9, 0, 0, 0]', "not valid JSON"),
        ("[" * 50_000, "nested"),
        ('{"waypoints": [[0, 0, 0.9, 0, 0, ' + "9" * 6000 + "]]}", "number too long"),
        (json.dumps({"waypoints": [WAYPOINTS[0]] * 20_000}), "number of waypoints"),
    ],
)
def test_hostile_waypoint_json_is_refused_in_one_line(tmp_path, content, what):
    path = tmp_path / "w.json"
    path.write_text(content)
    with pytest.raises(PathError, match=what) as err:
        read_waypoints(path)
    assert "\n" not in str(err.value) and str(path) in str(err.value) and len(str(err.value)) < 300


@pytest.mark.parametrize(
    ("content", "what"),
    [
        (b"", "empty"),
        (b"\xff\xfe0,0,0.9", "UTF-8"),
        (b"0,0,0.9,0,0,0\n0.1,0,nan,0,0,0\n", "NaN"),
        (b"0,0,0.9,0,0,0\n0.1,0,inf,0,0,0\n", "infinite"),
        (b"x,y,z,rx,ry,rz,t\n0,0,0.9,0,0,0,0\n0.1,0,0.9,0,0,0\n", "every row 7"),
        (b"foo,bar\n0,0,0.9,0,0,0\n0.1,0,0.9,0,0,0\n", "header"),
        (b"0,0,0.9,0,0,0\n0.1,0,zero,0,0,0\n", "number"),
        (b"0,0,0.9,0,0,0\n", "number of waypoints"),
        (b"0,0,0.9,0,0,0,0\n0.1,0,0.9,0,0,0,2\n0.2,0,0.9,0,0,0,1\n", "increasing"),
    ],
)
def test_hostile_waypoint_csv_is_refused_in_one_line(tmp_path, content, what):
    path = tmp_path / "w.csv"
    path.write_bytes(content)
    with pytest.raises(PathError, match=what) as err:
        read_waypoints(path)
    assert "\n" not in str(err.value)


def test_degrees_are_a_real_boolean(tmp_path):
    path = tmp_path / "w.json"
    path.write_text(json.dumps({"waypoints": [[0, 0, 0.9, 0, 0, 0], [0, 0, 0.9, 0, 0, 90]], "degrees": True}))
    assert np.linalg.norm(pin.log3(read_waypoints(path).waypoints[1].rotation)) == pytest.approx(np.pi / 2)
    path.write_text(json.dumps({"waypoints": [[0, 0, 0.9, 0, 0, 0], [0, 0, 0.9, 0, 0, 1]], "degrees": False}))
    assert np.linalg.norm(pin.log3(read_waypoints(path).waypoints[1].rotation)) == pytest.approx(1.0)


def _split(plan, index):
    """The same plan on a two-segment path through the planned sample ``index`` (the screw
    geodesic's pieces are geodesics, so every sample keeps its pose on the new path)."""
    u = plan.parameters
    us = u[index]
    path = EEPath((plan.path.at(0.0), plan.path.at(us), plan.path.at(1.0)), plan.path.kind)
    params = np.where(u <= us, u / us, 1.0 + (u - us) / (1.0 - us))
    params[index] = 1.0
    return dataclasses.replace(plan, path=path, parameters=params)


def test_waypoint_times_are_honoured_or_refused(am, short, tmp_path):
    plan = _split(short, 2)
    for u, state in zip(plan.parameters, plan.states, strict=True):  # the split path holds every sample
        assert kinematic_problems(am.config, state.plates, goal=plan.path.at(u), tol=1e-9) == []
    free = time_parametrize(am, _prefix(plan, 3), rate=50.0).duration  # segment 0 at the legs' limits
    t1 = 1.5 * free
    t2 = t1 + 3.0
    timed = dataclasses.replace(plan, path=dataclasses.replace(plan.path, times=(0.0, t1, t2)))
    traj = time_parametrize(am, timed, rate=50.0)
    assert traj.duration == pytest.approx(t2, abs=1e-12) and traj.meta["waypoint_times"] == [0.0, t1, t2]
    k = int(np.argmin(np.abs(traj.times - t1)))
    assert traj.times[k] == pytest.approx(t1, abs=1e-12)  # a row at the waypoint's time ...
    np.testing.assert_allclose(traj.lengths[k], plan.states[2].leg_lengths, atol=1e-12)  # ... at the waypoint
    np.testing.assert_allclose(traj.ee[k, :3], plan.path.waypoints[1].translation, atol=1e-9)
    assert np.abs(traj.speeds()[k - 1 : k + 1]).max() < 1e-2 * am.config.leg.max_speed  # at rest
    assert verify_trajectory(am, traj) == [] and traj.feasible.all()
    read_trajectory(traj.write(tmp_path / "timed.csv"))
    too_short = dataclasses.replace(plan, path=dataclasses.replace(plan.path, times=(0.0, 0.2 * free, t2)))
    with pytest.raises(TrajectoryError, match=r"needs at least .* the path gives"):
        time_parametrize(am, too_short, rate=50.0)


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.floats() | st.integers(-(10**30), 10**30) | st.text(max_size=4),
    lambda inner: st.lists(inner, max_size=7) | st.dictionaries(st.text(max_size=4), inner, max_size=3),
    max_leaves=40,
)


@HYPO
@given(
    doc=st.dictionaries(st.sampled_from(["waypoints", "times", "degrees", "extra"]), JSON_VALUES, max_size=4),
    rows=st.lists(st.lists(st.floats(-2, 2) | st.integers(-2, 2), min_size=6, max_size=6), max_size=4),
)
def test_random_waypoint_documents_are_refused_or_read_exactly(tmp_path, doc, rows):
    if rows and "waypoints" not in doc:
        doc["waypoints"] = rows
    path = tmp_path / "w.json"
    path.write_text(json.dumps(doc))  # NaN and Infinity written as JSON's non-standard tokens
    try:
        read = read_waypoints(path)
    except PathError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 300
        return
    assert set(doc) <= {"waypoints", "times", "degrees"} and doc.get("degrees", False) in (True, False)
    assert len(read.waypoints) == len(doc["waypoints"]) >= 2
    for pose, row in zip(read.waypoints, doc["waypoints"], strict=True):
        np.testing.assert_array_equal(pose.translation, np.array(row[:3], dtype=float))
    assert read.times is None if doc.get("times") is None else list(read.times) == [float(t) for t in doc["times"]]


def test_version_2_files_are_refused_with_a_way_out(tmp_path):
    """Version 3 added the time law and the forces with the motion's part: a v2 file is refused."""
    (tmp_path / "v2.csv").write_text("# assembler-pin trajectory v2\n# meta: {}\nt\n# end: 0 rows\n")
    with pytest.raises(TrajectoryError, match=r"not v3.*plan it again"):
        read_trajectory(tmp_path / "v2.csv")
    doc = {"format": "assembler-pin trajectory", "version": 2, "meta": {}, "columns": [], "rows": []}
    (tmp_path / "v2.json").write_text(json.dumps(doc))
    with pytest.raises(TrajectoryError, match=r"version 2 is not 3.*plan it again"):
        read_trajectory(tmp_path / "v2.json")
