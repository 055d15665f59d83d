"""The Assembler as a compliant truss: stiffness, loaded pose and compensated lengths, each held
to an independent computation.

The reference here is a nonlinear elastic equilibrium written from the design alone: the total
potential (legs as springs ½k(L−L0)², the weight of plates, motors, shafts and payload placed from
the plate poses and the design anchors of ``checks.py``, as ``conftest.potential_energy`` does),
its exact gradient by complex-step differentiation, minimized by ``scipy.optimize.minimize``. The
EE compliance is the finite difference of that equilibrium under small EE wrenches.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from checks import design_anchors
from conftest import potential_energy
from scipy.optimize import minimize

import assembler_pin as ap
from assembler_pin.compliance import compensated_lengths, loaded_pose
from assembler_pin.compliance.ee_stiffness import stiffness
from assembler_pin.exceptions import LoadError

STEP = 1e-20  # complex step


def _rotations(w: np.ndarray) -> np.ndarray:
    """exp3 of rotation vectors (..., 3), real or complex (series near 0: analytic everywhere)."""
    th2 = (w * w).sum(axis=-1)
    small = np.abs(th2) < 1e-4
    safe2 = np.where(small, 1.0, th2)
    th = np.sqrt(safe2)
    series_a = 1 - th2 / 6 + th2**2 / 120 - th2**3 / 5040 + th2**4 / 362880
    series_b = 0.5 - th2 / 24 + th2**2 / 720 - th2**3 / 40320 + th2**4 / 3628800
    a = np.where(small, series_a, np.sin(th) / th)
    b = np.where(small, series_b, (1 - np.cos(th)) / safe2)
    K = np.zeros((*w.shape, 3), dtype=w.dtype)
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -w[..., 2], w[..., 1], -w[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = w[..., 2], -w[..., 1], w[..., 0]
    return a[..., None, None] * K + b[..., None, None] * (K @ K)  # exp3(w) - I


class ElasticStack:
    """The total potential of the stack as a function of plate increments ``x`` (6n: per plate
    1..n a translation and a rotation vector, world axes: ``p = p_ref + δp``, ``R = exp3(w) R_ref``),
    measured from the reference pose so that no digits cancel near the minimum."""

    def __init__(self, cfg, R, p, rest, k, wrench=None):
        self.cfg, self.n, self.k = cfg, cfg.platforms, k
        self.R, self.p = np.array(R, dtype=float), np.array(p, dtype=float)
        self.wrench = np.zeros(6) if wrench is None else np.asarray(wrench, float)
        anchors = [design_anchors(cfg, j) for j in range(self.n)]
        self.bottom = np.array([np.asarray(b) @ self.R[j].T for j, (b, _) in enumerate(anchors)])  # (n, 6, 3) world
        self.top = np.array([np.asarray(t) @ self.R[j + 1].T for j, (_, t) in enumerate(anchors)])
        self.d_ref = self.top + self.p[1:, None] - self.bottom - self.p[:-1, None]
        self.L_ref = np.sqrt((self.d_ref**2).sum(-1))
        self.offset = self.L_ref - rest  # the springs' stretch at the reference

    def energy(self, x: np.ndarray) -> np.ndarray:
        """V(x) − V(0) [J] for a batch x (B, 6n), real or complex."""
        cfg, n = self.cfg, self.n
        leg, g = cfg.leg, cfg.gravity
        x = x.reshape(x.shape[0], n, 6)
        dp, dR = x[..., :3], _rotations(x[..., 3:])  # (B, n, 3), (B, n, 3, 3) = exp3 - I
        zeros = np.zeros((x.shape[0], 1, 3), dtype=x.dtype)
        # displacement of every point: plate origin's plus (exp3(w) - I) r
        move_b = np.concatenate([zeros, dp[:, :-1]], 1)[:, :, None] + np.einsum(
            "bjkl,jil->bjik", np.concatenate([np.zeros((x.shape[0], 1, 3, 3), x.dtype), dR[:, :-1]], 1), self.bottom
        )
        move_t = dp[:, :, None] + np.einsum("bjkl,jil->bjik", dR, self.top)
        dd = move_t - move_b
        d = self.d_ref + dd
        dL = (dd * (d + self.d_ref)).sum(-1) / (np.sqrt((d * d).sum(-1)) + self.L_ref)  # L − L_ref
        springs = 0.5 * self.k * (dL * (dL + 2 * self.offset)).sum((1, 2))
        L = self.L_ref + dL
        du = d / L[..., None] - self.d_ref / self.L_ref[..., None]
        motors = leg.motor_mass * g * (move_b[..., 2] + leg.motor_com * du[..., 2]).sum((1, 2))
        shafts = leg.shaft_mass * g * (move_t[..., 2] - leg.shaft_com * du[..., 2]).sum((1, 2))
        plates = cfg.plate.mass * g * dp[..., 2].sum(1)
        payload_lever = self.R[n] @ np.array([0.0, 0.0, cfg.payload.offset])
        payload = cfg.payload.mass * g * (dp[:, -1, 2] + (dR[:, -1] @ payload_lever)[:, 2])
        work = x[:, -1] @ self.wrench
        return springs + motors + shafts + plates + payload - work

    def gradient(self, x: np.ndarray) -> np.ndarray:
        m = x.size
        return self.energy(x[None] + 1j * STEP * np.eye(m)).imag / STEP

    def hessian(self, x: np.ndarray, h: float = 1e-7) -> np.ndarray:
        m = x.size
        cols = [(self.gradient(x + h * e) - self.gradient(x - h * e)) / (2 * h) for e in np.eye(m)]
        H = np.array(cols)
        return 0.5 * (H + H.T)

    def solve(self, hess: np.ndarray, x0: np.ndarray | None = None) -> np.ndarray:
        """The minimum of the potential: ``scipy.optimize.minimize`` (trust region), then Newton
        steps on the exact gradient to polish the digits the energy values cannot resolve
        (near the minimum V changes by less than its rounding)."""
        x0 = np.zeros(6 * self.n) if x0 is None else x0
        res = minimize(
            lambda x: float(self.energy(x[None])[0].real),
            x0,
            jac=self.gradient,
            hess=lambda x: hess,
            method="trust-exact",
            options={"gtol": 1e-10, "maxiter": 200},
        )
        x = res.x
        for _ in range(20):
            grad = self.gradient(x)
            if np.abs(grad).max() < 1e-12:
                break
            x = x - np.linalg.solve(hess, grad)
        assert np.abs(self.gradient(x)).max() < 1e-11, res.message
        return x

    def moved(self, x: np.ndarray, rest, wrench=None) -> ElasticStack:
        """The same stack referenced at the plates moved by x."""
        xs = x.reshape(self.n, 6)
        R = self.R.copy()
        p = self.p.copy()
        R[1:] = (np.eye(3) + _rotations(xs[:, 3:])) @ R[1:]
        p[1:] += xs[:, :3]
        return ElasticStack(self.cfg, R, p, rest, self.k, wrench)


def _design_lengths(cfg, pa) -> np.ndarray:
    out = []
    for j in range(cfg.platforms):
        b, t = design_anchors(cfg, j)
        out.append(np.linalg.norm(t @ pa.R[j + 1].T + pa.p[j + 1] - b @ pa.R[j].T - pa.p[j], axis=1))
    return np.array(out)


def _fd_compliance(stack: ElasticStack, rest, guess_compliance: np.ndarray, scale: float) -> np.ndarray:
    """Central differences of the EE's equilibrium displacement under small EE wrenches."""
    hess = stack.hessian(np.zeros(6 * stack.n))
    C = np.empty((6, 6))
    for i in range(6):
        target = 1e-6 if i < 3 else 1e-6 / scale  # about a micrometre of motion
        eps = target / guess_compliance[i, i]
        e = np.zeros(6)
        e[i] = eps
        plus = ElasticStack(stack.cfg, stack.R, stack.p, rest, stack.k, e).solve(hess)[-6:]
        minus = ElasticStack(stack.cfg, stack.R, stack.p, rest, stack.k, -e).solve(hess)[-6:]
        C[:, i] = (plus - minus) / (2 * eps)
    return C


