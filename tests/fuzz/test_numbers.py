"""Numbers too large for a float, unknown keys and long scenes, in every file the package reads.

* An integer of hundreds of digits (YAML and JSON read it exactly, as a Python int) is refused
  in one line like ``1e308``, wherever a number is read: every configuration key, every scene
  number, footholds, waypoints, trajectory files, plate files, map grids and the options;
  never an ``OverflowError`` (exit 70 at the command line).
* An unknown key names the closest allowed one (``did you mean 'leg.motor_radius'?``) in a
  line of at most 200 characters.
* A scene's obstacle list stops the read at its 257th item; a scene file is at most
  ``scene.bytes`` (256 KiB) long.
"""

from __future__ import annotations

import dataclasses
import json

import pinocchio as pin
import pytest

import assembler_pin as ap
from assembler_pin.collision.scene import MAX_OBSTACLES, MAX_SCENE_BYTES, read_scene, scene_from_dict
from assembler_pin.config.checks import MAX_MESSAGE
from assembler_pin.config.numbers import finite_float, read_number
from assembler_pin.exceptions import ConfigError, SceneError

from .harness import judge_cli, run_cli

#: An integer of 400 digits: exact in YAML and JSON, beyond any float (about 1.8e308).
HUGE = 10**400
#: One of 5000 digits: beyond what ``repr`` of an int converts by default (4300 digits).
HUGER = 10**5000
HUGE_TEXT = "1" + "0" * 400


def test_finite_float_reads_every_finite_real_and_nothing_else():
    """The one number reader against Python's own conversion (a second method: ``float`` of
    the decimal text, compared by value)."""
    for value in (0, -3, 1.5, 2**1023, -(2**1023), 1e308, True - 2):
        assert finite_float(value) == float(str(value))
    for value in (HUGE, -HUGE, HUGER, 2**1024, float("nan"), float("inf"), True, None, "1", [1], 1j):
        assert finite_float(value) is None, value
    assert read_number(2.5, "x", ConfigError, 0, 3) == 2.5
    for value, words in ((HUGE, "must be a finite number"), (4, "must be in [0, 3]"), ("2", "finite number")):
        with pytest.raises(ConfigError, match=words.replace("[", r"\[").replace("]", r"\]")):
            read_number(value, "x", ConfigError, 0, 3)


def _config_keys() -> list[str]:
    cfg = ap.load_config()
    keys = ["platforms", "gravity", "clearance"]
    for section in ("plate", "leg", "payload"):
        keys += [f"{section}.{f.name}" for f in dataclasses.fields(getattr(cfg, section))]
    return keys


def _nested(key: str, value: object) -> dict:
    section, _, name = key.rpartition(".")
    return {section: {name: value}} if section else {key: value}


@pytest.mark.parametrize("value", [HUGE, -HUGE, HUGER], ids=["1e400", "-1e400", "1e5000"])
@pytest.mark.parametrize("key", _config_keys())
def test_every_config_key_refuses_an_integer_too_large_for_a_float(key, value):
    with pytest.raises(ConfigError) as info:
        ap.load_config(_nested(key, value))
    line = str(info.value)
    assert f"'{key}'" in line and "\n" not in line and len(line) <= MAX_MESSAGE, line
    assert ("integer from 1 to 64" if key == "platforms" else "must be a finite number") in line


@pytest.mark.parametrize("key", ["leg.motor_radius", "clearance", "plate.radius", "gravity", "payload.mass"])
def test_a_config_file_with_a_huge_integer_is_refused_not_an_internal_error(tmp_path, key):
    section, _, name = key.rpartition(".")
    text = f"{section}:\n  {name}: {HUGE_TEXT}\n" if section else f"{key}: {HUGE_TEXT}\n"
    path = tmp_path / "c.yaml"
    path.write_text(text)
    outcome = run_cli(["statics", "--home", "--json", "--config", str(path)])
    judge_cli(outcome, "refuse", f"statics --config with {key} = 1e400 as an integer")
    assert f"'{key}'" in outcome.err and "must be a finite number" in outcome.err, outcome.err


