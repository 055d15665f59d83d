"""The core's inputs held to the contract: model files that agree, FK in the mechanism's own
assembly mode, strict plate and config readers, checked API arguments, one home for errors."""

from __future__ import annotations

import ast
import builtins
import importlib.util
import json
import math
import pkgutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from checks import design_anchors, sp_legs
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import assembler_pin as ap
from assembler_pin import exceptions
from assembler_pin.cli import main
from assembler_pin.cli.plate_file import plates_from_file
from assembler_pin.exceptions import (
    AssemblerError,
    CLIError,
    ConfigError,
    ModelFileError,
    OptionsError,
    PoseError,
)
from assembler_pin.kinematics import PlateArrays, plates_from_q, q_from_plates

# ---------------------------------------------------------------------- helpers


def _one_line(exc: BaseException, limit: int = 300) -> str:
    text = str(exc)
    assert "\n" not in text and 0 < len(text) <= limit, text
    return text


@pytest.fixture(scope="module")
def am1() -> ap.AssemblerModel:
    return ap.AssemblerModel.from_config({"platforms": 1})


@pytest.fixture()
def files(tmp_path):
    """An exported 2-platform model: (directory, URDF text, sidecar text)."""
    ap.export.export_model_files(ap.load_config({"platforms": 2}), tmp_path)
    return tmp_path, (tmp_path / "assembler.urdf").read_text(), (tmp_path / "assembler.yaml").read_text()


def _write(directory: Path, urdf: str, sidecar: str) -> None:
    (directory / "assembler.urdf").write_text(urdf)
    (directory / "assembler.yaml").write_text(sidecar)


# ---------------------------------------------------------------------- item 5: model files


@pytest.mark.parametrize(
    ("which", "old", "new", "needles"),
    [
        ("sidecar", "mass: 5.0", "mass: 50.0", ["payload.mass", "URDF 5, sidecar 50"]),
        ("urdf", '<mass value="5.0" />', '<mass value="50" />', ["payload.mass", "URDF 50, sidecar 5"]),
        ("sidecar", "mass: 0.2", "mass: 0.25", ["plate.mass"]),
        ("sidecar", "motor_com: 0.06", "motor_com: 0.07", ["leg.motor_com"]),
        ("sidecar", "shaft_mass: 0.04", "shaft_mass: 0.05", ["leg.shaft_mass"]),
        ("sidecar", "max_deflection_deg: 45.0", "max_deflection_deg: 40.0", ["leg.max_deflection_deg"]),
        ("sidecar", "max_tension: 200.0", "max_tension: 300.0", ["leg.max_tension", "URDF 200, sidecar 300"]),
        ("sidecar", "max_length: 0.35", "max_length: 0.36", ["leg.max_length"]),
        ("sidecar", "node_radius: 0.15", "node_radius: 0.151", ["plate.node_radius"]),
        ("sidecar", "offset: 0.2", "offset: 0.25", ["payload.offset", "URDF 0.2, sidecar 0.25"]),
        ("sidecar", "platforms: 2", "platforms: 3", ["platform count", "2 platforms", "platforms = 3"]),
        ("urdf", 'ixx="0.001126666666667"', 'ixx="0.0011267"', ["plate.mass"]),
        ("urdf", '<axis xyz="1 0 0" />', '<axis xyz="0 1 0" />', ["axis"]),
    ],
)
def test_model_files_that_disagree_are_refused(files, which, old, new, needles):
    directory, urdf, sidecar = files
    text = sidecar if which == "sidecar" else urdf
    assert old in text
    edited = text.replace(old, new)
    _write(directory, edited if which == "urdf" else urdf, edited if which == "sidecar" else sidecar)
    with pytest.raises(ModelFileError) as info:
        ap.AssemblerModel.from_files(directory)
    message = _one_line(info.value)
    assert "disagree" in message
    for needle in needles:
        assert needle in message


