"""Independent checks shared by the test modules.

Nothing here uses the package's own geometry or leg state: anchors, home directions, leg
lengths, deflections and rise are computed again from the design notes (node angles
90° + 60°·j + 120°·m, legs from node m towards the nodes at ±60°), so a check cannot agree
with a bug in :mod:`assembler_pin.kinematics`.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from scipy.optimize import minimize

import assembler_pin as ap
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


# ------------------------------------------------ references shared across test folders

STEP = 1e-20  # complex step


def _cayley_minus_identity(a: np.ndarray) -> np.ndarray:
    """``cayley(a) − I`` (..., 3, 3) of Cayley parameters a (..., 3), real or complex: the
    rotation ``(I − A)⁻¹(I + A)`` (exactly orthogonal), written without cancelling digits."""
    K = np.zeros((*a.shape, 3), dtype=a.dtype)
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -a[..., 2], a[..., 1], -a[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = a[..., 2], -a[..., 1], a[..., 0]
    s = 2.0 / (1.0 + (a * a).sum(-1))
    return s[..., None, None] * (K + K @ K)


class HeldStack:
    """The potential of the stack with plates 0 and n fixed, over x (6(n−1)): per free plate a
    translation and Cayley parameters, ``p = p_ref + δp``, ``R = cayley(a) R_ref``; the springs'
    stretch is measured from the reference pose so that no digits cancel near the minimum."""

    def __init__(self, cfg, R, p, rest, free: slice = slice(1, -1)):
        self.cfg, self.n, self.k = cfg, cfg.platforms, cfg.leg.stiffness
        self.free = free  # the plates that move: 1..n−1 (both ends held), 0..n−1 (the EE held)
        self.count = len(range(cfg.platforms + 1)[free])
        self.R, self.p = np.array(R, float), np.array(p, float)
        anchors = [design_anchors(cfg, j) for j in range(self.n)]
        self.bottom = np.array([np.asarray(b) @ self.R[j].T for j, (b, _) in enumerate(anchors)])  # world arms
        self.top = np.array([np.asarray(t) @ self.R[j + 1].T for j, (_, t) in enumerate(anchors)])
        self.d_ref = self.top + self.p[1:, None] - self.bottom - self.p[:-1, None]
        self.L_ref = np.sqrt((self.d_ref**2).sum(-1))
        self.offset = self.L_ref - np.asarray(rest, float)  # the springs' stretch at the reference

    def _moves(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Plate translations (B, n+1, 3) and ``R R_ref⁻¹ − I`` (B, n+1, 3, 3); held plates stay."""
        B = x.shape[0]
        xs = x.reshape(B, self.count, 6)
        dp = np.zeros((B, self.n + 1, 3), dtype=x.dtype)
        dR = np.zeros((B, self.n + 1, 3, 3), dtype=x.dtype)
        dp[:, self.free] = xs[..., :3]
        dR[:, self.free] = _cayley_minus_identity(xs[..., 3:])
        return dp, dR

    def energy(self, x: np.ndarray) -> np.ndarray:
        """V(x) − V(0) [J] for a batch x (B, 6(n−1)), real or complex."""
        cfg, leg, g, n = self.cfg, self.cfg.leg, self.cfg.gravity, self.n
        dp, dR = self._moves(x)
        move_b = dp[:, :-1, None] + np.einsum("bjkl,jil->bjik", dR[:, :-1], self.bottom)
        move_t = dp[:, 1:, None] + np.einsum("bjkl,jil->bjik", dR[:, 1:], self.top)
        dd = move_t - move_b
        d = self.d_ref + dd
        dL = (dd * (d + self.d_ref)).sum(-1) / (np.sqrt((d * d).sum(-1)) + self.L_ref)  # L − L_ref
        springs = 0.5 * self.k * (dL * (dL + 2 * self.offset)).sum((1, 2))
        du = d / (self.L_ref + dL)[..., None] - self.d_ref / self.L_ref[..., None]
        motors = leg.motor_mass * g * (move_b[..., 2] + leg.motor_com * du[..., 2]).sum((1, 2))
        shafts = leg.shaft_mass * g * (move_t[..., 2] - leg.shaft_com * du[..., 2]).sum((1, 2))
        plates = cfg.plate.mass * g * dp[..., 2].sum(1)
        lever = self.R[n] @ np.array([0.0, 0.0, cfg.payload.offset])
        payload = cfg.payload.mass * g * (dp[:, -1, 2] + (dR[:, -1] @ lever)[:, 2])
        return springs + motors + shafts + plates + payload

    def gradient(self, x: np.ndarray) -> np.ndarray:
        return self.energy(x[None] + 1j * STEP * np.eye(x.size)).imag / STEP

    def minimum(self) -> np.ndarray:
        """scipy's trust-region minimum, polished by Newton steps on the exact gradient (the energy
        values cannot resolve the last digits near the minimum)."""
        m = 6 * (self.n - 1)
        h = 1e-7
        H = np.array([(self.gradient(h * e) - self.gradient(-h * e)) / (2 * h) for e in np.eye(m)])
        H = 0.5 * (H + H.T)
        res = minimize(
            lambda x: float(self.energy(x[None])[0].real),
            np.zeros(m),
            jac=self.gradient,
            hess=lambda x: H,
            method="trust-exact",
            options={"gtol": 1e-10},
        )
        x = res.x
        for _ in range(20):
            grad = self.gradient(x)
            if np.abs(grad).max() < 1e-12:
                break
            x = x - np.linalg.solve(H, grad)
        assert np.abs(self.gradient(x)).max() < 1e-11, res.message
        return x

    def forces(self, x: np.ndarray) -> np.ndarray:
        """Leg forces k (L − L0) [N] at x."""
        dp, dR = self._moves(x[None])
        move_b = dp[:, :-1, None] + np.einsum("bjkl,jil->bjik", dR[:, :-1], self.bottom)
        move_t = dp[:, 1:, None] + np.einsum("bjkl,jil->bjik", dR[:, 1:], self.top)
        dd = (move_t - move_b)[0]
        d = self.d_ref + dd
        dL = (dd * (d + self.d_ref)).sum(-1) / (np.sqrt((d * d).sum(-1)) + self.L_ref)
        return self.k * (dL + self.offset)