#: Every number of a scene, as a path into the document of :data:`SCENE`.
SCENE = {
    "floor": {"z": 0.0},
    "obstacles": [
        {"box": {"size": [0.1, 0.1, 0.1], "pose": [1.0, 0.0, 0.5, 0.0, 0.0, 0.0]}},
        {"cylinder": {"radius": 0.02, "length": 1.0, "pose": [1.0, 0.0, 0.5, 0.0, 0.0, 0.0]}},
        {"sphere": {"radius": 0.05, "center": [1.0, 0.3, 0.9]}},
    ],
}
SCENE_NUMBERS = [
    ("floor", "z"),
    *[(0, "box", "size", i) for i in range(3)],
    *[(0, "box", "pose", i) for i in range(6)],
    (1, "cylinder", "radius"),
    (1, "cylinder", "length"),
    *[(1, "cylinder", "pose", i) for i in range(6)],
    (2, "sphere", "radius"),
    *[(2, "sphere", "center", i) for i in range(3)],
]


def _scene_with(where: tuple, value: object) -> dict:
    doc = json.loads(json.dumps(SCENE))
    node = doc if where[0] == "floor" else doc["obstacles"]
    for step in where[:-1]:
        node = node[step]
    node[where[-1]] = value
    return doc


@pytest.mark.parametrize("where", SCENE_NUMBERS, ids=[".".join(map(str, w)) for w in SCENE_NUMBERS])
def test_every_scene_number_refuses_an_integer_too_large_for_a_float(where):
    assert scene_from_dict(_scene_with(where, 1.0)) is not None  # the place holds a number
    for value in (HUGE, -HUGE, HUGER):
        with pytest.raises(SceneError, match="must be a finite number") as info:
            scene_from_dict(_scene_with(where, value))
        assert len(str(info.value)) <= MAX_MESSAGE


@pytest.mark.parametrize("where", [("floor", "z"), (0, "box", "size", 0), (2, "sphere", "center", 1)])
def test_a_scene_file_with_a_huge_integer_is_refused_in_one_line(tmp_path, where):
    text = json.dumps(_scene_with(where, "HUGE")).replace('"HUGE"', HUGE_TEXT)
    path = tmp_path / "s.yaml"
    path.write_text(text)  # JSON is YAML: the integer is read exactly
    outcome = run_cli(["statics", "--home", "--json", "--scene", str(path)])
    judge_cli(outcome, "refuse", f"statics --scene with {where} = 1e400 as an integer")
    assert "must be a finite number" in outcome.err, outcome.err


def _json_readers(tmp_path):
    from assembler_pin.cli.plate_file import plates_from_file
    from assembler_pin.motion.paths import read_waypoints
    from assembler_pin.walk.footholds import read_footholds

    eye = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    row = [0, 0, 0.9, 0, 0, 0]
    return [
        ("footholds row", read_footholds, {"footholds": [[HUGE, 0, 0, 0, 0, 0], [0.5, 0, 0, 0, 0, 0]]}),
        ("footholds matrix", read_footholds, {"footholds": [[[HUGE, 0, 0, 0], *eye[1:]], [0.5, 0, 0, 0, 0, 0]]}),
        ("footholds floor_z", read_footholds, {"footholds": [row, [0.5, 0, 0.9, 0, 0, 0]], "floor_z": HUGE}),
        ("waypoints row", read_waypoints, {"waypoints": [[0, 0, HUGE, 0, 0, 0], row]}),
        ("waypoints times", read_waypoints, {"waypoints": [row, [0, 0, 0.8, 0, 0, 0]], "times": [0, HUGE]}),
        ("plate file", plates_from_file, {"plates": [[[HUGE, 0, 0, 0], *eye[1:]]] * 5}),
    ]


def test_every_json_reader_refuses_an_integer_too_large_for_a_float(tmp_path):
    for name, read, doc in _json_readers(tmp_path):
        path = tmp_path / f"{name.replace(' ', '_')}.json"
        path.write_text(json.dumps(doc))
        with pytest.raises(ap.AssemblerError) as info:
            read(path if name != "plate file" else str(path))
        line = str(info.value)
        assert "\n" not in line and len(line) < 300 and "number" in line, (name, line)


