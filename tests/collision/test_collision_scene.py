"""The scene reader: the example, and every malformed scene refused in one line."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from assembler_pin.collision import Scene, read_scene, scene_from_dict
from assembler_pin.collision.scene import MAX_OBSTACLES
from assembler_pin.exceptions import AssemblerError, SceneError


def test_the_example_truss_bay():
    scene = read_scene("examples/truss_bay.yaml")
    assert isinstance(scene, Scene) and scene.floor_z == 0.0
    names = [o.name for o in scene.obstacles]
    assert "lower strut" in names and len(names) == 9
    strut = scene.obstacles[names.index("lower strut")]
    np.testing.assert_allclose(strut.pose.rotation[:, 2], [0.0, -1.0, 0.0], atol=1e-12)  # along y
    assert strut.size == (0.015, 0.9)


def test_default_names_and_the_empty_scene():
    scene = scene_from_dict({"obstacles": [{"sphere": {"radius": 0.1, "center": [0, 0, 1]}}]})
    assert scene.obstacles[0].name == "sphere 0" and scene.floor_z is None
    assert read_scene(None) is None and scene_from_dict(None) == Scene()


HOSTILE = {
    "unknown_top": {"walls": []},
    "unknown_kind": {"obstacles": [{"cone": {"radius": 1}}]},
    "two_kinds": {"obstacles": [{"sphere": {"radius": 0.1, "center": [0, 0, 0]}, "box": {}}]},
    "no_kind": {"obstacles": [{"name": "x"}]},
    "not_a_list": {"obstacles": {"sphere": {}}},
    "not_a_mapping": {"obstacles": [3]},
    "missing_size": {"obstacles": [{"box": {"pose": [0, 0, 0, 0, 0, 0]}}]},
    "extra_key": {"obstacles": [{"box": {"size": [1, 1, 1], "pose": [0] * 6, "colour": 1}}]},
    "short_pose": {"obstacles": [{"box": {"size": [1, 1, 1], "pose": [0, 0, 0]}}]},
    "negative_size": {"obstacles": [{"box": {"size": [1, -1, 1], "pose": [0] * 6}}]},
    "zero_radius": {"obstacles": [{"cylinder": {"radius": 0, "length": 1, "pose": [0] * 6}}]},
    "nan_centre": {"obstacles": [{"sphere": {"radius": 1, "center": [0, float("nan"), 0]}}]},
    "inf_floor": {"floor": {"z": float("inf")}},
    "huge": {"obstacles": [{"sphere": {"radius": 1e9, "center": [0, 0, 0]}}]},
    "bool": {"obstacles": [{"sphere": {"radius": True, "center": [0, 0, 0]}}]},
    "string": {"floor": {"z": "0"}},
    "floor_extra": {"floor": {"z": 0, "tilt": 1}},
    "floor_no_z": {"floor": {}},
    "big_rotation": {"obstacles": [{"box": {"size": [1, 1, 1], "pose": [0, 0, 0, 1e9, 0, 0]}}]},
    "bad_name": {"obstacles": [{"name": "x" * 41, "sphere": {"radius": 1, "center": [0, 0, 0]}}]},
    "dup_name": {"obstacles": [{"name": "a", "sphere": {"radius": 1, "center": [0, 0, 0]}}] * 2},
    "support_text": {"obstacles": [{"support": "yes", "box": {"size": [1, 1, 1], "pose": [0, 0, -1, 0, 0, 0]}}]},
    "support_number": {"obstacles": [{"support": 1, "box": {"size": [1, 1, 1], "pose": [0, 0, -1, 0, 0, 0]}}]},
    "support_sphere": {"obstacles": [{"support": True, "sphere": {"radius": 1, "center": [0, 0, -1]}}]},
    "too_many": {"obstacles": [{"sphere": {"radius": 1, "center": [0, 0, 0]}}] * (MAX_OBSTACLES + 1)},
    "top_list": [1, 2],
}


@pytest.mark.parametrize("name", list(HOSTILE))
def test_hostile_scenes_are_refused_in_one_line(name, tmp_path):
    with pytest.raises(SceneError) as exc:
        scene_from_dict(HOSTILE[name])
    text = str(exc.value)
    assert text and "\n" not in text and len(text) <= 200
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(HOSTILE[name]) if name not in ("nan_centre", "inf_floor") else "floor: {z: .inf}\n")
    with pytest.raises(SceneError) as exc:
        read_scene(path)
    assert "\n" not in str(exc.value) and len(str(exc.value)) <= 200


@pytest.mark.parametrize(
    "text",
    [
        b"floor: {z: 0.0}\nfloor: {z: 1.0}\n",
        b"a: &x [1]\nb: *x\n",
        b"\xff\xfe",
        b"obstacles: [\n",
        b"floor: {z: 9_81}\n",
    ],
)
def test_malformed_files_are_refused(text, tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_bytes(text)
    with pytest.raises(SceneError):
        read_scene(path)
    with pytest.raises(SceneError):
        read_scene(tmp_path / "missing.yaml")


bad = st.one_of(
    st.booleans(),
    st.text(max_size=4),
    st.none(),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([1e308, -1.0, 0.0, 1e-300, "nan"]),
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=7),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)
entry = st.fixed_dictionaries(
    {},
    optional={
        "box": st.one_of(bad, st.fixed_dictionaries({"size": bad, "pose": bad})),
        "cylinder": st.one_of(bad, st.fixed_dictionaries({"radius": bad, "length": bad, "pose": bad})),
        "sphere": st.one_of(bad, st.fixed_dictionaries({"radius": bad, "center": bad})),
        "name": bad,
        "support": st.one_of(bad, st.booleans()),
    },
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    doc=st.one_of(
        bad,
        st.fixed_dictionaries(
            {},
            optional={
                "floor": st.one_of(bad, st.fixed_dictionaries({"z": bad})),
                "obstacles": st.one_of(bad, st.lists(entry, max_size=3)),
            },
        ),
    )
)
def test_any_mapping_is_a_scene_or_one_scene_error(doc):
    try:
        scene = scene_from_dict(doc)
    except AssemblerError as exc:
        assert isinstance(exc, SceneError) and str(exc) and "\n" not in str(exc)
        return
    for o in scene.obstacles:
        assert all(math.isfinite(x) and x > 0 for x in o.size)


def test_a_support_obstacle_gets_the_floor_rule():
    """A table just under the base plate: every pose collides with it unless it is the
    stack's support; as a support it is not checked against the base plate nor the base
    legs' joint zones, and a base leg beyond its zone is still measured (coal on a capsule
    and a box built here)."""
    import coal

    import assembler_pin as ap
    from assembler_pin.collision import clearance
    from assembler_pin.collision.bodies import stack_bodies

    am = ap.AssemblerModel.from_config()
    top = -0.5 * am.config.plate.thickness  # the table's top face under the base plate
    table = {"size": [0.8, 0.8, 0.1], "pose": [0.0, 0.0, top - 0.05, 0.0, 0.0, 0.0]}
    plain = scene_from_dict({"obstacles": [{"name": "table", "box": table}]})
    mounted = scene_from_dict({"obstacles": [{"name": "table", "box": table, "support": True}]})
    assert mounted.obstacles[0].support and not plain.obstacles[0].support
    c = clearance(am, am.home, plain)
    assert c.between[1] == "table" and c.min_distance < 0  # the motors reach below the plate
    c = clearance(am, am.home, mounted)
    rows = {(c.names[i], c.names[j]): r for r, (i, j) in enumerate(c.pairs)}
    assert c.clear and c.distances[rows[("plate 0", "table")]] == np.inf
    leg = am.config.leg
    b = stack_bodies(am, am.home)
    box = (coal.Box(*table["size"]), coal.Transform3s(np.eye(3), np.array(table["pose"][:3])))
    for g in range(6):  # base legs: beyond their bottom joint's zone
        u, best = b.axis[g], np.inf
        for lo, hi, r in (
            (leg.node_zone, leg.motor_length, leg.motor_radius),
            (leg.motor_length, b.length[g], leg.shaft_radius),
        ):
            R = ap.model.geometry.rotation_z_to(u)
            capsule = (coal.Capsule(r, hi - lo), coal.Transform3s(R, b.bottom[g] + 0.5 * (lo + hi) * u))
            best = min(best, coal.distance(*capsule, *box, coal.DistanceRequest(), coal.DistanceResult()))
        r = rows[(f"SP0 leg {g}", "table")]
        assert c.distances[r] <= best + 1e-9 and (not c.exact[r] or c.distances[r] == pytest.approx(best, abs=1e-6))
    with pytest.raises(SceneError, match="support"):
        scene_from_dict({"obstacles": [{"sphere": {"radius": 0.1, "center": [0, 0, -1]}, "support": True}]})
    with pytest.raises(SceneError, match="support"):
        scene_from_dict({"obstacles": [{"box": table, "support": "yes"}]})
