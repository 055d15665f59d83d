"""The payload as a body: a sphere of ``payload.radius`` at the payload's centre, held to the
tests' own closed forms (segments, a solid disc, two spheres, the floor) and to coal on shapes
built here (a box), its derivatives to central differences, its name in the messages."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest
from checks import brute_segment_distance

import assembler_pin as ap
from assembler_pin.collision import Scene, clearance, scene_from_dict
from assembler_pin.collision.bodies import stack_bodies
from assembler_pin.config.schema import load_config
from assembler_pin.exceptions import ConfigError
from assembler_pin.state import evaluate_state

RADIUS = 0.05


@pytest.fixture(scope="module")
def am():
    return ap.AssemblerModel.from_config(load_config({"payload": {"radius": RADIUS}}))


def _pose(am, scale: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.array(
        [am.home[0].homogeneous] + [(pin.exp6(rng.normal(size=6) * scale) * m).homogeneous for m in am.home[1:]]
    )


def _centre(am, plates) -> np.ndarray:
    top = pin.SE3(plates[-1])
    return top.translation + am.config.payload.offset * top.rotation[:, 2]


def _disc_sdf(am, plates, k: int, x: np.ndarray) -> float:
    frame = pin.SE3(plates[k])
    local = frame.rotation.T @ (x - frame.translation)
    q = np.array(
        [np.hypot(local[0], local[1]) - am.config.plate.radius, abs(local[2]) - 0.5 * am.config.plate.thickness]
    )
    return float(np.linalg.norm(np.maximum(q, 0.0)) + min(q.max(), 0.0))


def _rows(c) -> dict:
    return {(c.names[i], c.names[j]): r for r, (i, j) in enumerate(c.pairs)}


def test_the_payload_against_the_legs_and_plates(am):
    """Every leg (the legs jointed to the EE plate only beyond node_zone there) and plates
    0..n-1, not the EE plate it is fixed to: the tests' own distances."""
    leg, n = am.config.leg, am.n
    for plates in (np.array([m.homogeneous for m in am.home]), _pose(am, 0.2, 1), _pose(am, 0.4, 2)):
        c = clearance(am, plates)
        rows, centre, b = _rows(c), _centre(am, plates), stack_bodies(am, plates)
        assert ("plate 4", "payload") not in rows and "payload" in c.names
        for g in range(6 * n):
            L, u = b.length[g], b.axis[g]
            best = np.inf
            for lo, hi, r in ((0.0, leg.motor_length, leg.motor_radius), (leg.motor_length, L, leg.shaft_radius)):
                hi = min(hi, L - leg.node_zone) if g // 6 == n - 1 else hi
                if hi >= lo:
                    d = brute_segment_distance(b.bottom[g] + lo * u, (hi - lo) * u, centre, np.zeros(3))
                    best = min(best, d - r - RADIUS)
            got = c.distances[rows[(f"SP{g // 6} leg {g % 6}", "payload")]]
            assert got == pytest.approx(best, abs=1e-7)
        for k in range(n):
            got = c.distances[rows[(f"plate {k}", "payload")]]
            assert got == pytest.approx(_disc_sdf(am, plates, k, centre) - RADIUS, abs=1e-12)


def test_the_payload_against_a_scene_and_named_in_the_messages(am):
    """A sphere and the floor in closed form, a box through coal on shapes built here; a box
    through the payload is a collision between ``payload`` and the box."""
    plates = np.array([m.homogeneous for m in am.home])
    centre = _centre(am, plates)
    box = {"size": [0.1, 0.2, 0.05], "pose": [*(centre + np.array([0.08, 0.0, 0.02])).tolist(), 0.3, 0.2, 0.1]}
    ball = {"radius": 0.03, "center": (centre + np.array([0.0, -0.1, 0.05])).tolist()}
    scene = scene_from_dict({"floor": {"z": 0.0}, "obstacles": [{"box": box}, {"sphere": ball}]})
    c = clearance(am, plates, scene)
    rows = _rows(c)
    got_ball = c.distances[rows[("payload", "sphere 1")]]
    assert got_ball == pytest.approx(np.linalg.norm(centre - ball["center"]) - 0.03 - RADIUS, abs=1e-12)
    assert c.distances[rows[("payload", "floor")]] == pytest.approx(centre[2] - RADIUS, abs=1e-12)
    shape = coal.Box(*box["size"])
    frame = coal.Transform3s(pin.exp3(np.array(box["pose"][3:])), np.array(box["pose"][:3]))
    want = coal.distance(
        coal.Sphere(RADIUS),
        coal.Transform3s(np.eye(3), centre),
        shape,
        frame,
        coal.DistanceRequest(),
        coal.DistanceResult(),
    )
    r = rows[("payload", "box 0")]
    assert c.exact[r] and c.distances[r] == pytest.approx(want, abs=1e-6) and want < 0
    state = evaluate_state(am, plates, scene=scene)
    assert not state.feasible and state.clearance.between == ("payload", "box 0")
    assert any(v.kind == "collision" and v.between == ("payload", "box 0") for v in state.violations)
    a, _ = c.witness_points()
    assert np.linalg.norm(a - centre) == pytest.approx(RADIUS, abs=1e-9)


def test_the_payload_rows_derivatives_against_central_differences(am):
    """∂d/∂η_k of the payload's rows, η_k a world twist of plate k (plate n carries it)."""
    scene = scene_from_dict(
        {"floor": {"z": 0.0}, "obstacles": [{"sphere": {"radius": 0.05, "center": [0.3, 0.0, 1.2]}}]}
    )
    plates = _pose(am, 0.05, 5)
    c = clearance(am, plates, scene)
    rows = np.array([r for r, (i, j) in enumerate(c.pairs) if "payload" in (c.names[i], c.names[j])])
    grad = c.gradient(rows)
    h = 1e-6
    for k in range(len(plates)):
        for a in range(6):
            values = []
            for sign in (1.0, -1.0):
                eta = np.zeros(6)
                eta[a] = sign * h
                moved = plates.copy()
                moved[k] = (pin.exp6(eta) * pin.SE3(plates[k])).homogeneous
                values.append(clearance(am, moved, scene).distances[rows])
            assert np.abs(grad[:, k, a] - (values[0] - values[1]) / (2 * h)).max() < 1e-6, (k, a)


def test_no_radius_no_payload_body():
    am = ap.AssemblerModel.from_config()
    assert am.config.payload.radius == 0.0 and "payload" not in clearance(am, am.home, Scene((), 0.0)).names
    for bad in (-0.01, 1.5, float("nan"), "big"):
        with pytest.raises(ConfigError, match=r"payload\.radius"):
            load_config({"payload": {"radius": bad}})