def test_agreeing_model_files_give_the_sidecar_forces(files):
    """Files that agree load, and their statics are those of the sidecar's payload: the
    payload's weight on the base equals total mass x g (independent sum of the masses)."""
    directory, _, sidecar = files
    side = sidecar.replace("mass: 5.0", "mass: 50.0")
    _write(directory, ap.model.urdf.assembler_urdf(ap.load_config({"platforms": 2, "payload": {"mass": 50.0}})), side)
    am = ap.AssemblerModel.from_files(directory)
    cfg = am.config
    expected_mass = 3 * cfg.plate.mass + 12 * (cfg.leg.motor_mass + cfg.leg.shaft_mass) + 50.0
    state = ap.evaluate_state(am, am.home)
    assert state.statics.base_wrench[2] == pytest.approx(expected_mass * cfg.gravity, rel=1e-9)


@pytest.mark.parametrize(
    ("urdf", "sidecar", "needle"),
    [
        ("not xml at all", None, "not XML"),
        ('<robot name="r2d2"><link name="body"/></robot>', None, "does not describe an Assembler"),
        ('<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaa">]><robot name="x"/>', None, "DOCTYPE"),
        ("<robt/>", None, "root element must be <robot>"),
        (None, "closed_loop: []\n", "must have the keys"),
        (None, "- 1\n- 2\n", "must have the keys"),
        (None, "a: &x [1, 2]\nb: *x\n", "aliases"),
        (None, "closed_loop: [\n", "not valid YAML"),
        (None, "x: 1\nx: 2\n", "given twice"),
    ],
)
def test_hostile_model_files_are_one_line(files, urdf, sidecar, needle):
    directory, good_urdf, good_sidecar = files
    _write(directory, good_urdf if urdf is None else urdf, good_sidecar if sidecar is None else sidecar)
    with pytest.raises(ModelFileError) as info:
        ap.AssemblerModel.from_files(directory)
    assert needle in _one_line(info.value)


@pytest.mark.parametrize(
    ("key", "value", "needle"),
    [
        ("closed_loop", 5, "closed_loop must be a list"),
        ("closed_loop", [["a", 1]], "closed_loop must be a list"),
        ("name_mot", {"a": 1}, "name_mot must be a list"),
        ("type", [1, "3d"], "type must be a list of names"),
        ("assembler_config", 3, "assembler_config must be the mapping"),
        ("assembler_config", None, "assembler_config must be the mapping"),
        ("gravity", "9.81", "gravity"),
    ],
)
def test_sidecar_keys_of_the_wrong_type(files, key, value, needle):
    directory, urdf, sidecar = files
    doc = yaml.safe_load(sidecar)
    if key == "gravity":
        doc["assembler_config"]["gravity"] = value
    else:
        doc[key] = value
    _write(directory, urdf, yaml.safe_dump(doc))
    with pytest.raises(ModelFileError) as info:
        ap.AssemblerModel.from_files(directory)
    assert needle in _one_line(info.value)


def test_unreadable_model_files(files):
    directory, urdf, _ = files
    (directory / "assembler.urdf").write_bytes(b"\xff\xfe not utf-8")
    with pytest.raises(ModelFileError, match="not UTF-8"):
        ap.AssemblerModel.from_files(directory)
    with pytest.raises(ModelFileError, match="cannot read"):
        ap.AssemblerModel.from_files(directory / "missing.urdf")
    (directory / "assembler.urdf").write_text(urdf)
    with pytest.raises(ModelFileError, match="is a directory, not a regular file"):
        ap.AssemblerModel.from_files(directory, sidecar_path=directory)  # refused before it is opened


# ---------------------------------------------------------------------- item 6: FK assembly mode


def _in_mechanism_mode(cfg, j: int, top_in_bottom: pin.SE3) -> list[str]:
    """The rules of the mechanism's own mode, recomputed from the design (tests/checks.py):
    rise > 0 in the bottom frame, bottom joint below top joint in the top frame, relative
    rotation under 90°, deflections under 90°."""
    Rb, pb = np.eye(3), np.zeros(3)
    Rt, pt = top_in_bottom.rotation, top_in_bottom.translation
    _, defl_b, defl_t, rise = sp_legs(cfg, j, Rb, pb, Rt, pt)
    bottom, top = design_anchors(cfg, j)
    v = top @ Rt.T + pt - bottom
    problems = []
    if rise.min() <= 0:
        problems.append("rise")
    if (v @ Rt)[:, 2].min() <= 0:
        problems.append("top side")
    if np.linalg.norm(pin.log3(Rt)) >= math.pi / 2:
        problems.append("turned")
    if max(defl_b.max(), defl_t.max()) >= math.pi / 2:
        problems.append("deflection")
    return problems


