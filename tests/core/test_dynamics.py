"""Inverse dynamics of the closed-loop stack held to MuJoCo and to the energy balance.

MuJoCo's side knows nothing of our dynamics: the joint velocities and accelerations come from
finite differences (5-point stencils, ``mj_differentiatePos``) of MuJoCo ``qpos`` along a
smooth plate motion; ``mj_inverse`` with the constraints disabled gives the tree's
``M q̈ + c(q, q̇)``; the actuator and ball forces are then the solution of
``[Bᵀ | efc_Jᵀ] x = qfrc_inverse`` with MuJoCo's own constraint Jacobian (the rigid loop closure;
MuJoCo's soft constraints would answer with their impedance instead). The drives' armature
(reflected rotor inertia of the servo) is set to zero: it is part of MuJoCo's servo model,
not of the mechanism.
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from assembler_pin import AssemblerModel, solve_statics
from assembler_pin.dynamics import (
    inverse_dynamics,
    inverse_dynamics_from_lengths,
    path_force_coefficients,
    plate_motion_from_lengths,
)
from assembler_pin.exceptions import ArgumentError
from assembler_pin.kinematics import PlateArrays, leg_vectors
from assembler_pin.simulate import MujocoStack

H = 1e-3  # finite-difference step [s]


class _Motion:
    """Plates 1..n moving smoothly about a pose: p_k(t) = p_k + c_k sin(ω t), R_k(t) = R_k exp(w_k sin(ω t + φ))."""

    def __init__(self, plates: PlateArrays, rng: np.random.Generator, amplitude: float = 0.004) -> None:
        n = plates.R.shape[0] - 1
        self.R0, self.p0 = plates.R.copy(), plates.p.copy()
        self.c = np.vstack([np.zeros(3), rng.normal(size=(n, 3)) * amplitude])
        self.w = np.vstack([np.zeros(3), rng.normal(size=(n, 3)) * 5 * amplitude])
        self.omega, self.phi = 2.0 + rng.uniform(), rng.uniform(0, np.pi)

    def plates(self, t: float) -> PlateArrays:
        f = np.sin(self.omega * t + self.phi)
        R = np.array([R0 @ pin.exp3(w * f) for R0, w in zip(self.R0, self.w, strict=True)])
        return PlateArrays(R, self.p0 + self.c * np.sin(self.omega * t))

    def twists(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        om = self.omega
        fd, fdd = om * np.cos(om * t + self.phi), -(om**2) * np.sin(om * t + self.phi)
        w_world = np.einsum("kab,kb->ka", self.R0, self.w)  # R exp(w f) w = R w
        lin_v, lin_a = self.c * om * np.cos(om * t), -self.c * om**2 * np.sin(om * t)
        return np.hstack([lin_v, w_world * fd]), np.hstack([lin_a, w_world * fdd])


def _mujoco_forces(stack: MujocoStack, motion: _Motion, t: float) -> np.ndarray:
    """(n, 6) actuator forces [N, tension positive] of the motion at t, from MuJoCo alone."""
    m, d = stack.model, stack.data
    stack.set_plates(motion.plates(t))  # base placed, constraints evaluated at qpos(t)
    q0 = d.qpos.copy()
    disp = {}
    for k in (-2, -1, 1, 2):
        out = np.zeros(m.nv)
        mujoco.mj_differentiatePos(m, out, 1.0, q0, stack.qpos_from_plates(motion.plates(t + k * H)))
        disp[k] = out
    qvel = (8 * (disp[1] - disp[-1]) - (disp[2] - disp[-2])) / (12 * H)
    qacc = (16 * (disp[1] + disp[-1]) - (disp[2] + disp[-2])) / (12 * H**2)
    rows = stack.n_closure_rows
    J = d.efc_J[: rows * m.nv].reshape(rows, m.nv).copy()
    d.qvel[:], d.qacc[:] = qvel, qacc
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    try:
        mujoco.mj_inverse(m, d)
    finally:
        m.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    A = np.zeros((m.nv, m.nu + rows))
    A[stack.actuated_dofs, np.arange(m.nu)] = 1.0
    A[:, m.nu :] = J.T
    x = np.linalg.solve(A, d.qfrc_inverse)
    return -x[: m.nu].reshape(-1, 6)


@pytest.fixture(scope="module")
def stack(am) -> MujocoStack:
    s = MujocoStack(am)
    s.model.dof_armature[:] = 0.0
    return s


def test_zero_motion_is_the_statics(am, random_poses):
    for _, plates in [(None, am.home), *random_poses[:4]]:
        zero = np.zeros((am.n + 1, 6))
        dyn = inverse_dynamics(am, plates, zero, zero)
        st = solve_statics(am, plates)
        np.testing.assert_allclose(dyn.forces, st.forces, rtol=0, atol=1e-9)
        np.testing.assert_allclose(dyn.ball_forces, st.ball_forces, rtol=0, atol=1e-9)
        np.testing.assert_allclose(dyn.base_wrench, st.base_wrench, rtol=0, atol=1e-9)


def test_inverse_dynamics_equals_mujoco_inverse(am, stack, random_poses):
    rng = np.random.default_rng(7)
    worst, peak = 0.0, 0.0
    for _, plates in random_poses[:5]:
        motion = _Motion(plates, rng)
        for t in rng.uniform(0, 3, 2):
            twist, accel = motion.twists(t)
            ours = inverse_dynamics(am, motion.plates(t), twist, accel).forces
            theirs = _mujoco_forces(stack, motion, t)
            worst = max(worst, float(np.abs(ours - theirs).max()))
            peak = max(peak, float(np.abs(ours - solve_statics(am, motion.plates(t)).forces).max()))
    assert worst < 1e-6, worst
    assert peak > 0.05  # the motions' own part is well above the tolerance


def test_leg_rates_give_the_plate_motion_they_came_from(am, random_poses):
    """Leg-length rates and accelerations of a plate motion (finite differences of the
    lengths) map back to that motion's twists and accelerations."""
    rng = np.random.default_rng(3)
    _, plates = random_poses[1]
    motion = _Motion(plates, rng)
    t = 0.4
    L = {k: leg_vectors(am, motion.plates(t + k * H))[3] for k in (-2, -1, 0, 1, 2)}
    rates = (8 * (L[1] - L[-1]) - (L[2] - L[-2])) / (12 * H)
    accels = (16 * (L[1] + L[-1]) - 30 * L[0] - (L[2] + L[-2])) / (12 * H**2)
    twist, accel = plate_motion_from_lengths(am, motion.plates(t), rates, accels)
    want_t, want_a = motion.twists(t)
    np.testing.assert_allclose(twist, want_t, atol=1e-9)
    np.testing.assert_allclose(accel, want_a, atol=1e-6)
    np.testing.assert_allclose(
        inverse_dynamics_from_lengths(am, motion.plates(t), rates, accels).forces,
        inverse_dynamics(am, motion.plates(t), want_t, want_a).forces,
        atol=1e-5,
    )


