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
    lengths = np.array(
        [
            [
                np.linalg.norm(
                    state.plates.R[j + 1] @ t + state.plates.p[j + 1] - state.plates.R[j] @ b - state.plates.p[j]
                )
                for b, t in zip(*design_anchors(cfg, j), strict=True)
            ]
            for j in range(cfg.platforms)
        ]
    )
    fk = stack_forward_kinematics(am, lengths).raise_if_failed()
    np.testing.assert_allclose(fk.as_matrices(), state.plates.as_matrices(), atol=1e-8)


def _leg_free_body(cfg, L: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Weights of motor and shaft and the part of the top-joint force normal to each leg.

    A leg carries only forces on its own axis (the weights at the centres of mass and the
    joint forces), so its universal joint carries no torque and the moments about the
    bottom joint centre fix the normal part of the top force:
    ``L·f⊥ + motor_com·w_m⊥ + (L - shaft_com)·w_s⊥ = 0``.
    """
    g = np.array([0.0, 0.0, -cfg.gravity])
    w_m = np.broadcast_to(cfg.leg.motor_mass * g, u.shape)
    w_s = np.broadcast_to(cfg.leg.shaft_mass * g, u.shape)

    def normal(w):
        return w - np.sum(w * u, axis=1, keepdims=True) * u

    lever_m = cfg.leg.motor_com / L
    lever_s = (L - cfg.leg.shaft_com) / L
    f_normal = -(lever_m[:, None] * normal(w_m) + lever_s[:, None] * normal(w_s))
    return w_m, w_s, f_normal


def design_forces(cfg, plates) -> np.ndarray:
    """Actuator forces [N, tension positive], (n, 6), by free bodies from the top plate down.

    numpy only, from the design anchors: each plate's weight (and the payload's) and the
    forces of the legs above it are balanced by the six legs below it, whose normal force
    parts come from :func:`_leg_free_body` and whose six axial parts solve the plate's
    force and moment balance. The actuator force is the axial force on the shaft,
    ``(f_top + w_shaft)·u``. A second method to Pinocchio's statics (and to virtual work).
    """
    n, g = cfg.platforms, cfg.gravity
    out = np.zeros((n, 6))
    above = None  # (points, forces) the legs of the SP above apply to the current plate
    for j in reversed(range(n)):
        k = j + 1
        points = [plates.p[k]]
        loads = [np.array([0.0, 0.0, -cfg.plate.mass * g])]
        if k == n:
            points.append(plates.R[n] @ [0, 0, cfg.payload.offset] + plates.p[n])
            loads.append(np.array([0.0, 0.0, -cfg.payload.mass * g]))
        if above is not None:
            points += list(above[0])
            loads += list(above[1])
        force = np.sum(loads, axis=0)
        moment = np.sum([np.cross(c, f) for c, f in zip(points, loads, strict=True)], axis=0)
        bottom, top = design_anchors(cfg, j)
        b = bottom @ plates.R[j].T + plates.p[j]
        t = top @ plates.R[k].T + plates.p[k]
        L = np.linalg.norm(t - b, axis=1)
        u = (t - b) / L[:, None]
        w_m, w_s, f_normal = _leg_free_body(cfg, L, u)
        # plate k: loads - Σ f_top = 0, f_top = a·u + f_normal (force of the plate on the leg)
        A = np.vstack([u.T, np.cross(t, u).T])
        rhs = np.concatenate([force - f_normal.sum(axis=0), moment - np.cross(t, f_normal).sum(axis=0)])
        a = np.linalg.solve(A, rhs)
        f_top = a[:, None] * u + f_normal
        out[j] = np.sum((f_top + w_s) * u, axis=1)
        above = (b, f_top + w_m + w_s)  # the leg pushes its bottom plate with -f_bottom = f_top + w
    return out


def design_plate_deviation(plates) -> np.ndarray:
    """λ_k [rad], k = 1..n (paper eq. 9): angle between ``p_k - p_{k-1}`` and plate k-1's
    normal (plate k rests straight above plate k-1, plates parallel, at home)."""
    step = plates.p[1:] - plates.p[:-1]
    normal = plates.R[:-1][:, :, 2]
    # atan2 of |sin| and cos: arccos loses the small angles the optimizer drives towards 0
    return np.arctan2(np.linalg.norm(np.cross(step, normal), axis=1), np.sum(step * normal, axis=1))


def twist_moved(plates, column: int, h: float):
    """``plates`` (PlateArrays) with plate k = column // 6 + 1 moved by the world twist
    h·e_(column % 6): the perturbation of the optimizer's derivative columns."""
    k = column // 6 + 1
    twist = np.zeros(6)
    twist[column % 6] = h
    moved = pin.exp6(twist) * plates.se3(k)
    R, p = plates.R.copy(), plates.p.copy()
    R[k], p[k] = moved.rotation, moved.translation
    return type(plates)(R, p)


def design_objective(cfg, plates, w1: float = 1.0, w2: float = 1.0) -> float:
    """Ω = w1·max|F| + w2·sqrt(Σ λ_k²) (paper eq. 10) from :func:`design_forces` and
    :func:`design_plate_deviation`."""
    forces = design_forces(cfg, plates)
    return float(w1 * np.abs(forces).max() + w2 * np.sqrt(np.sum(design_plate_deviation(plates) ** 2)))


def design_problems(cfg, plates, goal: pin.SE3 | None = None, tol: float = 1e-9) -> list[str]:
    """Every broken constraint of plate poses: :func:`kinematic_problems` and the tension and
    compression limits on :func:`design_forces` (no package statics involved)."""
    out = kinematic_problems(cfg, plates, goal, tol)
    forces = design_forces(cfg, plates)
    if not np.all(np.isfinite(forces)):
        out.append("non-finite force")
    if forces.max() > cfg.leg.max_tension:
        out.append(f"tension {forces.max():.3f} N")
    if forces.min() < -cfg.leg.max_compression:
        out.append(f"compression {forces.min():.3f} N")
    return out