def _far_guess(rng: np.random.Generator, home: pin.SE3) -> pin.SE3:
    quat = rng.normal(size=4)
    quat /= np.linalg.norm(quat)
    return pin.SE3(pin.Quaternion(*quat).matrix(), home.translation + rng.uniform(-0.3, 0.3, 3))


def test_platform_fk_from_far_guesses_succeeds_only_in_the_mechanism_mode(am):
    """1,200 far guesses (uniform random rotations, offsets up to 0.3 m, random lengths in the
    stroke): every success is in the mode and, where FK from home solves the same lengths,
    is that pose; every failure that converged says which mode it found."""
    cfg = am.config
    rng = np.random.default_rng(20240522)
    successes = compared = 0
    for _ in range(1200):
        j = int(rng.integers(am.n))
        lengths = rng.uniform(cfg.leg.min_length, cfg.leg.max_length, 6)
        res = ap.kinematics.sp_forward_kinematics(
            am, j, lengths, guess=_far_guess(rng, am.plate_joint_placement[j + 1])
        )
        if not res.success:
            assert res.message != "converged"
            continue
        successes += 1
        assert _in_mechanism_mode(cfg, j, res.pose) == [], res
        got = sp_legs(cfg, j, np.eye(3), np.zeros(3), res.pose.rotation, res.pose.translation)[0]
        np.testing.assert_allclose(got, lengths, atol=1e-9)
        ref = ap.kinematics.sp_forward_kinematics(am, j, lengths)
        if ref.success:
            compared += 1
            assert _in_mechanism_mode(cfg, j, ref.pose) == []
            np.testing.assert_allclose(res.pose.homogeneous, ref.pose.homogeneous, atol=1e-8)
    assert successes >= 150 and compared >= 0.95 * successes, (successes, compared)


def test_stack_fk_from_far_guesses(am1):
    """Stack FK (2 platforms) from plate guesses far from home (each relative pose turned by
    up to 180° about a random axis, offsets up to 0.3 m): success only in the mode, and then
    the home-guess answer."""
    am = ap.AssemblerModel.from_config({"platforms": 2})
    cfg = am.config
    rng = np.random.default_rng(7)
    successes = 0
    for _ in range(150):
        lengths = rng.uniform(cfg.leg.min_length, cfg.leg.max_length, (am.n, 6))
        guess = [pin.SE3.Identity()]
        for j in range(am.n):
            axis = rng.normal(size=3)
            turn = pin.exp3(axis / np.linalg.norm(axis) * rng.uniform(0.0, math.pi))
            offset = am.plate_joint_placement[j + 1].translation + rng.uniform(-0.3, 0.3, 3)
            guess.append(guess[-1] * pin.SE3(turn, offset))
        res = ap.stack_forward_kinematics(am, lengths, guess=guess)
        if not res.success:
            assert res.message != "converged"
            continue
        successes += 1
        for j in range(am.n):
            rel = res.plates.se3(j).actInv(res.plates.se3(j + 1))
            assert _in_mechanism_mode(cfg, j, rel) == []
        ref = ap.stack_forward_kinematics(am, lengths)
        if ref.success:
            np.testing.assert_allclose(res.plates.as_matrices(), ref.plates.as_matrices(), atol=1e-8)
    assert successes >= 10


def test_a_foreign_mode_is_named(am):
    """A pose of the same lengths with the top plate upside down is a solution of the length
    equations, and FK started there says it is another assembly mode."""
    home = am.plate_joint_placement[1]
    flipped = pin.SE3(pin.rpy.rpyToMatrix(math.pi, 0.0, 0.0), home.translation)
    bottom, top = design_anchors(am.config, 0)
    lengths = np.linalg.norm(top @ flipped.rotation.T + flipped.translation - bottom, axis=1)
    res = ap.kinematics.sp_forward_kinematics(am, 0, lengths, guess=flipped)
    assert res.residual <= 1e-12 and not res.success
    assert "another assembly mode" in res.message
    with pytest.raises(ap.exceptions.ConvergenceError, match="assembly mode"):
        res.raise_if_failed()


# ---------------------------------------------------------------------- item 8: plate files

_I4 = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]


def _plate_doc(am) -> list:
    return ap.PlateArrays.from_se3(am.home).as_matrices().tolist()