def test_actuator_power_is_the_rate_of_mechanical_energy(am, stack, random_poses):
    """-Σ F_i L̇_i (the actuators' power; F tension positive) = d(KE + PE)/dt, the energies
    from MuJoCo (armature zero) by central differences along the motion."""
    m, d = stack.model, stack.data
    m.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    rng = np.random.default_rng(11)
    _, plates = random_poses[2]
    motion = _Motion(plates, rng, amplitude=0.01)

    def energy(t: float) -> float:
        stack.set_plates(motion.plates(t))
        q0 = d.qpos.copy()
        dq = [np.zeros(m.nv) for _ in range(2)]
        mujoco.mj_differentiatePos(m, dq[0], 1.0, q0, stack.qpos_from_plates(motion.plates(t + H)))
        mujoco.mj_differentiatePos(m, dq[1], 1.0, q0, stack.qpos_from_plates(motion.plates(t - H)))
        d.qvel[:] = (dq[0] - dq[1]) / (2 * H)
        mujoco.mj_forward(m, d)
        return float(d.energy[0] + d.energy[1])

    for t in (0.3, 1.1, 2.0):
        dE = (energy(t + 1e-2) - energy(t - 1e-2)) / 2e-2
        twist, accel = motion.twists(t)
        forces = inverse_dynamics(am, motion.plates(t), twist, accel).forces
        rates = (leg_vectors(am, motion.plates(t + H))[3] - leg_vectors(am, motion.plates(t - H))[3]) / (2 * H)
        power = -float((forces * rates).sum())
        assert abs(power - dE) < 1e-3 * max(1.0, abs(dE)), (power, dE)
        assert abs(dE) > 0.05  # a test of something