@pytest.fixture(scope="module")
def trajectory_json(am, tmp_path_factory) -> str:
    """The JSON text of a short planned trajectory (1 cm down from home)."""
    goal = ap.kinematics.taa_to_se3([0.0, 0.0, 0.956, 0.0, 0.0, 0.0])
    motion = ap.plan_trajectory(am, ap.EEPath((am.home[-1], goal)), am.home)
    return motion.trajectory.write(tmp_path_factory.mktemp("traj") / "t.json").read_text()


@pytest.mark.parametrize("key", ["base", "waypoint_times", "rate_hz", "version"])
def test_a_trajectory_file_with_a_huge_integer_is_refused(tmp_path, trajectory_json, key):
    path = tmp_path / "t.json"
    path.write_text(trajectory_json)
    assert len(ap.read_trajectory(path).times) > 1  # the original reads back
    doc = json.loads(trajectory_json)
    if key == "version":
        doc["version"] = "HUGER"
    elif key == "base":
        doc["meta"]["base"][0][3] = HUGE
    elif key == "waypoint_times":
        doc["meta"]["waypoint_times"] = [0, HUGE]
    else:
        doc["meta"][key] = HUGE
    path.write_text(json.dumps(doc).replace('"HUGER"', "1" + "0" * 5000))
    with pytest.raises(ap.exceptions.TrajectoryError) as info:
        ap.read_trajectory(path)
    assert "\n" not in str(info.value) and len(str(info.value)) < 300


@pytest.mark.parametrize(
    "make",
    [
        lambda: ap.OptimizeOptions(w1=HUGE),
        lambda: ap.OptimizeOptions(ftol=HUGE),
        lambda: ap.OptimizeOptions(max_iterations=HUGE),
        lambda: ap.HelperArmOptions(d_step=HUGE),
        lambda: ap.HelperArmOptions(regularization=HUGER),
        lambda: ap.config.options.GoalTolerance(HUGE, 1e-3),
        lambda: ap.PlanOptions(w3=HUGE),
        lambda: ap.PlanOptions(position_step=HUGER),
        lambda: ap.walk.WalkOptions(floor_z=HUGE),
        lambda: ap.walk.WalkOptions(clearance=HUGER),
        lambda: ap.maps.Grid(x=(HUGE,), y=(0.0,), z=(0.5,)),
        lambda: ap.config.bounds.check_bound("plan.rate", HUGER),
        lambda: ap.AssemblerConfig(gravity=HUGE),
        lambda: ap.EEPath((pin.SE3.Identity(), pin.SE3.Random()), kind=HUGER),
    ],
)
def test_every_option_refuses_an_integer_too_large_for_a_float(make):
    with pytest.raises(ap.AssemblerError) as info:
        make()
    assert "\n" not in str(info.value) and len(str(info.value)) < 300


# ---------------------------------------------------------------------- unknown keys


@pytest.mark.parametrize(
    ("doc", "hint"),
    [
        ({"leg": {"motor_radious": 0.02}}, "unknown config key 'leg.motor_radious': did you mean 'leg.motor_radius'?"),
        ({"leg": {"stifness": 1e6}}, "did you mean 'leg.stiffness'?"),
        ({"plate": {"radus": 0.2}}, "did you mean 'plate.radius'?"),
        ({"payload": {"mas": 1.0}}, "did you mean 'payload.mass'?"),
        ({"gravty": 9.81}, "did you mean 'gravity'?"),
        ({"platfroms": 3}, "did you mean 'platforms'?"),
    ],
)
def test_an_unknown_config_key_names_the_closest_allowed_one(doc, hint):
    with pytest.raises(ConfigError) as info:
        ap.load_config(doc)
    assert hint in str(info.value) and len(str(info.value)) <= MAX_MESSAGE


