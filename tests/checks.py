"""Independent checks shared by the test modules.

Nothing here uses the package's own geometry or leg state: anchors, home directions, leg
lengths, deflections and rise are computed again from the design notes (node angles
90° + 60°·j + 120°·m, legs from node m towards the nodes at ±60°), so a check cannot agree
with a bug in :mod:`assembler_pin.kinematics`.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from assembler_pin import solve_statics, stack_forward_kinematics


def design_anchors(cfg, j: int) -> tuple[np.ndarray, np.ndarray]:
    """Bottom (plate j frame) and top (plate j+1 frame) joint centres of SP j, (6, 3) each."""
    r = cfg.plate.node_radius
    half = np.deg2rad(cfg.plate.node_spacing_deg) / 2
    bottom, top = [], []
    for m in range(3):
        node = np.deg2rad(90 + 60 * j + 120 * m)
        for sign in (+1, -1):
            a_b = node + sign * half
            a_t = node + sign * (np.pi / 3 - half)
            bottom.append([r * np.cos(a_b), r * np.sin(a_b), 0.0])
            top.append([r * np.cos(a_t), r * np.sin(a_t), 0.0])
    return np.array(bottom), np.array(top)


def home_height(cfg) -> float:
    """Plate spacing with every leg at mid-stroke and plates parallel [m]."""
    b, t = design_anchors(cfg, 0)
    chord = np.linalg.norm(t[0] - b[0])
    mid = 0.5 * (cfg.leg.min_length + cfg.leg.max_length)
    return float(np.sqrt(mid**2 - chord**2))


def home_directions(cfg, j: int) -> np.ndarray:
    """Home leg directions of SP j (bottom frame), from the design anchors and home height."""
    bottom, top = design_anchors(cfg, j)
    v = top + np.array([0.0, 0.0, home_height(cfg)]) - bottom
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def sp_legs(cfg, j: int, Rb, pb, Rt, pt) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Lengths [m], bottom and top deflections [rad], rise [m] of SP j's legs for world plate poses."""
    bottom, top = design_anchors(cfg, j)
    b = bottom @ Rb.T + pb
    t = top @ Rt.T + pt
    v = t - b
    lengths = np.linalg.norm(v, axis=1)
    u = v / lengths[:, None]
    home = home_directions(cfg, j)
    defl_b = np.arccos(np.clip(np.sum((u @ Rb) * home, axis=1), -1, 1))
    defl_t = np.arccos(np.clip(np.sum((u @ Rt) * home, axis=1), -1, 1))
    rise = (v @ Rb)[:, 2]
    return lengths, defl_b, defl_t, rise


def kinematic_problems(cfg, plates, goal: pin.SE3 | None = None, tol: float = 1e-9) -> list[str]:
    """Every broken kinematic constraint of plate poses (``PlateArrays``), recomputed from the
    design: stroke, deflection at both joints, top joint above bottom joint, EE at the goal."""
    leg = cfg.leg
    out = []
    for j in range(cfg.platforms):
        L, db, dt, rise = sp_legs(cfg, j, plates.R[j], plates.p[j], plates.R[j + 1], plates.p[j + 1])
        if L.min() < leg.min_length - 1e-12 or L.max() > leg.max_length + 1e-12:
            out.append(f"SP{j} length {L.min():.4f}..{L.max():.4f}")
        if max(db.max(), dt.max()) > np.deg2rad(leg.max_deflection_deg) + 1e-9:
            out.append(f"SP{j} deflection {np.rad2deg(max(db.max(), dt.max())):.2f} deg")
        if rise.min() <= 0:
            out.append(f"SP{j} rise {rise.min():.4f}")
    if goal is not None:
        n = cfg.platforms
        if np.linalg.norm(plates.p[n] - goal.translation) > tol:
            out.append("EE position")
        if np.linalg.norm(pin.log3(goal.rotation.T @ plates.R[n])) > tol:
            out.append("EE rotation")
    return out


def assert_feasible(am, state, goal: pin.SE3 | None = None, tol: float = 1e-9) -> None:
    """A state meets every constraint: kinematics from the design (:func:`kinematic_problems`),
    finite forces within the limits, and its leg lengths give back its plates by stack FK."""
    cfg = am.config
    assert kinematic_problems(cfg, state.plates, goal, tol) == []
    forces = solve_statics(am, state.plates).forces
    assert np.all(np.isfinite(forces))
    assert np.all(forces <= cfg.leg.max_tension) and np.all(forces >= -cfg.leg.max_compression)
    lengths = np.array([[np.linalg.norm(
        state.plates.R[j + 1] @ t + state.plates.p[j + 1] - state.plates.R[j] @ b - state.plates.p[j])
        for b, t in zip(*design_anchors(cfg, j), strict=True)] for j in range(cfg.platforms)])  # fmt: skip
    fk = stack_forward_kinematics(am, lengths).raise_if_failed()
    np.testing.assert_allclose(fk.as_matrices(), state.plates.as_matrices(), atol=1e-8)