def test_path_coefficients_rebuild_the_forces_of_a_timed_path(am, random_poses):
    rng = np.random.default_rng(5)
    _, plates = random_poses[3]
    d1, d2 = rng.normal(size=(am.n, 6)) * 0.02, rng.normal(size=(am.n, 6)) * 0.05
    a, b, c = path_force_coefficients(am, plates, d1, d2)
    sd, sdd = 1.7, -0.6
    want = inverse_dynamics_from_lengths(am, plates, d1 * sd, d1 * sdd + d2 * sd**2).forces
    np.testing.assert_allclose(a * sdd + b * sd**2 + c, want, atol=1e-9)
    np.testing.assert_allclose(c, solve_statics(am, plates).forces, atol=1e-9)


def test_bad_motion_arrays_are_refused(am):
    zero = np.zeros((am.n + 1, 6))
    with pytest.raises(ArgumentError, match="twists"):
        inverse_dynamics(am, am.home, np.zeros(5), zero)
    with pytest.raises(ArgumentError, match="accelerations"):
        inverse_dynamics(am, am.home, zero, np.full((am.n + 1, 6), np.nan))
    with pytest.raises(ArgumentError, match="rates"):
        inverse_dynamics_from_lengths(am, am.home, np.zeros(3), np.zeros((am.n, 6)))


def test_two_threads_on_one_model_get_the_single_threaded_forces(random_poses):
    """inverse_dynamics never writes the model's own Data: two threads calling it on one model
    at once give, pose by pose, the forces of the calls made one after another."""
    model = AssemblerModel.from_config()
    rng = np.random.default_rng(7)
    cases = [
        (plates, rng.normal(size=(model.n, 6)) * 0.05, rng.normal(size=(model.n, 6))) for _, plates in random_poses
    ]
    expected = [inverse_dynamics(model, *case).forces for case in cases]
    start = threading.Barrier(2)

    def run(order: list[int]) -> dict[int, np.ndarray]:
        start.wait()
        return {k: inverse_dynamics(model, *cases[k]).forces for k in order * 5}

    with ThreadPoolExecutor(2) as pool:
        forward = pool.submit(run, list(range(len(cases))))
        backward = pool.submit(run, list(reversed(range(len(cases)))))
        results = [forward.result(), backward.result()]
    for got in results:
        for k, want in enumerate(expected):
            np.testing.assert_array_equal(got[k], want)
    assert model._data is None  # the model's own Data was never made, let alone written


def test_a_callers_data_gives_the_same_forces(am, random_poses):
    plates = random_poses[0][1]
    twist, accel = np.full((am.n, 6), 0.01), np.full((am.n, 6), 0.2)
    want = inverse_dynamics(am, plates, twist, accel).forces
    np.testing.assert_array_equal(inverse_dynamics(am, plates, twist, accel, data=am.create_data()).forces, want)
    with pytest.raises(ArgumentError, match="data must be"):
        inverse_dynamics(am, plates, twist, accel, data=object())