def _scaled_error(A: np.ndarray, B: np.ndarray, scale: float) -> float:
    """‖A − B‖ / ‖B‖ with rotations measured as arcs of the node radius (one unit: N/m or m/N)."""
    D = np.r_[np.ones(3), np.full(3, 1.0 / scale)]
    if np.abs(B[:3, :3]).max() < 1.0:  # a compliance: the inverse scaling
        D = 1.0 / D
    return float(np.linalg.norm(D[:, None] * (A - B) * D) / np.linalg.norm(D[:, None] * B * D))


def _pose(am, kind: str):
    if kind == "home":
        return ap.kinematics.plate_arrays(am, am.home)
    rng = np.random.default_rng(7 + am.n)
    leg = am.config.leg
    while True:
        fk = ap.stack_forward_kinematics(am, rng.uniform(leg.min_length + 0.02, leg.max_length - 0.02, (am.n, 6)))
        if fk.success:
            return fk.plates


_MODELS: dict = {}


def _model(overrides: dict) -> ap.AssemblerModel:
    key = repr(sorted(overrides.items()))
    if key not in _MODELS:
        _MODELS[key] = ap.AssemblerModel.from_config(overrides)
    return _MODELS[key]


def _check_against_fd(am, kind: str, tol: float = 1e-6):
    cfg = am.config
    pa = _pose(am, kind)
    result = stiffness(am, pa)
    assert result.success, result.message
    scale = cfg.plate.node_radius
    rest = _design_lengths(cfg, pa)
    k = cfg.leg.stiffness
    # the independent loaded equilibrium, then its compliance by finite differences
    free = ElasticStack(cfg, pa.R, pa.p, rest, k)
    x = free.solve(free.hessian(np.zeros(6 * am.n)))
    loaded = free.moved(x, rest)
    np.testing.assert_allclose(loaded.p, result.plates.p, rtol=0, atol=1e-12)
    np.testing.assert_allclose(loaded.R, result.plates.R, rtol=0, atol=1e-11)
    np.testing.assert_allclose(x[-6:-3], result.sag_translation, rtol=0, atol=1e-12)
    C_fd = _fd_compliance(loaded, rest, result.compliance, scale)
    assert _scaled_error(result.compliance, C_fd, scale) < tol
    K_fd = np.linalg.inv(C_fd)
    assert _scaled_error(result.stiffness, K_fd, scale) < tol
    # the elastic part: the same structure without loads at the loaded pose (rest = its lengths)
    massless = ap.load_config(cfg.to_dict() | {"gravity": 0.0})
    rest_here = _design_lengths(cfg, result.plates)
    bare = ElasticStack(massless, loaded.R, loaded.p, rest_here, k)
    C_el = _fd_compliance(bare, rest_here, np.linalg.inv(result.elastic), scale)
    K_el = np.linalg.inv(C_el)
    assert _scaled_error(result.elastic, K_el, scale) < tol
    return result, K_fd, K_el


