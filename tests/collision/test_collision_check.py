"""The clearance of a pose against independent computations: the tests' own segment
distances and trim rule, coal as a second engine, finite differences for the derivatives,
and the poses the issue names (crossing legs, a plate through the floor, home, scenarios)."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest
from checks import brute_segment_distance

import assembler_pin as ap
from assembler_pin.collision import Scene, clearance, read_scene, scene_from_dict
from assembler_pin.collision.bodies import MOTOR, SHAFT, leg_segments, stack_bodies, stack_body_names
from assembler_pin.collision.pairs import pair_table
from assembler_pin.common.messages import binding, describe
from assembler_pin.exceptions import SceneError
from assembler_pin.scenarios import SCENARIOS
from assembler_pin.state import evaluate_state


@pytest.fixture(scope="module")
def am():
    return ap.AssemblerModel.from_config()


def _twisted(am, degrees: float) -> np.ndarray:
    """Home, with plates 1..n turned about their own z by ``degrees``: SP0's legs twist."""
    R = pin.exp3(np.array([0.0, 0.0, np.deg2rad(degrees)]))
    plates = np.array([m.homogeneous for m in am.home])
    plates[1:, :3, :3] = R
    return plates


def _perturbed(am, scale: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    out = [am.home[0].homogeneous]
    for k in range(1, len(am.home)):
        out.append((pin.exp6(rng.normal(size=6) * scale) * am.home[k]).homogeneous)
    return np.array(out)


def _leg_ends(am, plates, g):
    b = stack_bodies(am, plates)
    return b.bottom[g], b.top[g]


def _independent_leg_distance(am, plates, ga: int, gb: int, trims: tuple[bool, bool, bool, bool]) -> float:
    """Two legs' distance from their joint centres alone: each leg is the motor (0 to
    motor_length from the bottom joint, motor_radius) and the shaft (to the top joint,
    shaft_radius), trimmed by node_zone at the ends asked; the tests' own minimizer."""
    leg = am.config.leg
    best = np.inf
    segments = []
    for g, (trim_b, trim_t) in ((ga, trims[:2]), (gb, trims[2:])):
        b, t = _leg_ends(am, plates, g)
        L = np.linalg.norm(t - b)
        u = (t - b) / L
        parts = []
        for lo, hi, r in ((0.0, leg.motor_length, leg.motor_radius), (leg.motor_length, L, leg.shaft_radius)):
            lo = max(lo, leg.node_zone) if trim_b else lo
            hi = min(hi, L - leg.node_zone) if trim_t else hi
            if hi >= lo:
                parts.append((b + lo * u, (hi - lo) * u, r))
        segments.append(parts)
    for p1, d1, r1 in segments[0]:
        for p2, d2, r2 in segments[1]:
            best = min(best, brute_segment_distance(p1, d1, p2, d2) - r1 - r2)
    return best


def _row(c, a: str, b: str) -> int:
    names = c.names
    for k, (i, j) in enumerate(c.pairs):
        if {names[i], names[j]} == {a, b}:
            return k
    raise AssertionError(f"no pair {a} / {b}")


def test_pair_rule(am):
    t = pair_table(am.config)
    assert len(t.leg_a) == 24 * 23 // 2  # every leg pair
    assert t.trim.any(axis=1).sum() == 4 * 6 + 3 * 3 * 4  # node pairs: in a platform, and across a plate
    platform = np.arange(24) // 6
    own = np.array([k in (platform[g], platform[g] + 1) for g, k in t.leg_plate])
    assert len(t.leg_plate) == 24 * 5 and own.sum() == 48 and len(t.plate_pairs) == 10
    g, k = t.leg_plate[:, 0], t.leg_plate[:, 1]  # its own plates: only beyond the joint there
    assert np.array_equal(t.leg_plate_trim[:, 0], own & (k == platform[g]))
    assert np.array_equal(t.leg_plate_trim[:, 1], own & (k == platform[g] + 1))


def test_home_is_clear_and_measured_independently(am):
    c = clearance(am, am.home)
    assert c.clear and c.between == ("SP0 leg 0", "plate 0")  # the motor beyond its joint's zone
    want = _independent_leg_plate_distance(am, am.home, 0, 0, (True, False))
    assert c.min_distance == pytest.approx(want, abs=1e-7)
    pair = _independent_leg_distance(am, am.home, 0, 1, (True, False, True, False))  # they share the bottom node
    assert c.distances[_row(c, "SP0 leg 0", "SP0 leg 1")] == pytest.approx(pair, abs=1e-7) and pair > want
    state = evaluate_state(am, am.home)
    assert state.feasible and state.to_dict()["clearance"]["between"] == ["SP0 leg 0", "plate 0"]


def _independent_leg_plate_distance(am, plates, g: int, k: int, trims: tuple[bool, bool]) -> float:
    """A leg against a plate through coal on shapes built here: the leg's motor and shaft as
    capsules between its joint centres (trimmed by node_zone at the ends asked), the plate as
    a cylinder of its configured radius and thickness at its pose."""
    leg, plate = am.config.leg, am.config.plate
    b, t = _leg_ends(am, plates, g)
    L = np.linalg.norm(t - b)
    u = (t - b) / L
    frame = pin.SE3(plates[k]) if np.ndim(plates[k]) == 2 else plates[k]
    disc = (coal.Cylinder(plate.radius, plate.thickness), coal.Transform3s(frame.rotation, frame.translation))
    best = np.inf
    for lo, hi, r in ((0.0, leg.motor_length, leg.motor_radius), (leg.motor_length, L, leg.shaft_radius)):
        lo = max(lo, leg.node_zone) if trims[0] else lo
        hi = min(hi, L - leg.node_zone) if trims[1] else hi
        if hi < lo:
            continue
        R = ap.model.geometry.rotation_z_to(u)
        capsule = (coal.Capsule(r, max(hi - lo, 1e-12)), coal.Transform3s(R, b + 0.5 * (lo + hi) * u))
        best = min(best, coal.distance(*capsule, *disc, coal.DistanceRequest(), coal.DistanceResult()))
    return best


#: A valid pose (lengths, deflections, forces in range) with plates 1..n moved rigidly by this
#: twist of plate 1's frame: SP0 leg 0's motor lies 0.2 mm from the base plate, beyond its
#: joint's zone; every other pair is at least 23 mm apart.
MOTOR_ON_ITS_BASE = (-0.10346718, 0.08167104, -0.05137056, -0.07158892, -0.36744152, 0.44717051)


def _moved_rigidly(am, twist) -> np.ndarray:
    home = [m.homogeneous for m in am.home]
    frame = pin.SE3(home[1])
    move = frame * pin.exp6(np.array(twist)) * frame.inverse()
    return np.array([home[0]] + [(move * pin.SE3(h)).homogeneous for h in home[1:]])


def test_a_leg_against_its_own_plates_beyond_the_joint_zone(am):
    """The motor near its own base plate is a collision, named and measured by coal on shapes
    built here; every leg against its own two plates, on random poses, the same way."""
    plates = _moved_rigidly(am, MOTOR_ON_ITS_BASE)
    state = evaluate_state(am, plates)
    assert [v.kind for v in state.violations] == ["collision"]
    c = state.clearance
    assert c.between == ("SP0 leg 0", "plate 0") and 0 <= c.min_distance < 0.001
    assert c.min_distance == pytest.approx(_independent_leg_plate_distance(am, plates, 0, 0, (True, False)), abs=1e-6)
    G = 6 * am.n
    offset = c.pairs[:, 1] - G - c.pairs[:, 0] // 6
    own = (c.pairs[:, 0] < G) & (offset >= 0) & (offset <= 1)
    assert own.sum() == 2 * G and c.distances[~own].min() > 0.02  # the rule before: clear by 23 mm
    checked = 0
    for pose in (am.home, _perturbed(am, 0.05, 3), _perturbed(am, 0.1, 8), plates):
        c = clearance(am, pose)
        for g in range(6 * am.n):
            for end in (0, 1):
                k = g // 6 + end
                row = _row(c, f"SP{g // 6} leg {g % 6}", f"plate {k}")
                want = _independent_leg_plate_distance(am, pose, g, k, (end == 0, end == 1))
                if c.exact[row]:
                    assert c.distances[row] == pytest.approx(want, abs=1e-6), (g, k)
                    checked += 1
                else:
                    assert c.distances[row] <= want + 1e-9, (g, k)  # a lower bound
    assert checked >= 100


def test_crossing_legs_are_a_collision(am):
    plates = _twisted(am, 130.0)
    c = clearance(am, plates)
    assert c.between == ("SP0 leg 0", "SP0 leg 2")  # no shared node: checked whole
    want = _independent_leg_distance(am, plates, 0, 2, (False, False, False, False))
    assert c.min_distance == pytest.approx(want, abs=1e-7) and want < 0
    state = evaluate_state(am, plates)
    assert not state.feasible
    v = binding([v for v in state.violations if v.kind == "collision"])
    assert v is not None and v.between == ("SP0 leg 0", "SP0 leg 2")
    text = describe(v)
    assert text.startswith("collision: SP0 leg 0 and SP0 leg 2") and " m apart, clearance 0.005 m" in text
    assert state.to_dict()["violations"][-1]["between"] == ["SP0 leg 0", "SP0 leg 2"]


def test_a_plate_through_the_floor_is_a_collision(am):
    scene = Scene((), floor_z=0.24)  # plate 1's lower face is at home_height - thickness / 2
    state = evaluate_state(am, am.home, scene=scene)
    assert not state.feasible and any(v.kind == "collision" and "floor" in v.between for v in state.violations)
    c = state.clearance
    want = am.config.home_height - 0.5 * am.config.plate.thickness - 0.24
    assert c.distances[_row(c, "plate 1", "floor")] == pytest.approx(want, abs=1e-12) and want < 0
    assert not any("plate 0" in (c.names[i], c.names[j]) and "floor" in (c.names[i], c.names[j]) for i, j in c.pairs)


def test_every_leg_pair_against_coal(am):
    """A random pose: each leg pair's distance through coal's capsules (the same trimmed
    segments) equals the closed form wherever the two are apart."""
    plates = _perturbed(am, 0.05, 3)
    c = clearance(am, plates)
    b = stack_bodies(am, plates)
    t = pair_table(am.config)
    req = coal.DistanceRequest()
    checked = 0
    for k in range(len(t.leg_a)):
        ga, gb = int(t.leg_a[k]), int(t.leg_b[k])
        best = np.inf
        for pa in (MOTOR, SHAFT):
            for pb in (MOTOR, SHAFT):
                sa, va, loa, hia, _, ra = leg_segments(b, np.array([ga]), np.array([pa]), t.trim[k, 0], t.trim[k, 1])
                sb, vb, lob, hib, _, rb = leg_segments(b, np.array([gb]), np.array([pb]), t.trim[k, 2], t.trim[k, 3])
                if hia[0] < loa[0] or hib[0] < lob[0]:
                    continue
                shapes = []
                for s, v, r in ((sa[0], va[0], ra[0]), (sb[0], vb[0], rb[0])):
                    length = float(np.linalg.norm(v))
                    R = ap.model.geometry.rotation_z_to(v / length)
                    shapes += [coal.Capsule(float(r), length), coal.Transform3s(R, s + 0.5 * v)]
                best = min(best, coal.distance(*shapes, req, coal.DistanceResult()))
        row = _row(c, f"SP{ga // 6} leg {ga % 6}", f"SP{gb // 6} leg {gb % 6}")
        if best > 1e-3:
            assert c.distances[row] == pytest.approx(best, abs=1e-6)
            checked += 1
    assert checked > 200


TRUSS = {
    "floor": {"z": 0.0},
    "obstacles": [
        {"sphere": {"radius": 0.05, "center": [0.2, 0.0, 0.35]}},
        {"box": {"size": [0.1, 0.2, 0.05], "pose": [-0.25, 0.05, 0.55, 0.3, 0.2, 0.1]}},
        {"cylinder": {"radius": 0.02, "length": 0.8, "pose": [0.05, 0.25, 0.7, 1.4, 0.1, 0.0]}},
    ],
}


def test_derivatives_against_central_differences(am):
    """∂d/∂η_k of every measured pair within 0.1 m, η_k a world twist of plate k: closed-form
    pairs to 1e-6, pairs measured by coal (legs and plates against plates, boxes, cylinders)
    to 1e-4 when apart (GJK on curved shapes) and 1e-3 when overlapping (EPA's depth)."""
    scene = scene_from_dict(TRUSS)
    plates = _perturbed(am, 0.04, 7)
    c = clearance(am, plates, scene)
    rows = np.flatnonzero(c.exact & (c.distances < 0.1))
    kinds = {
        tuple(sorted(("leg" if "leg" in c.names[i] else c.names[i].split()[0]) for i in pair)) for pair in c.pairs[rows]
    }
    assert len(rows) > 20 and len(kinds) >= 4, kinds
    grad = c.gradient(rows)
    h = 1e-6
    fd = np.zeros_like(grad)
    pairs = [tuple(p) for p in c.pairs[rows]]
    for k in range(len(plates)):
        for a in range(6):
            values = []
            for sign in (1.0, -1.0):
                eta = np.zeros(6)
                eta[a] = sign * h
                moved = plates.copy()
                moved[k] = (pin.exp6(eta) * pin.SE3(plates[k])).homogeneous
                other = clearance(am, moved, scene)
                lookup = {tuple(p): d for p, d in zip(other.pairs.tolist(), other.distances, strict=True)}
                values.append(np.array([lookup[p] for p in pairs]))
            fd[:, k, a] = (values[0] - values[1]) / (2 * h)
    err = np.abs(grad - fd).max(axis=(1, 2))
    names = [(c.names[i], c.names[j]) for i, j in c.pairs[rows]]
    through_coal = np.array(["plate" in a + b or "box" in b or "cylinder" in b for a, b in names])
    apart = c.distances[rows] > 1e-3
    tol = np.where(through_coal, np.where(apart, 1e-4, 1e-3), 1e-6)
    bad = np.flatnonzero(err > tol)
    assert not len(bad), [(names[i], err[i], c.distances[rows[i]]) for i in bad]
    assert (~through_coal).sum() > 20 and through_coal.sum() >= 3


@pytest.fixture(scope="module")
def scenario_states(am):
    out = {}
    for sc in SCENARIOS.values() if isinstance(SCENARIOS, dict) else SCENARIOS:
        result = ap.solver.pipeline.solve(am, sc.goal)
        out[sc.name] = (sc, result)
    return out


def test_scenario_poses_are_clear(am, scenario_states):
    for name, (sc, result) in scenario_states.items():
        scene = Scene((), sc.floor_z)
        for state in (result.initial, result.best):
            c = clearance(am, state.plates, scene)
            assert c.clear, (name, c)


def test_the_truss_bay_strut_crosses_the_translation_optimum(am, scenario_states):
    scene = read_scene("examples/truss_bay.yaml")
    assert clearance(am, am.home, scene).clear
    _, result = scenario_states["translation"]
    state = evaluate_state(am, result.best.plates, scene=scene)
    assert not state.feasible
    assert state.clearance.between[1] == "lower strut" and state.clearance.min_distance < 0


def _adversarial(am) -> list[np.ndarray]:
    """Poses that stress the closed forms: home, random leans small and large, crossing legs,
    every plate on the base (legs of nearly zero length), plates turned upside down, and
    translations only (parallel legs across platforms)."""
    poses = [np.array([m.homogeneous for m in am.home]), _twisted(am, 130.0)]
    poses += [_perturbed(am, scale, seed) for seed, scale in ((3, 0.05), (11, 0.1), (12, 0.3), (13, 0.6))]
    flat = np.array([m.homogeneous for m in am.home])
    flat[:, :3, 3] = flat[0, :3, 3]
    flipped = np.array([m.homogeneous for m in am.home])
    flipped[2:, :3, :3] = np.diag([1.0, -1.0, -1.0])
    shifted = np.array([m.homogeneous for m in am.home])
    shifted[:, 0, 3] += 0.3 * np.arange(len(shifted))
    return [*poses, flat, flipped, shifted]


def test_the_compiled_kernel_equals_its_numpy_reference(am):
    """The kernel's arrays (joint centres, leg-pair rows, screens' bounds) against the tests'
    numpy version on adversarial and 40 random poses: distances and points to 1e-12 m."""
    from clearance_reference import reference_own_pairs

    from assembler_pin.collision.kernel import kernel_inputs, own_pairs
    from assembler_pin.kinematics import plate_arrays

    inp = kernel_inputs(am.config)
    P, m = len(inp.va) // 4, len(inp.va) // 4 + len(inp.leg_plate) + len(inp.plate_pairs)
    inp_a, inp_b = inp.va[::4] // 8, inp.vb[::4] // 8
    leg = am.config.leg
    poses = _adversarial(am) + [_perturbed(am, 0.15, 100 + s) for s in range(40)]
    for plates in poses:
        pa = plate_arrays(am, plates)
        got_d, ref_d = np.full(m, np.nan), np.full(m, np.nan)
        got_e, ref_e = np.zeros(m, bool), np.zeros(m, bool)
        got = own_pairs(inp, pa.R, pa.p, got_d, P, got_e)
        ref = reference_own_pairs(am.config, pa.R, pa.p, ref_d, P, ref_e)
        np.testing.assert_allclose(got_d, ref_d, rtol=0, atol=1e-12)
        np.testing.assert_allclose(got.btu, ref.btu, rtol=0, atol=1e-12)
        np.testing.assert_allclose(got.length, ref.length, rtol=0, atol=1e-12)
        np.testing.assert_allclose(got.lp, ref.lp, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(got.lp_end, ref.lp_end)
        np.testing.assert_array_equal(got.lp_row, ref.lp_row)
        np.testing.assert_array_equal(got_e, ref_e)
        same = (np.abs(got.legs - ref.legs).max(axis=1) <= 1e-9) | np.isinf(got_d[:P])  # inf: trimmed away
        assert same.mean() > 0.99
        for legs in (got.legs, ref.legs):  # elsewhere a tie (parallel axes): both witnesses realize it
            for side, g in ((0, inp_a), (1, inp_b)):
                x = legs[:, 3 * side : 3 * side + 3]
                on_axis = got.btu[0][g] + legs[:, 9 + side, None] * got.btu[2][g]
                np.testing.assert_allclose(x, on_axis, rtol=0, atol=1e-12)
            gap = np.linalg.norm(legs[~same, 0:3] - legs[~same, 3:6], axis=1)
            radii = np.add.outer([leg.motor_radius, leg.shaft_radius], [leg.motor_radius, leg.shaft_radius]).ravel()
            assert (np.abs(gap[:, None] - radii - got_d[:P][~same, None]).min(axis=1) < 1e-12).all()


def test_a_scene_leaves_the_stack_s_own_pairs_as_they_are(am):
    """Every pair of the stack alone has the same distance with a scene around it (the
    leg–plate pairs coal measures included, whatever obstacles are measured after them)."""
    scene = scene_from_dict({"obstacles": [{"cylinder": {"radius": 0.01, "length": 0.5, "pose": [3, 0, 1, 0, 0, 0]}}]})
    for seed in range(6):
        plates = _perturbed(am, 0.25, seed)
        alone, around = clearance(am, plates), clearance(am, plates, scene)
        measured = {tuple(p): d for p, d, e in zip(around.pairs, around.distances, around.exact, strict=True) if e}
        for pair, d, exact in zip(alone.pairs, alone.distances, alone.exact, strict=True):
            if exact and tuple(pair) in measured:
                assert measured[tuple(pair)] == pytest.approx(d, abs=1e-9), pair


def test_standing_plates_are_not_checked_against_the_floor(am):
    """A plate on the floor (a walk's foot) and its legs' node zones are left out when it
    stands; the rest of those legs is measured, by the test's own lowest-point formula."""
    import dataclasses

    n = am.n
    plates = np.array([m.homogeneous for m in am.home])
    floor = float(plates[n, 2, 3])  # the floor through plate n's joint plane
    free = clearance(am, plates, Scene((), floor_z=floor))
    assert free.distances[_row(free, f"plate {n}", "floor")] == pytest.approx(-0.5 * am.config.plate.thickness)
    stood = clearance(am, plates, Scene((), floor_z=floor, standing=(0, n)))
    on_floor = [stood.names[i] for i, j in stood.pairs if stood.names[j] == "floor"]
    assert f"plate {n}" not in on_floor and "plate 0" not in on_floor and "plate 1" in on_floor
    b = stack_bodies(am, plates)
    leg, zone = am.config.leg, am.config.leg.node_zone
    for g in range(6 * (n - 1), 6 * n):  # the last platform's legs: their top zone is left out
        # each part's lowest point: the motor on [0, motor_length], the shaft up to L - zone
        z = b.bottom[g, 2] + np.array([0.0, leg.motor_length, b.length[g] - zone]) * b.axis[g, 2]
        motor = min(z[0], z[1]) - leg.motor_radius
        shaft = min(z[1], z[2]) - leg.shaft_radius
        want = min(motor, shaft) - floor
        got = stood.distances[_row(stood, f"SP{n - 1} leg {g % 6}", "floor")]
        assert got == pytest.approx(want, abs=1e-12)
    with pytest.raises(SceneError, match="beyond plate"):
        clearance(am, plates, dataclasses.replace(Scene((), floor_z=floor), standing=(n + 1,)))
    with pytest.raises(SceneError, match="standing"):
        Scene((), standing=[0])  # type: ignore[arg-type]


def test_a_turned_model_measures_the_original_bodies(am):
    """The stack modelled from its EE plate has the original's bodies (the motor at the lower
    joint of the physical leg): the same distances at the same pose, the derivatives in the
    turned plate order, held to central differences in the turned model's own twists."""
    from assembler_pin.supports.turned import turned_model

    tm = turned_model(am)
    plates = _perturbed(am, 0.03, 11)
    scene = scene_from_dict(TRUSS)
    c = clearance(am, plates, scene)
    turned = tm.plates(plates)
    t = clearance(tm.model, turned, Scene(scene.obstacles, scene.floor_z, standing=(am.n,)))
    assert np.array_equal(c.pairs, t.pairs) and np.abs(c.distances - t.distances).max() < 1e-12
    assert t.between == c.between
    rows = np.flatnonzero(t.exact & (t.distances < 0.1))[:12]
    grad = t.gradient(rows)
    h = 1e-6
    for k in (1, am.n - 1):
        for a in (0, 4):
            values = []
            for sign in (1.0, -1.0):
                eta = np.zeros(6)
                eta[a] = sign * h
                moved = turned.se3_list() if hasattr(turned, "se3_list") else [turned.se3(i) for i in range(am.n + 1)]
                moved[k] = pin.exp6(eta) * moved[k]
                other = clearance(tm.model, moved, Scene(scene.obstacles, scene.floor_z, standing=(am.n,)))
                values.append(other.distances[rows])
            fd = (values[0] - values[1]) / (2 * h)
            assert np.abs(grad[:, k, a] - fd).max() < 1e-4, (k, a)


def _scene_with_extras(seed: int) -> Scene:
    """The truss bay and, around the stack, four more boxes, cylinders and spheres each."""
    import yaml

    with open("examples/truss_bay.yaml") as f:
        doc = yaml.safe_load(f)
    rng = np.random.default_rng(seed)
    for i in range(4):
        where = [*rng.uniform(-0.3, 0.3, 2), rng.uniform(0.15, 1.1)]
        turn = rng.uniform(-1.5, 1.5, 3).tolist()
        ball = {"radius": float(rng.uniform(0.02, 0.08)), "center": [where[1], where[0], where[2]]}
        doc["obstacles"] += [
            {"name": f"box {i}", "box": {"size": rng.uniform(0.02, 0.2, 3).tolist(), "pose": [*where, *turn]}},
            {"name": f"rod {i}", "cylinder": {"radius": 0.02, "length": 0.3, "pose": [*where[::-1], *turn]}},
            {"name": f"ball {i}", "sphere": ball},
        ]
    return scene_from_dict(doc)


def test_the_scene_pass_equals_one_obstacle_at_a_time(am):
    """Every obstacle of a kind in one pass gives each pair what a scene of that obstacle alone
    (or the floor alone, or the stack alone) gives it: closed forms to 1e-12 m, coal's
    measurements exactly, the bounds of pairs left out to 1e-12 m; a pair measured in one and
    only bounded in the other has its bound below its distance."""
    scene = _scene_with_extras(4)
    own = set(stack_body_names(am.n))
    closed_form = {o.name for o in scene.obstacles if o.kind == "sphere"} | {"floor"}
    coal_rows = closed_rows = 0
    for seed in (21, 22):
        plates = _perturbed(am, 0.06, seed)
        c = clearance(am, plates, scene)
        got = {(c.names[i], c.names[j]): (d, e) for (i, j), d, e in zip(c.pairs, c.distances, c.exact, strict=True)}
        assert len(got) == len(c.pairs)  # one row per pair
        seen = 0
        parts = [Scene((), scene.floor_z)] + [Scene((o,)) for o in scene.obstacles]
        for k, part in enumerate(parts):
            ref = clearance(am, plates, part)
            for (i, j), d, exact in zip(ref.pairs, ref.distances, ref.exact, strict=True):
                a, b = ref.names[i], ref.names[j]
                if k and b in own:
                    continue  # the stack's own pairs: compared once, in the first part
                seen += 1
                d_all, exact_all = got[(a, b)]
                if b in closed_form or ("leg" in a and "leg" in b):
                    assert exact and exact_all and abs(d_all - d) <= 1e-12, (a, b, d_all, d)
                    closed_rows += b in closed_form and d < 0.1
                elif exact and exact_all:
                    assert d_all == d, (a, b, d_all, d)
                    coal_rows += b not in own
                elif not exact and not exact_all:
                    assert abs(d_all - d) <= 1e-12, (a, b, d_all, d)
                else:  # measured in one only: the other's bound is below the distance
                    bound, measured = (d_all, d) if exact else (d, d_all)
                    assert bound <= measured + 1e-10, (a, b, bound, measured)
        assert seen == len(c.pairs)  # every row of the whole scene compared
    assert coal_rows >= 6 and closed_rows >= 10, (coal_rows, closed_rows)


def _plate_sdf(am, plates, k: int, x: np.ndarray) -> float:
    """Signed distance [m] of the point x to plate k's solid disc (the tests' own closed form)."""
    frame = pin.SE3(plates[k])
    local = frame.rotation.T @ (x - frame.translation)
    q = np.array(
        [np.hypot(local[0], local[1]) - am.config.plate.radius, abs(local[2]) - 0.5 * am.config.plate.thickness]
    )
    return float(np.linalg.norm(np.maximum(q, 0.0)) + min(q.max(), 0.0))


def test_witness_points_lie_on_both_surfaces_at_the_motor_shaft_junction(am):
    """A leg deep in a plate, its closest point on the shaft's end at the motor/shaft junction
    (a random lean, seed 77): the witness on the leg is on the shaft's surface, the other on
    the plate's, by the tests' own distance to each."""
    rng = np.random.default_rng(77)
    plates = np.array(
        [am.home[0].homogeneous] + [(pin.exp6(rng.normal(size=6) * 0.15) * m).homogeneous for m in am.home[1:]]
    )
    c = clearance(am, plates)
    assert c.between == ("SP1 leg 4", "plate 3") and c.min_distance < -0.1
    a, b = c.witness_points()
    bottom, top = _leg_ends(am, plates, 10)
    u = (top - bottom) / np.linalg.norm(top - bottom)
    leg = am.config.leg
    shaft = (bottom + leg.motor_length * u, top)
    assert _point_segment(a, *shaft) == pytest.approx(leg.shaft_radius, abs=1e-6)
    x = a + leg.shaft_radius * (a - b) / c.min_distance  # its point on the axis: at the junction
    assert np.dot(x - bottom, u) == pytest.approx(leg.motor_length, abs=1e-6)
    assert _plate_sdf(am, plates, 3, b) == pytest.approx(0.0, abs=1e-6)
    assert np.linalg.norm(a - b) == pytest.approx(-c.min_distance, abs=1e-12)


def _point_segment(x, p, q) -> float:
    d = q - p
    t = np.clip(np.dot(x - p, d) / np.dot(d, d), 0.0, 1.0)
    return float(np.linalg.norm(x - p - t * d))