def _read_plates(tmp_path: Path, text: str) -> list:
    path = tmp_path / "plates.json"
    path.write_text(text)
    return plates_from_file(str(path))


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ('{"plates": [' + json.dumps(_I4).replace("1.0", '"1.0"', 1) + "]}", "plate 0"),
        ('{"plates": [' + json.dumps(_I4).replace("0.0", "true", 1) + "]}", "plate 0"),
        ('{"plates": [' + json.dumps(_I4).replace("0.0", "null", 1) + "]}", "plate 0"),
        ('{"plates": [' + json.dumps(_I4).replace("0.0", '{"re": 1, "im": 2}', 1) + "]}", "plate 0"),
        ('{"plates": [' + json.dumps(_I4).replace("0.0", "NaN", 1) + "]}", "NaN"),
        ('{"plates": [' + json.dumps(_I4).replace("0.0", "Infinity", 1) + "]}", "Infinity"),
        ('{"plates": [' + json.dumps(_I4).replace("0.0", "-Infinity", 1) + "]}", "Infinity"),
        ('{"plates": [' + json.dumps(_I4).replace("0.0", "1e999", 1) + "]}", "out of range"),
        ('{"plates": [' + json.dumps(_I4).replace("0.0", "1" + "0" * 400, 1) + "]}", "not a finite number"),
        ('{"plates": [], "plates": []}', "given twice"),
        ('{"plates": [' + json.dumps(_I4) + ', {"a": 1, "a": 2}]}', "given twice"),
        ('{"plates": [' + json.dumps(_I4) + ", " + json.dumps(_I4[:3]) + "]}", "plate 1"),
        ('{"plates": [' + json.dumps(_I4) + ", " + json.dumps([r[:3] for r in _I4]) + "]}", "plate 1"),
        ('{"plates": [[' + json.dumps(_I4) + "]]}", "plate 0"),
        ('{"plates": [' + json.dumps(_I4).replace("[0.0, 0.0, 0.0, 1.0]", "[0.0, 0.0, 0.0, 2.0]") + "]}", "bottom row"),
        (
            '{"plates": [' + json.dumps(_I4).replace("[0.0, 0.0, 0.0, 1.0]", "[1e-6, 0.0, 0.0, 1.0]") + "]}",
            "bottom row",
        ),
        ('{"plates": [' + json.dumps(_I4).replace("1.0", "-1.0", 1) + "]}", "not a rotation"),  # det -1
        ('{"plates": [' + json.dumps(_I4).replace("1.0", "1.0000001", 1) + "]}", "not a rotation"),
        ('{"plates": [' + json.dumps(_I4).replace("1.0", "2.0", 1) + "]}", "not a rotation"),
        ('{"plates": "none"}', "list"),
        ("[1, 2]", "JSON object"),
    ],
)
def test_plate_files_are_read_strictly(tmp_path, text, needle):
    with pytest.raises(CLIError) as info:
        _read_plates(tmp_path, text)
    assert needle in _one_line(info.value, 200)