@pytest.mark.parametrize("key", [HUGER, 5, None, ("a",), "x" * 10_000], ids=["1e5000", "5", "None", "tuple", "long"])
def test_an_unknown_key_of_any_kind_is_named_in_one_short_line(key):
    for doc in ({key: 1}, {"leg": {key: 1}}):
        with pytest.raises(ConfigError) as info:
            ap.load_config(doc)
        assert len(str(info.value)) <= MAX_MESSAGE and "unknown config key" in str(info.value)
    with pytest.raises(SceneError, match="unknown scene key") as info:
        scene_from_dict({"floor": {key: 1}})
    assert len(str(info.value)) <= MAX_MESSAGE


def test_an_unknown_key_without_a_close_one_lists_them_or_names_the_page():
    with pytest.raises(ConfigError) as info:
        ap.load_config({"colour": "red"})
    assert str(info.value).endswith("allowed: platforms, gravity, clearance, plate, leg, payload, hexapod")
    with pytest.raises(ConfigError) as info:
        ap.load_config({"leg": {"zzz": 1}})
    line = str(info.value)
    assert "listed in docs/configuration.md" in line and "…" not in line and len(line) <= MAX_MESSAGE


@pytest.mark.parametrize(
    ("doc", "hint"),
    [
        ({"obstacle": []}, "did you mean 'file.obstacles'?"),
        ({"floor": {"zz": 0}}, "did you mean 'floor.z'?"),
        ({"obstacles": [{"box": {"sise": [1, 1, 1], "pose": [0] * 6}}]}, "did you mean 'obstacles[0].box.size'?"),
        ({"obstacles": [{"sphere": {"radius": 1, "centre": [0, 0, 0]}}]}, "'obstacles[0].sphere.center'?"),
    ],
)
def test_an_unknown_scene_key_names_the_closest_allowed_one(doc, hint):
    with pytest.raises(SceneError) as info:
        scene_from_dict(doc)
    assert hint in str(info.value) and len(str(info.value)) <= MAX_MESSAGE


# ---------------------------------------------------------------------- long scenes

ENTRY = "  - box: {size: [0.1, 0.1, 0.1], pose: [5.0, 0.0, 0.25, 0.0, 0.0, 0.0]}\n"


def test_a_scene_of_the_bound_is_read_and_one_more_obstacle_stops_the_read(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text("obstacles:\n" + ENTRY * MAX_OBSTACLES)
    assert len(read_scene(path).obstacles) == MAX_OBSTACLES
    path.write_text("obstacles:\n" + ENTRY * 3000)  # 216 kB: within the byte bound
    assert path.stat().st_size < MAX_SCENE_BYTES
    with pytest.raises(SceneError, match=f"line {MAX_OBSTACLES + 2}: a list holds more than {MAX_OBSTACLES} items"):
        read_scene(path)
    path.write_text("obstacles: [" + "{sphere: {radius: 1, center: [5, 0, 0]}}, " * 5000 + "]")
    with pytest.raises(SceneError, match=f"at most {MAX_OBSTACLES} obstacles"):
        read_scene(path)


def test_a_scene_file_longer_than_its_bound_is_refused_before_it_is_parsed(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text("obstacles:\n" + ENTRY * 10_000)  # 730 kB
    outcome = run_cli(["statics", "--home", "--json", "--scene", str(path)])
    judge_cli(outcome, "refuse", "statics --scene of 10,000 obstacles")
    assert f"is larger than {MAX_SCENE_BYTES} bytes (scene.bytes)" in outcome.err, outcome.err


def test_a_config_file_longer_than_its_bound_is_refused_unread(tmp_path):
    from assembler_pin.config.schema import MAX_CONFIG_BYTES

    path = tmp_path / "c.yaml"
    path.write_text("# a comment line of a configuration file\n" * (MAX_CONFIG_BYTES // 40))
    assert path.stat().st_size > MAX_CONFIG_BYTES == 1 << 16
    with pytest.raises(ConfigError, match=r"larger than 65536 bytes \(config.bytes\)"):
        ap.load_config(path)
    path.write_text("# a comment line of a configuration file\n" * (MAX_CONFIG_BYTES // 50))
    assert ap.load_config(path) == ap.load_config()