@pytest.mark.parametrize("n", [1, 2, 4, 8])
@pytest.mark.parametrize("kind", ["home", "random"])
def test_stiffness_equals_finite_differences_of_an_independent_equilibrium(n, kind):
    am = _model({"platforms": n})
    result, K_fd, K_el = _check_against_fd(am, kind)
    # the load-dependent part (1e-4 of the whole at 1e6 N/m), to 1e-6 of itself
    assert _scaled_error(result.geometric, K_fd - K_el, am.config.plate.node_radius) < 1e-6


@pytest.mark.parametrize("kind", ["home", "random"])
def test_soft_legs_make_the_load_dependent_part_large_and_it_matches(kind):
    """At k = 2e4 N/m the loads change the lateral stiffness by a few percent."""
    am = _model({"platforms": 2, "leg": {"stiffness": 2e4}})
    result, K_fd, K_el = _check_against_fd(am, kind)
    G_fd = K_fd - K_el
    assert abs(G_fd[0, 0]) > 0.01 * K_fd[0, 0]
    scale = am.config.plate.node_radius
    assert _scaled_error(result.geometric, G_fd, scale) < 1e-6


def test_independent_potential_is_the_conftest_gravity_energy(am, random_poses):
    """The reference potential's weight terms agree with conftest.potential_energy."""
    _, pa = random_poses[0]
    rest = _design_lengths(am.config, pa)
    stack = ElasticStack(am.config, pa.R, pa.p, rest, am.config.leg.stiffness)
    x = np.random.default_rng(3).normal(size=6 * am.n) * 1e-3
    moved = stack.moved(x, rest)
    weight = potential_energy(am.config, ap.PlateArrays(moved.R, moved.p)) - potential_energy(am.config, pa)
    springs = (
        0.5
        * am.config.leg.stiffness
        * ((_design_lengths(am.config, ap.PlateArrays(moved.R, moved.p)) - rest) ** 2).sum()
    )
    assert stack.energy(x[None])[0] == pytest.approx(weight + springs, rel=1e-9, abs=1e-12)