def test_plate_file_refusal_at_the_cli(tmp_path, capsys):
    path = tmp_path / "p.json"
    path.write_text('{"plates": [' + json.dumps(_I4).replace("1.0", '"1"', 1) + "]}")
    code = main(["statics", "--plates", str(path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "plate 0" in err[0]


_HOSTILE_LEAVES = st.one_of(
    st.text(max_size=5),
    st.booleans(),
    st.none(),
    st.lists(st.integers(), max_size=2),
    st.dictionaries(st.text(max_size=2), st.integers(), max_size=1),
)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(plate=st.integers(0, 4), row=st.integers(0, 3), col=st.integers(0, 3), leaf=_HOSTILE_LEAVES)
def test_plate_file_fuzz_names_the_plate(am, tmp_path, plate, row, col, leaf):
    doc = _plate_doc(am)
    doc[plate][row][col] = leaf
    with pytest.raises(CLIError) as info:
        _read_plates(tmp_path, json.dumps({"plates": doc}))
    assert f"plate {plate}" in _one_line(info.value, 200)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    quat=st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1),
    scale=st.floats(2e-9, 1e-3),
    plate=st.integers(0, 4),
)
def test_a_rotation_off_by_more_than_1e9_is_refused_not_projected(am, tmp_path, quat, scale, plate):
    doc = _plate_doc(am)
    good = pin.Quaternion(*(np.array(quat) / np.linalg.norm(quat))).matrix()
    for row in range(3):
        doc[plate][row][:3] = (good[row] * (1.0 + scale)).tolist()
    with pytest.raises(CLIError) as info:
        _read_plates(tmp_path, json.dumps({"plates": doc}))
    assert f"plate {plate}" in _one_line(info.value, 200)
    matrices = np.array(doc)
    with pytest.raises(PoseError, match=f"plate {plate}"):
        ap.kinematics.plate_arrays(am, matrices)  # the API's conversion refuses it too
    doc[plate][0][:3] = good[0].tolist()
    doc[plate][1][:3] = good[1].tolist()
    doc[plate][2][:3] = good[2].tolist()
    assert len(_read_plates(tmp_path, json.dumps({"plates": doc}))) == 5  # an exact rotation is read


@pytest.mark.parametrize(
    "value",
    [
        [[["1", 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]],
        [[[1 + 0j, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]],
        np.eye(4, dtype=complex)[None],
        np.array([[["1", "0", "0", "0"]] * 4]),
        [[[True, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]],
    ],
)
def test_api_plate_conversion_refuses_non_real_numbers(am1, value):
    with pytest.raises(PoseError, match="real numbers"):
        ap.kinematics.plate_arrays(am1, value)


# ---------------------------------------------------------------------- item 8: configs


def _config(tmp_path: Path, text: str) -> ap.AssemblerConfig:
    path = tmp_path / "c.yaml"
    path.write_text(text)
    return ap.load_config(path)


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("gravity: 9_81\n", "gravity"),
        ("gravity: !!float 9_81\n", "not a number"),
        ("platforms: !!int 1_0\n", "not an integer"),
        ("gravity: 1:30\n", "gravity"),
        ("platforms: 0b11\n", "platforms"),
        ("platforms: yes\n", "platforms"),
        ("gravity: on\n", "gravity"),
        ("gravity: true\n", "gravity"),
        ("gravity: '9.81'\n", "gravity"),
        ("gravity: .nan\n", "gravity"),
        ("leg: {max_length: .inf}\n", "leg.max_length"),
        ("gravity: 9.81\ngravity: 1.0\n", "given twice"),
        ("leg: {max_length: 0.4, max_length: 0.5}\n", "given twice"),
        ("a: &g 9.81\ngravity: *g\n", "aliases"),
        ("base: &b {mass: 1}\npayload:\n  <<: *b\n", "aliases"),
        ("payload: {<<: {mass: 1}}\n", "unknown config key 'payload.<<'"),
        ("colour: red\n", "allowed: platforms, gravity, clearance, plate, leg, payload"),
        ("leg: {stroke: 1}\n", "keys, listed in docs/configuration.md"),
        ("leg: {motor_radious: 0.02}\n", "unknown config key 'leg.motor_radious': did you mean 'leg.motor_radius'?"),
        ("plate: [1, 2]\n", "mapping"),
    ],
)
def test_config_files_are_read_strictly(tmp_path, text, needle):
    with pytest.raises(ConfigError) as info:
        _config(tmp_path, text)
    assert needle in _one_line(info.value, 200)


def test_yaml12_numbers_are_numbers(tmp_path):
    cfg = _config(tmp_path, "gravity: 1e1\nplate: {mass: .5}\nleg: {max_tension: +3e2, max_compression: 0x64}\n")
    assert cfg.gravity == 10.0 and cfg.plate.mass == 0.5
    assert cfg.leg.max_tension == 300.0 and cfg.leg.max_compression == 100.0
    assert _config(tmp_path, "platforms: 017\n").platforms == 17  # decimal, not YAML 1.1's octal 15


def _alias_bomb(levels: int) -> str:
    """A config whose anchors sit on real keys and whose ``gravity`` expands to 9**levels strings."""
    keys = [
        "min_length",
        "max_length",
        "motor_mass",
        "shaft_mass",
        "motor_com",
        "shaft_com",
        "max_deflection_deg",
        "max_tension",
        "max_compression",
    ][:levels]
    items = ['a0: &a0 ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]'.replace("a0: ", f"{keys[0]}: ")]
    for k in range(1, levels):
        items.append(f"{keys[k]}: &a{k} [" + ",".join([f"*a{k - 1}"] * 9) + "]")
    return "leg: {" + ", ".join(items) + "}\n" + f"gravity: *a{levels - 1}\n"


def test_alias_bombs_are_refused_at_once_with_a_short_line(tmp_path):
    for levels in (3, 9):  # 729 strings (a 4 kB message before), then 387 million (a hang before)
        with pytest.raises(ConfigError) as info:
            _config(tmp_path, _alias_bomb(levels))
        assert "aliases" in _one_line(info.value, 200)


def test_config_messages_are_short():
    for data in (
        {"platforms": "x" * 10_000},
        {"x" * 10_000: 1},
        {"leg": {"y" * 10_000: 1}},
        {"plate": list(range(10_000))},
        {"gravity": [[1] * 1000] * 100},
    ):
        with pytest.raises(ConfigError) as info:
            ap.load_config(data)
        _one_line(info.value, 200)


_YAML_SCALARS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**30), 10**30),
    st.booleans(),
    st.none(),
    st.text(max_size=12),
    st.sampled_from(["9_81", "1:30", "yes", "off", "~", ".inf", "0o17", "0x1F", "1e5", "&a 1", "*a", "[1", "{"]),
)
_KEYS = st.sampled_from(["platforms", "gravity", "plate", "leg", "payload", "mass", "offset", "x", "<<"])


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    doc=st.dictionaries(_KEYS, st.one_of(_YAML_SCALARS, st.dictionaries(_KEYS, _YAML_SCALARS, max_size=3)), max_size=4)
)
def test_config_fuzz_answers_or_refuses_in_one_short_line(tmp_path, doc):
    def render(value):
        if isinstance(value, dict):
            return "{" + ", ".join(f"{k}: {render(v)}" for k, v in value.items()) + "}"
        return str(value) if not isinstance(value, str) else value

    text = "\n".join(f"{k}: {render(v)}" for k, v in doc.items()) + "\n"
    try:
        cfg = _config(tmp_path, text)
    except ConfigError as exc:
        _one_line(exc, 200)
    else:
        assert isinstance(cfg, ap.AssemblerConfig)
        assert all(math.isfinite(v) for v in (cfg.gravity, cfg.payload.mass, cfg.leg.max_length))


