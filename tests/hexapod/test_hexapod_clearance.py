"""The hexapod's clearance held to coal's distance of every pair, measured one by one."""

from __future__ import annotations

import coal
import numpy as np
import pytest
from pinocchio import exp3 as pin_exp3

import assembler_pin as ap
from assembler_pin.collision.bodies import stack_bodies
from assembler_pin.hexapod import hexapod_clearance, ring_stacks, stand


def _z_to(u):
    helper = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, u)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(u, x), u])


def _solids(am, plates, stack, skip_ee=False, trim_last=False):
    """Every body of one stack as (name, coal shape, transform), written from the sizes."""
    cfg = am.config
    leg = cfg.leg
    b = stack_bodies(am, plates)
    out = []
    for g in range(6 * am.n):
        u, L = b.axis[g], b.length[g]
        top = L - leg.node_zone if trim_last and g >= 6 * (am.n - 1) else L
        for name, lo, hi, r in (
            ("motor", 0.0, min(leg.motor_length, top), leg.motor_radius),
            ("shaft", leg.motor_length, top, leg.shaft_radius),
        ):
            if hi <= lo:
                continue
            centre = b.bottom[g] + 0.5 * (lo + hi) * u
            out.append((f"stack {stack} leg {g} {name}", coal.Capsule(r, hi - lo), coal.Transform3s(_z_to(u), centre)))
    for j in range(am.n + (0 if skip_ee else 1)):
        shape = coal.Cylinder(cfg.plate.radius, cfg.plate.thickness)
        out.append((f"stack {stack} plate {j}", shape, coal.Transform3s(b.R[j], b.p[j])))
    return out


def _distance(a, b):
    req = coal.DistanceRequest()
    req.gjk_tolerance = 1e-12
    return coal.distance(a[1], a[2], b[1], b[2], req, coal.DistanceResult())


@pytest.mark.parametrize("radius", [0.2, 0.35])
def test_the_smallest_distance_is_coals_over_every_pair(radius):
    am = ap.AssemblerModel.from_config({"platforms": 2, "payload": {"mass": 0.0}, "hexapod": {"body_radius": 0.3}})
    stacks = ring_stacks(am, 3, radius)
    result = stand(am, stacks, 10.0, [0.0, 0.0, stacks[0].p[-1, 2] + 0.1])
    got = hexapod_clearance(am, result)
    plates = [result.plates[i] for i in range(3)]
    solids = [_solids(am, p, i) for i, p in enumerate(plates)]
    own = min(ap.collision.clearance(am, p).min_distance for p in plates)
    across = min(_distance(a, b) for i in range(3) for j in range(i + 1, 3) for a in solids[i] for b in solids[j])
    hc = am.config.hexapod
    lift = np.array([0.0, 0.0, 0.5 * am.config.plate.thickness + 0.5 * hc.body_thickness])
    centre = result.plates[:, -1, :3, 3].mean(0) + lift
    body = ("body", coal.Cylinder(hc.body_radius, hc.body_thickness), coal.Transform3s(np.eye(3), centre))
    under = [_solids(am, p, i, skip_ee=True, trim_last=True) for i, p in enumerate(plates)]
    to_body = min(_distance(body, s) for group in under for s in group)
    assert got.min_distance == pytest.approx(min(own, across, to_body), abs=1e-9)
    assert got.clear == (got.min_distance >= am.config.clearance)


def test_a_stand_too_close_or_under_an_obstacle_is_a_collision():
    """Feet 0.19 m from the centre: the plates of neighbouring stacks overlap; a box 2 mm above
    the body: the body and the box are the closest pair, at coal's distance."""
    am = ap.AssemblerModel.from_config({"platforms": 1, "payload": {"mass": 0.0}})
    close = stand(am, ring_stacks(am, 3, 0.19), 5.0, [0.0, 0.0, 0.3])
    assert not close.feasible and close.clearance.min_distance < 0
    assert any("plate 0" in v and "apart" in v for v in close.violations)
    stacks = ring_stacks(am, 3, 0.4)
    top = stacks[0].p[-1, 2] + 0.5 * am.config.plate.thickness + am.config.hexapod.body_thickness
    box = {"size": [0.2, 0.2, 0.1], "pose": [0.1, 0.0, top + 0.002 + 0.05, 0.0, 0.0, 0.0]}
    scene = ap.collision.scene_from_dict({"obstacles": [{"box": box, "name": "beam"}]})
    got = stand(am, stacks, 5.0, [0.0, 0.0, top], scene=scene)
    hc = am.config.hexapod
    turn = pin_exp3(got.body_displacement[3:])
    centre = got.plates[:, -1, :3, 3].mean(0) + turn[:, 2] * 0.5 * (am.config.plate.thickness + hc.body_thickness)
    body = ("body", coal.Cylinder(hc.body_radius, hc.body_thickness), coal.Transform3s(turn, centre))
    beam = ("beam", coal.Box(0.2, 0.2, 0.1), coal.Transform3s(np.eye(3), np.array(box["pose"][:3])))
    assert got.clearance.between == ("body", "beam")
    assert got.clearance.min_distance == pytest.approx(_distance(body, beam), abs=1e-9)
    assert not got.feasible and any("beam" in v for v in got.violations)  # 2 mm < clearance 5 mm