# ---------------------------------------------------------------------- closed forms
def test_one_weightless_platform_is_jt_k_j():
    """K = Jᵀ k J with J = dL/dx the inverse of the EE Jacobian (kinematics), no load part."""
    am = _model({"platforms": 1, "gravity": 0.0})
    k = am.config.leg.stiffness
    for kind in ("home", "random"):
        pa = _pose(am, kind)
        result = stiffness(am, pa)
        J = np.linalg.inv(ap.kinematics.ee_jacobian_wrt_lengths(am, pa))
        K = k * J.T @ J
        np.testing.assert_allclose(result.stiffness, K, rtol=0, atol=1e-9 * np.abs(K).max())
        assert np.abs(result.geometric).max() < 1e-9 * np.abs(K).max()
        assert np.abs(result.sag_translation).max() < 1e-15 and result.iterations == 0


def test_weightless_stack_compliance_is_the_serial_sum():
    """Legs in series: C = J_ee J_eeᵀ / k with J_ee the EE Jacobian of all 6n lengths."""
    am = _model({"platforms": 4, "gravity": 0.0})
    pa = _pose(am, "random")
    result = stiffness(am, pa)
    J = ap.kinematics.ee_jacobian_wrt_lengths(am, pa)
    C = J @ J.T / am.config.leg.stiffness
    np.testing.assert_allclose(result.compliance, C, rtol=0, atol=1e-9 * np.abs(C).max())
    np.testing.assert_allclose(result.platform_compliance.sum(axis=0), C, rtol=0, atol=1e-9 * np.abs(C).max())
    assert result.platform_share.sum() == pytest.approx(1.0)


def test_home_figures_and_the_weakest_direction(am):
    result = stiffness(am, am.home)
    assert result.success and result.iterations <= 3
    t = result.translational_stiffness
    assert t[0] == pytest.approx(t[1], rel=1e-9)  # three-fold symmetry: isotropic in the plane
    assert 2.8e4 < t[0] < 2.9e4 and 1.1e6 < t[2] < 1.2e6
    assert result.weakest_name.startswith("lateral")
    assert abs(result.weakest_direction[2]) < 1e-9
    # the sag is straight down, 0.06 mm; the lowest platform gives most of the lateral compliance
    assert np.abs(result.sag_translation[:2]).max() < 1e-12
    assert -6.1e-5 < result.sag_translation[2] < -5.9e-5
    assert np.all(np.diff(result.platform_share) < 0)
    doc = result.to_dict()
    assert np.array(doc["stiffness"]).shape == (6, 6) and set(doc["sag"]) == {"translation", "rotation"}
    assert repr(result).count("\n") == 0