# ---------------------------------------------------------------------- item 9: API arguments


def test_goal_tolerance_refuses_nan_inf_negative():
    for bad in (math.nan, math.inf, -1e-3, "1e-6", True, None):
        with pytest.raises(OptionsError, match="GoalTolerance"):
            ap.constraints.GoalTolerance(position=bad)
        with pytest.raises(OptionsError, match="GoalTolerance"):
            ap.constraints.GoalTolerance(rotation=bad)


def test_a_nan_tolerance_never_passes_a_pose_off_its_goal(am):
    """Even a tolerance forced to NaN past its checks calls a pose 0.3 m off the goal infeasible."""
    goal = am.home[-1] * pin.SE3(np.eye(3), np.array([0.3, 0.0, 0.0]))
    tol = ap.constraints.GoalTolerance()
    object.__setattr__(tol, "position", math.nan)
    object.__setattr__(tol, "rotation", math.nan)
    state = ap.evaluate_state(am, am.home, goal=goal, tolerance=tol)
    assert not state.feasible and {"ee_position", "ee_rotation"} <= {v.kind for v in state.violations}
    nan_goal = pin.SE3(np.eye(3), np.array([math.nan, 0.0, 1.0]))
    with pytest.raises(PoseError, match="goal"):
        ap.evaluate_state(am, am.home, goal=nan_goal)


