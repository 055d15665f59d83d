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


def kinematic_problems(cfg, plates, goal: pin.SE3 | None = None, tol: float = 1e-9) -> list[str]:
    """Every broken kinematic constraint of plate poses (``PlateArrays``), recomputed from
    the design: stroke, deflection at both joints, top joint above bottom joint, EE at goal."""
    leg = cfg.leg
    h = home_height(cfg)
    out = []
    for j in range(cfg.platforms):
        b_loc, t_loc = design_anchors(cfg, j)
        home = t_loc + np.array([0.0, 0.0, h]) - b_loc
        home /= np.linalg.norm(home, axis=1, keepdims=True)
        Rb, Rt = plates.R[j], plates.R[j + 1]
        for i in range(6):
            b = Rb @ b_loc[i] + plates.p[j]
            t = Rt @ t_loc[i] + plates.p[j + 1]
            length = np.linalg.norm(t - b)
            u = (t - b) / length
            if not leg.min_length - 1e-12 <= length <= leg.max_length + 1e-12:
                out.append(f"SP{j} leg {i}: length {length}")
            for where, R in (("bottom", Rb), ("top", Rt)):
                angle = np.arccos(np.clip((R.T @ u) @ home[i], -1, 1))
                if angle > np.deg2rad(leg.max_deflection_deg) + 1e-9:
                    out.append(f"SP{j} leg {i}: {where} deflection {np.rad2deg(angle)} deg")
            if (Rb.T @ (t - b))[2] <= 0:
                out.append(f"SP{j} leg {i}: top joint not above the bottom joint")
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