# ---------------------------------------------------------------------- the EE held alone: the turned model
def ee_held_reference(am, pa) -> np.ndarray:
    """The leg forces (n, 6) [N] that balance plates 0..n−1 with plate n held, by virtual work:
    the reference potential's gradient over the free plates is affine in the forces (commanded
    L − F/k), so equilibrium is a 6n × 6n linear system (nothing of the package's statics)."""
    n, k = am.n, am.config.leg.stiffness
    L = ap.kinematics.leg_state(am, pa).lengths
    zero = np.zeros(6 * n)
    g0 = HeldStack(am.config, pa.R, pa.p, L, free=slice(0, n)).gradient(zero)
    A = np.array(
        [
            HeldStack(am.config, pa.R, pa.p, L - e.reshape(n, 6) / k, free=slice(0, n)).gradient(zero) - g0
            for e in np.eye(6 * n)
        ]
    ).T
    return np.linalg.solve(A, -g0).reshape(n, 6)


def whole_stack_forces(am: ap.AssemblerModel, plates) -> np.ndarray:
    """Actuator forces from the whole-stack Pinocchio model: g(q) = Sᵀτ + J_cᵀλ with Pinocchio's
    own constraint Jacobian of the 6n ball joints, solved as one dense system (rows of every
    joint but the root). Tension positive."""
    model, data = am.model, am.data
    q = ap.kinematics.q_from_plates(am, plates)
    g = pin.computeGeneralizedGravity(model, data, q)
    pin.computeJointJacobians(model, data, q)
    for cm, cd in zip(am.constraint_models, am.constraint_datas, strict=True):
        cm.calc(model, data, cd)
    jc = pin.getConstraintsJacobian(model, data, am.constraint_models, am.constraint_datas)
    select = np.zeros((6 * am.n, model.nv))
    select[np.arange(6 * am.n), am.leg_idx_v[:, :, 2].ravel()] = 1.0
    system = np.hstack([select.T, jc.T])[6:]
    tau = np.linalg.solve(system, g[6:])[: 6 * am.n]
    return -tau.reshape(am.n, 6)