# ---------------------------------------------------------------------- loaded pose
def test_loaded_leg_forces_are_pinocchios_statics_at_the_loaded_pose(am, random_poses):
    """k (L − L0) at the loaded pose is what Pinocchio's statics say the legs carry there."""
    for lengths, _ in random_poses[:3]:
        loaded = loaded_pose(am, lengths)
        assert loaded.success, loaded.message
        statics = ap.solve_statics(am, loaded.plates).forces
        np.testing.assert_allclose(loaded.forces, statics, rtol=0, atol=1e-6)
        assert loaded.residual <= 1e-12


def test_loaded_pose_under_a_wrench_is_an_independent_equilibrium(am, random_poses):
    lengths, _ = random_poses[1]
    wrench = np.array([20.0, -10.0, 5.0, 1.0, -2.0, 0.5])
    loaded = loaded_pose(am, lengths, wrench=wrench)
    assert loaded.success, loaded.message
    stack = ElasticStack(am.config, loaded.plates.R, loaded.plates.p, lengths, am.config.leg.stiffness, wrench)
    assert np.abs(stack.gradient(np.zeros(6 * am.n))).max() < 1e-6  # N, N·m
    free = loaded_pose(am, lengths)
    assert np.linalg.norm(loaded.translation - free.translation) > 1e-4  # the wrench did move the EE


def test_sag_is_linear_in_small_loads():
    """Doubling a small payload (or EE wrench) doubles the sag, to 1%."""
    weightless = {"plate": {"mass": 0.0}, "leg": {"motor_mass": 0.0, "shaft_mass": 0.0}}
    sags = []
    for mass in (0.5, 1.0):
        am = _model(weightless | {"payload": {"mass": mass}})
        sags.append(stiffness(am, _pose(am, "random")).sag_translation)
    np.testing.assert_allclose(sags[1], 2 * sags[0], rtol=0, atol=0.01 * np.linalg.norm(sags[1]))
    am = _model({})
    lengths = ap.kinematics.leg_state(am, am.home).lengths
    base = loaded_pose(am, lengths).translation
    w = np.array([2.0, 1.0, -3.0, 0.1, 0.0, 0.2])
    one, two = (loaded_pose(am, lengths, wrench=s * w).translation - base for s in (1, 2))
    np.testing.assert_allclose(two, 2 * one, rtol=0, atol=0.01 * np.linalg.norm(two))
    linear = (stiffness(am, am.home).compliance @ w)[:3]  # the tangent compliance predicts it
    np.testing.assert_allclose(one, linear, rtol=0, atol=0.01 * np.linalg.norm(one))


# ---------------------------------------------------------------------- compensation
def test_compensated_lengths_hold_the_pose_in_an_independent_equilibrium(am, random_poses):
    for _, plates in [(None, ap.kinematics.plate_arrays(am, am.home)), *random_poses[:3]]:
        comp = compensated_lengths(am, plates)
        assert comp.success, comp.message
        assert comp.error <= 1e-9
        np.testing.assert_allclose(comp.check.plates.p, plates.p, rtol=0, atol=1e-9)
        # compressed legs are commanded longer than they end up: L0 = L - F/k
        F = ap.solve_statics(am, plates).forces
        assert np.all(np.sign(comp.lengths - comp.geometric) == -np.sign(F))
        stack = ElasticStack(am.config, plates.R, plates.p, comp.lengths, am.config.leg.stiffness)
        assert np.abs(stack.gradient(np.zeros(6 * am.n))).max() < 1e-6  # the pose is its equilibrium
        lengths_result = stiffness(am, plates, lengths=comp.lengths)
        assert np.abs(lengths_result.plates.p - plates.p).max() < 1e-9


# ---------------------------------------------------------------------- bad input
@pytest.mark.parametrize("value", [0.0, -1e6, float("nan"), float("inf"), 1e12, 10.0, "stiff", True])
def test_bad_leg_stiffness_is_refused_naming_the_key(value):
    with pytest.raises(ap.exceptions.ConfigError, match=r"leg\.stiffness"):
        ap.load_config({"leg": {"stiffness": value}})