@pytest.mark.parametrize(
    ("call", "needle"),
    [
        (lambda am, g: ap.solve(am, g, options={"w1": 1.0}), "options must be a OptimizeOptions"),
        (lambda am, g: ap.solve(am, g, helper_options=ap.OptimizeOptions()), "helper_options must be a HelperArm"),
        (lambda am, g: ap.solve(am, g, optimize="no"), "optimize must be True or False"),
        (lambda am, g: ap.optimize_internal_poses(am, am.home, g, options={"w1": 1}), "options must be"),
        (lambda am, g: ap.initial_condition(am, g, options={"d_step": 0.01}), "options must be a HelperArm"),
        (lambda am, g: ap.plan_trajectory(am, None, options={"rate": 5}), "options must be a PlanOptions"),
        (lambda am, g: ap.evaluate_state(am, am.home, goal=g, tolerance=(1e-6, 1e-6)), "tolerance must be"),
        (lambda am, g: ap.solve_statics(am, am.home, legs="legs"), "legs must be"),
        (lambda am, g: ap.solve_statics("model", am.home), "am must be an AssemblerModel"),
        (lambda am, g: ap.evaluate_state(am, am.home, goal="up"), "goal must be"),
        (lambda am, g: ap.solve(am, pin.SE3(np.eye(3), np.array([math.nan, 0, 1]))), "goal contains NaN"),
    ],
)
def test_api_arguments_of_the_wrong_type_are_named(am, call, needle):
    with pytest.raises(AssemblerError) as info:
        call(am, am.home[-1])
    assert needle in _one_line(info.value)


def test_plate_arrays_that_are_not_rotations(am):
    pa = ap.PlateArrays.from_se3(am.home)
    R = pa.R.copy()
    R[2] *= 1.001
    with pytest.raises(PoseError, match=r"R\[2\] is not a rotation"):
        ap.evaluate_state(am, PlateArrays(R, pa.p.copy()))
    R = pa.R.copy()
    R[1] = np.diag([1.0, 1.0, -1.0])  # orthonormal, det -1
    with pytest.raises(PoseError, match=r"R\[1\] is not a rotation"):
        ap.kinematics.leg_state(am, PlateArrays(R, pa.p.copy()))
    p = pa.p.copy()
    p[3, 0] = math.inf
    with pytest.raises(PoseError, match="plate 3"):
        ap.solve_statics(am, PlateArrays(pa.R.copy(), p))
    with pytest.raises(PoseError, match="expected 5 plate poses"):
        ap.kinematics.leg_state(am, PlateArrays(pa.R[:3].copy(), pa.p[:3].copy()))


def test_quaternions_in_q(am):
    q = q_from_plates(am, am.home)
    for k, scale in ((0, 0.0), (2, 2.0), (4, 1.0 + 1e-6)):
        bad = q.copy()
        start = int(am.plate_idx_q[k]) + 3
        bad[start : start + 4] *= scale
        with pytest.raises(PoseError, match=f"quaternion of plate {k}"):
            plates_from_q(am, bad)
    bad = q.copy()
    bad[5] = math.nan
    with pytest.raises(PoseError, match="NaN"):
        plates_from_q(am, bad)
    back = plates_from_q(am, q)
    np.testing.assert_allclose(back.as_matrices(), ap.PlateArrays.from_se3(am.home).as_matrices(), atol=1e-12)


# ---------------------------------------------------------------------- every error class in one module


def _exception_classes_outside(package) -> list[str]:
    """Every class deriving from Exception that is defined (at any depth, private ones too)
    in a module of the package other than exceptions.py. Read with ast, without importing:
    a base is an exception when it is a built-in one, a class of exceptions.py, a class of
    the same module already found to be one, or (an import from elsewhere) named ``*Error``
    / ``*Exception``."""
    known = {name for name, obj in vars(exceptions).items() if isinstance(obj, type) and issubclass(obj, Exception)}
    found = []
    for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
        if info.name == "assembler_pin.exceptions":
            continue
        spec = importlib.util.find_spec(info.name)
        if spec is None or spec.origin is None or not spec.origin.endswith(".py"):
            continue
        local: set[str] = set()
        for node in ast.walk(ast.parse(Path(spec.origin).read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ClassDef):
                continue
            for base in node.bases:
                name = base.attr if isinstance(base, ast.Attribute) else getattr(base, "id", "")
                builtin = getattr(builtins, name, None)
                if (
                    (isinstance(builtin, type) and issubclass(builtin, Exception))
                    or name in known
                    or name in local
                    or (builtin is None and name.endswith(("Error", "Exception")))
                ):
                    local.add(node.name)
                    found.append(f"{info.name}.{node.name}")
                    break
    return found


def test_every_exception_class_lives_in_exceptions_py():
    assert _exception_classes_outside(ap) == []
    assert issubclass(exceptions.SingularIterateError, AssemblerError)
    assert issubclass(exceptions.ArgumentError, AssemblerError)