def check_result(am, result) -> None:
    """A successful result: stack FK of its lengths gives its plates and the goal; every
    kinematic constraint holds when recomputed independently."""
    assert result.success, result.message
    n = am.n
    assert result.leg_lengths.shape == (n, 6)
    fk = stack_forward_kinematics(am, result.leg_lengths, guess=result.state.plates)
    assert fk.success, fk.message
    ee = fk.plates.se3(n)
    assert np.linalg.norm(ee.translation - result.goal.translation) < 1e-9
    assert np.linalg.norm(pin.log3(result.goal.rotation.T @ ee.rotation)) < 1e-9
    np.testing.assert_allclose(fk.plates.p, result.state.plates.p, atol=1e-9)
    assert kinematic_problems(am.config, result.state.plates, result.goal) == []
    kinds = {v.kind for v in result.state.violations}
    # the helper arm's pose is kinematic: its forces and clearance are the optimizer's to repair
    assert not kinds - {"tension", "compression", "collision"}


def brute_segment_distance(p1, d1, p2, d2) -> float:
    """Smallest distance of two segments: a bounded minimizer over (s, t) from a grid's best
    point (the squared distance is convex in (s, t))."""
    grid = np.linspace(0.0, 1.0, 41)
    pts1 = p1 + grid[:, None] * d1
    pts2 = p2 + grid[:, None] * d2
    dist = np.linalg.norm(pts1[:, None, :] - pts2[None, :, :], axis=-1)
    i, j = np.unravel_index(np.argmin(dist), dist.shape)

    def f(x):
        w = p1 + x[0] * d1 - p2 - x[1] * d2
        return w @ w

    res = minimize(
        f, [grid[i], grid[j]], bounds=[(0, 1), (0, 1)], method="L-BFGS-B", options={"ftol": 1e-16, "gtol": 1e-14}
    )
    return float(np.sqrt(min(res.fun, dist[i, j] ** 2)))


def _points_to_axis(points: np.ndarray, start: np.ndarray, vec: np.ndarray) -> np.ndarray:
    s = np.clip((points - start) @ vec / (vec @ vec), 0.0, 1.0)
    return np.linalg.norm(points - (start + s[:, None] * vec), axis=1)


def strut_distance(cfg, plates: np.ndarray, start: np.ndarray, vec: np.ndarray, radius: float) -> float:
    """The smallest distance [m] from a strut (a capsule: axis ``start`` → ``start + vec``,
    ``radius``; a cylinder's flat ends are farther) to a plate (its rims and faces sampled every
    ~1 mm) or a leg (its axis sampled every 0.5 mm, minus the capsule's radius), plates (n+1, 4, 4)."""
    angles = np.linspace(0.0, 2 * np.pi, 1080, endpoint=False)
    rings = np.linspace(0.0, cfg.plate.radius, 60)
    disc = np.array(
        [[r * np.cos(a), r * np.sin(a)] for r in rings for a in angles[::6]]
        + [[cfg.plate.radius * np.cos(a), cfg.plate.radius * np.sin(a)] for a in angles]
    )
    best = np.inf
    for T in plates:
        for z in (-0.5 * cfg.plate.thickness, 0.5 * cfg.plate.thickness):
            local = np.column_stack([disc, np.full(len(disc), z)])
            world = local @ T[:3, :3].T + T[:3, 3]
            best = min(best, float(_points_to_axis(world, start, vec).min()) - radius)
    for j in range(cfg.platforms):
        bottom, top = design_anchors(cfg, j)
        for i in range(6):
            b = plates[j][:3, :3] @ bottom[i] + plates[j][:3, 3]
            t = plates[j + 1][:3, :3] @ top[i] + plates[j + 1][:3, 3]
            L = np.linalg.norm(t - b)
            sigma = np.linspace(0.0, L, int(L / 5e-4) + 2)
            pts = b + sigma[:, None] * (t - b) / L
            r = np.where(sigma <= cfg.leg.motor_length, cfg.leg.motor_radius, cfg.leg.shaft_radius)
            best = min(best, float((_points_to_axis(pts, start, vec) - r).min()) - radius)
    return best