@pytest.mark.parametrize(
    "wrench", [[np.nan, 0, 0, 0, 0, 0], [0, 0, 0, 0, np.inf, 0], [1e9, 0, 0, 0, 0, 0], [1, 2, 3], "push", [True] * 6]
)
def test_bad_wrenches_are_refused(am, wrench):
    from assembler_pin.exceptions import LoadError

    with pytest.raises(LoadError, match="wrench"):
        loaded_pose(am, ap.kinematics.leg_state(am, am.home).lengths, wrench=wrench)


def test_a_singular_pose_is_reported_not_answered(am):
    """The octahedral singularity (plates turned 90°): no stiffness, no compensated lengths."""
    plates = [pin.SE3.Identity()]
    turn = pin.SE3(pin.exp3(np.array([0, 0, np.pi / 2])), np.array([0, 0, am.config.home_height]))
    for _ in range(am.n):
        plates.append(plates[-1] * turn)
    result = stiffness(am, plates)
    assert not result.success and "singular" in result.message
    assert np.all(np.isnan(result.stiffness)) and np.all(np.isnan(result.sag_translation))
    assert "null" in __import__("assembler_pin.cli.common", fromlist=["dumps"]).dumps(result.to_dict())
    with pytest.raises(ap.exceptions.SingularConfigurationError):
        compensated_lengths(am, plates)
    with pytest.raises(ap.exceptions.PoseError):
        stiffness(am, am.home, lengths=np.full((am.n, 6), np.nan))


def test_a_load_the_legs_cannot_carry_is_not_marked_converged():
    """Soft legs under the payload buckle (an inverted pendulum: the load's part is negative);
    huge wrenches give either no answer or a true equilibrium, however large the sag."""
    soft = _model({"leg": {"stiffness": 1e3}})
    for result in (stiffness(soft, soft.home), loaded_pose(soft, ap.kinematics.leg_state(soft, soft.home).lengths)):
        assert not result.success and "stable" in result.message
    am = _model({})
    lengths = ap.kinematics.leg_state(am, am.home).lengths
    outcomes = set()
    for wrench in ([0, 0, -5e4, 0, 0, 0], [3e3, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 500.0]):
        loaded = loaded_pose(am, lengths, wrench=wrench)
        outcomes.add(loaded.success)
        if loaded.success:
            stack = ElasticStack(am.config, loaded.plates.R, loaded.plates.p, lengths, 1e6, np.array(wrench, float))
            assert np.abs(stack.gradient(np.zeros(6 * am.n))).max() < 1e-6 * np.abs(loaded.forces).max()
        else:
            assert loaded.message != "converged" and np.all(np.isnan(loaded.forces))
    assert outcomes == {True, False}


# ---------------------------------------------------------------------- MuJoCo
def _stiff_mujoco(am):
    """MuJoCo's stack with its ball joints made ~100x stiffer than the exported default
    (timestep 0.2 ms, solref time constant 0.4 ms, impedance 0.999) and the joint limits off:
    the servos (gain ``leg.stiffness``) are the compliance left; the soft ball joints still add
    about 0.25% to the sag (their residual gaps are ~3e-7 m)."""
    pytest.importorskip("mujoco")
    from assembler_pin.simulate import MujocoStack

    stack = MujocoStack(am)
    m = stack.model
    m.opt.timestep = 2e-4
    m.eq_solref[:] = (4e-4, 1.0)
    m.eq_solimp[:, :3] = (0.999, 0.999, 1e-3)
    m.opt.disableflags |= int(stack.mujoco.mjtDisableBit.mjDSBL_LIMIT)
    return stack


def _settle(stack, plates, ctrl, seconds: float = 0.3) -> ap.PlateArrays:
    """Start at rest at ``plates``, command ``ctrl`` (n, 6) [m], simulate, return the plates."""
    stack.set_plates(plates)
    stack.data.ctrl[:] = np.asarray(ctrl).ravel()
    for _ in range(round(seconds / stack.model.opt.timestep)):
        stack.mujoco.mj_step(stack.model, stack.data)
    assert np.abs(stack.data.qvel).max() < 1e-5  # still
    return stack.plates()


