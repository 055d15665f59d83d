"""MuJoCo as a second engine: its contacts between the same capsules and plates.

The tests build their own MJCF of one pose: each leg's motor and shaft a capsule, each plate a
cylinder, every body free (MuJoCo does not collide two bodies welded to the world), every geom
with a margin, so ``mj_forward`` reports a contact, with its distance, for every pair closer
than the margin. Pairs the rule trims or leaves out (a leg's own two capsules, legs sharing a
node, a leg and its own plates) are excluded; MuJoCo's distance of every other leg pair, and of a leg and
another platform's plate, is the package's.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import assembler_pin as ap
from assembler_pin.collision import clearance
from assembler_pin.collision.bodies import MOTOR, SHAFT, leg_segments, stack_bodies
from assembler_pin.collision.pairs import pair_table

mujoco = pytest.importorskip("mujoco")

MARGIN = 0.08  # [m] MuJoCo reports the pairs closer than twice this


def _fmt(v) -> str:
    return " ".join(f"{x:.17g}" for x in v)


def _model(am, plates):
    """The MJCF of one pose, and for each MuJoCo body the package's body index (leg g or 6n + k)."""
    b = stack_bodies(am, plates)
    cfg = am.config
    G = len(b.length)
    xml, owner = [], []
    for g in range(G):
        for part in (MOTOR, SHAFT):
            start, vec, *_, radius = (x[0] for x in leg_segments(b, np.array([g]), np.array([part])))
            xml.append(
                f'<body name="c{g}_{part}"><freejoint/><geom type="capsule" size="{radius}" '
                f'fromto="{_fmt(start)} {_fmt(start + vec)}" margin="{MARGIN}"/></body>'
            )
            owner.append(g)
    for k in range(len(b.p)):
        quat = pin.Quaternion(b.R[k]).coeffs()  # x, y, z, w
        xml.append(
            f'<body name="p{k}" pos="{_fmt(b.p[k])}" quat="{quat[3]} {quat[0]} {quat[1]} {quat[2]}"><freejoint/>'
            f'<geom type="cylinder" size="{cfg.plate.radius} {0.5 * cfg.plate.thickness}" margin="{MARGIN}"/></body>'
        )
        owner.append(G + k)
    t = pair_table(cfg)
    shared = {(int(a), int(c)) for a, c, tr in zip(t.leg_a, t.leg_b, t.trim, strict=True) if tr.any()}
    own = {(g, g // 6 + end) for g in range(G) for end in (0, 1)}  # whole capsules here: not trimmed
    names = [f"c{g}_{p}" for g in range(G) for p in (MOTOR, SHAFT)] + [f"p{k}" for k in range(len(b.p))]
    excludes = []
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            oi, oj = owner[i], owner[j]
            skip = oi == oj or (min(oi, oj), max(oi, oj)) in shared
            skip |= oi < G <= oj and (oi, oj - G) in own
            skip |= oi >= G and oj >= G  # plate pairs: not compared here
            if skip:
                excludes.append(f'<exclude body1="{names[i]}" body2="{names[j]}"/>')
    text = (
        '<mujoco><option gravity="0 0 0"/><worldbody>'
        + "".join(xml)
        + "</worldbody><contact>"
        + "".join(excludes)
        + "</contact></mujoco>"
    )
    return mujoco.MjModel.from_xml_string(text), owner


def _mujoco_distances(am, plates) -> dict[tuple[int, int], float]:
    model, owner = _model(am, plates)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    out: dict[tuple[int, int], float] = {}
    for c in data.contact[: data.ncon]:
        a, b = owner[model.geom_bodyid[c.geom1] - 1], owner[model.geom_bodyid[c.geom2] - 1]
        key = (min(a, b), max(a, b))
        out[key] = min(out.get(key, np.inf), float(c.dist))
    return out


@pytest.mark.parametrize("pose", ["perturbed", "twisted"])
def test_mujoco_contacts_are_the_package_distances(pose):
    am = ap.AssemblerModel.from_config()
    if pose == "perturbed":
        rng = np.random.default_rng(3)
        plates = [am.home[0].homogeneous] + [(pin.exp6(rng.normal(size=6) * 0.05) * m).homogeneous for m in am.home[1:]]
    else:
        plates = np.array([m.homogeneous for m in am.home])
        plates[1:, :3, :3] = pin.exp3(np.array([0.0, 0.0, np.deg2rad(110.0)]))
    c = clearance(am, plates)
    G = 6 * am.config.platforms
    ours = {(int(a), int(b)): float(d) for (a, b), d, e in zip(c.pairs, c.distances, c.exact, strict=True) if e}
    theirs = _mujoco_distances(am, plates)
    legs = {k: v for k, v in theirs.items() if k[1] < G}
    assert len(legs) >= 3
    for key, dist in legs.items():  # capsule pairs: MuJoCo's closed form, to rounding
        assert ours[key] == pytest.approx(dist, abs=1e-9), key
    near = {k for k, v in ours.items() if v < 1.5 * MARGIN and k[1] < G and k not in _shared(am)}
    assert near <= set(legs)  # MuJoCo reports every leg pair the package finds near
    for key, dist in theirs.items():  # a leg and another platform's plate: coal and MuJoCo
        if key[1] >= G and key in ours:
            assert ours[key] == pytest.approx(dist, abs=1e-4), key


def _shared(am) -> set[tuple[int, int]]:
    t = pair_table(am.config)
    return {(int(a), int(b)) for a, b, tr in zip(t.leg_a, t.leg_b, t.trim, strict=True) if tr.any()}