@pytest.fixture(scope="module")
def ninety_degrees(am):
    result = ap.solve(am, ap.scenario("ninety_degrees").goal)
    assert result.success, result.message
    return result.optimized.plates


def test_mjcf_servo_gain_is_the_leg_stiffness():
    mujoco = pytest.importorskip("mujoco")
    from assembler_pin.model.mjcf import ACTUATOR_KV, actuator_gains, assembler_mjcf

    for k in (2e5, 1e6, 5e6):
        m = mujoco.MjModel.from_xml_string(assembler_mjcf(ap.load_config({"platforms": 1, "leg": {"stiffness": k}})))
        kp, kv, armature = actuator_gains(k)
        assert np.all(m.actuator_gainprm[:, 0] == k) and np.all(m.actuator_biasprm[:, 1] == -k)
        assert np.all(m.actuator_biasprm[:, 2] == -kv)
        assert kv / np.sqrt(kp * armature) == pytest.approx(ACTUATOR_KV / np.sqrt(1e6))  # the same damping ratio
        assert np.all(m.dof_armature[m.jnt_dofadr[m.actuator_trnid[:, 0]]] == armature)


@pytest.mark.parametrize(
    "n, k, pose", [(1, 1e6, "home"), (4, 1e6, "home"), (4, 1e6, "ninety_degrees"), (4, 2e5, "home"), (8, 1e6, "home")]
)
def test_mujoco_servos_sag_as_loaded_pose_says(n, k, pose, request):
    """MuJoCo holding the lengths of a pose sags where loaded_pose puts the EE (5% or 0.02 mm)."""
    am = _model({"platforms": n, "leg": {"stiffness": k}})
    plates = ap.kinematics.plate_arrays(am, request.getfixturevalue(pose) if pose != "home" else am.home)
    lengths = ap.kinematics.leg_state(am, plates).lengths
    ours = loaded_pose(am, lengths)
    assert ours.success
    settled = _settle(_stiff_mujoco(am), plates, lengths)
    sag = settled.p[-1] - plates.p[-1]
    gap = float(np.linalg.norm(sag - ours.translation))
    assert gap <= max(0.05 * np.linalg.norm(ours.translation), 2e-5), (gap, ours.translation)
    assert gap <= 0.01 * np.linalg.norm(ours.translation)  # measured: 0.25%
    turn = pin.log3(settled.R[-1] @ plates.R[-1].T)
    assert np.linalg.norm(turn - ours.rotation) <= 0.01 * np.linalg.norm(ours.rotation) + 1e-7


@pytest.mark.parametrize("pose", ["home", "random", "ninety_degrees"])
def test_compensated_lengths_held_by_mujoco_put_the_ee_at_the_goal(am, random_poses, pose, request):
    plates = {"home": lambda: am.home, "random": lambda: random_poses[2][1]}.get(
        pose, lambda: request.getfixturevalue(pose)
    )()
    plates = ap.kinematics.plate_arrays(am, plates)
    comp = compensated_lengths(am, plates)
    assert comp.success, comp.message
    off = np.linalg.norm(_settle(_stiff_mujoco(am), plates, comp.lengths).p[-1] - plates.p[-1])
    plain = np.linalg.norm(loaded_pose(am, comp.geometric).translation)  # the sag without compensation
    assert off <= 5e-5 and off < 0.05 * plain, (off, plain)


def test_compensation_beyond_the_stroke_is_not_a_success(am):
    """The translation optimum has legs at their stroke ends: compressed ones would need more."""
    result = ap.solve(am, ap.scenario("translation").goal)
    comp = compensated_lengths(am, result.optimized.plates)
    assert comp.error <= 1e-9  # the lengths are right ...
    assert not comp.within_stroke and not comp.success and "stroke" in comp.message  # ... but cannot be commanded
    with pytest.raises(LoadError):
        compensated_lengths(am, am.home, tolerance=0.0)


# ---------------------------------------------------------------------- API and CLI
def test_top_level_names_stay_the_functions_whatever_was_imported():
    import subprocess
    import sys

    code = (
        "import assembler_pin as ap, assembler_pin.compliance.loaded, assembler_pin.cli.stiffness; "
        "assert callable(ap.stiffness) and callable(ap.loaded_pose) and callable(ap.compensated_lengths); "
        "assert ap.compliance.ee_stiffness.StiffnessResult.__name__ == 'StiffnessResult'"
    )
    assert subprocess.run([sys.executable, "-c", code], capture_output=True).returncode == 0


def test_cli_stiffness_json_text_and_refusals(capsys, tmp_path, am):
    import json

    from assembler_pin.cli import main

    assert main(["stiffness", "--home", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    for key in ("stiffness", "compliance", "elastic", "geometric"):
        assert np.array(doc[key]).shape == (6, 6)
    assert set(doc["sag"]) == {"translation", "rotation"} and doc["weakest"]["name"].startswith("lateral")
    assert len(doc["principal"]["translational"]["stiffness"]) == 3
    np.testing.assert_allclose(doc["stiffness"], stiffness(am, am.home).stiffness)
    assert main(["stiffness", "--home"]) == 0
    text = capsys.readouterr().out
    assert "weakest" in text and max(map(len, text.splitlines())) <= 100
    plates = tmp_path / "p.json"
    plates.write_text(json.dumps({"plates": [p.homogeneous.tolist() for p in am.home]}))
    assert main(["stiffness", "--plates", str(plates), "--compensated", "--json"]) == 0
    assert np.abs(json.loads(capsys.readouterr().out)["sag"]["translation"]).max() < 1e-12
    turned = [pin.SE3.Identity()]
    for _ in range(am.n):
        turned.append(turned[-1] * pin.SE3(pin.exp3(np.array([0, 0, np.pi / 2])), np.array([0, 0, 0.24])))
    plates.write_text(json.dumps({"plates": [p.homogeneous.tolist() for p in turned]}))
    assert main(["stiffness", "--plates", str(plates), "--json"]) == 1  # answered: there is none
    doc = json.loads(capsys.readouterr().out, parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))
    assert doc["success"] is False and doc["stiffness"][0][0] is None
    bad = tmp_path / "bad.yaml"
    bad.write_text("leg:\n  stiffness: -5\n")
    refused = (
        ["stiffness"],
        ["stiffness", "--home", "--config", str(bad)],
        ["stiffness", "--goal", *"nan 0 0 0 0 0".split()],
    )
    for argv, word in zip(refused, ("--home", "leg.stiffness", "goal"), strict=True):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and word in err[0], err


def test_the_block_sweep_of_long_stacks_equals_the_dense_solve(monkeypatch):
    """Above DENSE_MAX_PLATFORMS the tangent is swept block by block: the same answers."""
    import assembler_pin.compliance.elastic as elastic

    am = _model({"platforms": 4})
    pa = _pose(am, "random")
    lengths = ap.kinematics.leg_state(am, pa).lengths
    wrench = np.array([5.0, -3.0, 2.0, 0.4, -0.2, 0.3])
    dense = stiffness(am, pa), loaded_pose(am, lengths, wrench=wrench)
    monkeypatch.setattr(elastic, "DENSE_MAX_PLATFORMS", 0)
    swept = stiffness(am, pa), loaded_pose(am, lengths, wrench=wrench)
    assert elastic.elastic_terms(am, pa.R, pa.p, None, 1e6).hessian is None
    np.testing.assert_allclose(swept[0].stiffness, dense[0].stiffness, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(swept[0].sag_translation, dense[0].sag_translation, rtol=0, atol=1e-14)
    np.testing.assert_allclose(swept[1].plates.p, dense[1].plates.p, rtol=0, atol=1e-13)
    assert swept[1].success and swept[1].iterations == dense[1].iterations
