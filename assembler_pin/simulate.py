"""The stack in MuJoCo: the exported MJCF (:mod:`assembler_pin.mjcf`) set to our poses, its
statics from MuJoCo's own gravity and constraint Jacobian, and a held pose simulated.

Two independent checks of :func:`~assembler_pin.statics.solve_statics` come from here:

* :func:`mujoco_statics` — MuJoCo's generalized gravity ``qfrc_bias`` (zero velocity) is
  balanced by the actuator forces on the slides and the ball-joint forces through MuJoCo's
  equality-constraint Jacobian ``efc_J``: one square linear system, exact up to rounding.
* :func:`hold_pose` — the position actuators are commanded to our leg lengths and MuJoCo
  integrates until the stack is still: the forces the actuators end up exerting, and how far
  the end effector sagged. It differs from the exact statics by the compliance of the
  position loop (:data:`~assembler_pin.mjcf.ACTUATOR_KP`) and of MuJoCo's soft constraints.
  With the actuators' force limits (``forcerange``) a pose whose forces exceed them cannot be
  held: the stack sags and :attr:`HoldResult.held` is false.

MuJoCo's actuator force is positive when it pushes the shaft out (compression); forces here
are the package's: tension positive.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from .bounds import check_bound
from .exceptions import SimulationError, SingularConfigurationError
from .kinematics import PlateArrays, leg_vectors, plate_arrays, q_from_arrays
from .model import AssemblerModel
from .naming import names
from .options import is_number

__all__ = [
    "HOLD_DRIFT_TOLERANCE",
    "FollowResult",
    "HoldResult",
    "MujocoStack",
    "MujocoStatics",
    "SimulationError",
    "follow_trajectory",
    "hold_pose",
    "mujoco_statics",
]

logger = logging.getLogger(__name__)

#: Largest EE displacement [m] of a held pose. The position loops (1 µm/N per leg) and the
#: soft ball joints let the default stack sag 0.1–4 mm under 16–130 N; a pose whose
#: forces exceed the actuators' limits sags by centimetres.
HOLD_DRIFT_TOLERANCE = 5.0e-3
#: Largest EE rotation [rad] of a held pose (1°).
HOLD_ROTATION_TOLERANCE = float(np.deg2rad(1.0))


def _mujoco():
    try:
        import mujoco
    except ImportError as exc:  # pragma: no cover - the test extra installs it
        raise SimulationError(
            f"MuJoCo is not installed ({exc}); install it with: pip install 'assembler_pin[sim]'"
        ) from None
    return mujoco


@dataclass(frozen=True)
class MujocoStatics:
    """Statics of a pose computed by MuJoCo.

    Attributes:
        forces: (n, 6) actuator forces [N], tension positive.
        ball_forces: (n, 6, 3) force of each ball joint on its shaft, world frame [N].
        closure_residual: largest distance between the two sides of a ball joint in MuJoCo's
            model of the pose [m] (≈ 1e-15 when our q closes the loops).
    """

    forces: np.ndarray
    ball_forces: np.ndarray
    closure_residual: float

    @property
    def max_abs_force(self) -> float:
        return float(np.abs(self.forces).max())


@dataclass
class HoldResult:
    """A pose held by the position actuators, simulated in MuJoCo.

    Attributes:
        times: (T,) sample times [s].
        ee_drift: (T,) distance of the EE plate from its commanded position [m].
        ee_rotation_drift: (T,) angle between the EE plate and its commanded orientation [rad].
        forces: (T, n, 6) actuator forces [N], tension positive.
        saturated: (T, n, 6) True where an actuator sits at its force limit.
        end_stop_forces: (T, n, 6) force the slides' end stops (the stroke limits) carry [N],
            tension positive; a leg commanded exactly to a stroke end that sags by the
            servo's compliance rests on its stop, which then takes part of the load.
        closure_residual: (T,) largest ball-joint gap [m].
        plates: the plate poses at the end.
        held: True when, at the end, the EE is within the drift tolerance and
            :data:`HOLD_ROTATION_TOLERANCE` of the commanded pose, no actuator is at its force
            limit and the stack is still.
        message: why not held, or "held".
    """

    times: np.ndarray
    ee_drift: np.ndarray
    ee_rotation_drift: np.ndarray
    forces: np.ndarray
    saturated: np.ndarray
    end_stop_forces: np.ndarray
    closure_residual: np.ndarray
    plates: PlateArrays
    held: bool
    message: str
    samples: list[PlateArrays] = field(default_factory=list, repr=False)

    @property
    def final_forces(self) -> np.ndarray:
        """(n, 6) actuator forces at the end [N], tension positive."""
        return self.forces[-1]

    def __repr__(self) -> str:
        return (
            f"HoldResult(held={self.held}, {self.times[-1]:.2f} s, EE drift {1e3 * self.ee_drift[-1]:.3f} mm, "
            f"max|F| {np.abs(self.final_forces).max():.2f} N, message={self.message!r})"
        )

    def to_dict(self) -> dict:
        """JSON of ``assembler-pin simulate --json`` (the time series sampled as stored)."""
        return {
            "held": self.held,
            "message": self.message,
            "seconds": float(self.times[-1]),
            "final_ee_drift_m": float(self.ee_drift[-1]),
            "max_ee_drift_m": float(self.ee_drift.max()),
            "final_ee_rotation_drift_rad": float(self.ee_rotation_drift[-1]),
            "final_forces": self.final_forces.tolist(),
            "final_max_abs_force": float(np.abs(self.final_forces).max()),
            "max_closure_residual_m": float(self.closure_residual.max()),
            "times": self.times.tolist(),
            "ee_drift_m": self.ee_drift.tolist(),
            "max_abs_force": np.abs(self.forces).max(axis=(1, 2)).tolist(),
            "saturated_actuators": self.saturated.sum(axis=(1, 2)).tolist(),
            "final_end_stop_forces": self.end_stop_forces[-1].tolist(),
        }


class MujocoStack:
    """The stack's MJCF loaded in MuJoCo, with the maps between our poses and MuJoCo's state.

    ``qpos`` has the layout of the URDF's ``q`` without the root free-flyer (plate 0 is a body
    fixed to the world, placed at our plate 0's pose): per platform, the legs' ``(ux, uy,
    length)`` then the top plate's three slides and its ball quaternion, which MuJoCo orders
    ``w x y z`` and Pinocchio ``x y z w``.
    """

    def __init__(self, am: AssemblerModel) -> None:
        from .mjcf import assembler_mjcf

        mujoco = _mujoco()
        self.am = am
        self.mujoco = mujoco
        self.model = mujoco.MjModel.from_xml_string(assembler_mjcf(am.config))
        self.model.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE  # efc_J as a dense matrix
        self.data = mujoco.MjData(self.model)
        body = lambda name: mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, name)  # noqa: E731
        self.plate_body_ids = np.array([body(names.plate(k)) for k in range(am.n + 1)])
        self.actuated_dofs = self.model.jnt_dofadr[self.model.actuator_trnid[:, 0]]
        self.n_closure_rows = 3 * 6 * am.n

    def qpos_from_plates(self, plates: PlateArrays | Sequence | np.ndarray) -> np.ndarray:
        """MuJoCo's ``qpos`` for plate poses (closed form, loops closed to rounding)."""
        pa = plate_arrays(self.am, plates)
        _, _, vec, lengths = leg_vectors(self.am, pa)
        return self._qpos(pa, vec, lengths)

    def _qpos(self, pa: PlateArrays, vec: np.ndarray, lengths: np.ndarray) -> np.ndarray:
        q = q_from_arrays(self.am, pa, vec, lengths)[7:].reshape(self.am.n, 25).copy()
        xyzw = q[:, 21:25].copy()
        q[:, 21] = xyzw[:, 3]
        q[:, 22:25] = xyzw[:, :3]
        return q.ravel()

    def set_plates(self, plates: PlateArrays | Sequence | np.ndarray) -> PlateArrays:
        """Put MuJoCo's model at the plate poses, at rest, and run its forward pass."""
        pa = plate_arrays(self.am, plates)
        m, d = self.model, self.data
        base = pa.se3(0)
        m.body_pos[self.plate_body_ids[0]] = base.translation
        x, y, z, w = pin.Quaternion(base.rotation).coeffs()
        m.body_quat[self.plate_body_ids[0]] = [w, x, y, z]
        _, _, vec, lengths = leg_vectors(self.am, pa)
        self.mujoco.mj_resetData(m, d)
        d.qpos[:] = self._qpos(pa, vec, lengths)
        d.ctrl[:] = lengths.ravel()
        self.mujoco.mj_forward(m, d)
        return pa

    def plates(self) -> PlateArrays:
        """World poses of the plates in MuJoCo's current state."""
        ids = self.plate_body_ids
        return PlateArrays(self.data.xmat[ids].reshape(-1, 3, 3).copy(), self.data.xpos[ids].copy())

    def closure_residual(self) -> float:
        """Largest ball-joint gap [m] in the current state."""
        rows = self.data.efc_pos[: self.n_closure_rows].reshape(-1, 3)
        return float(np.linalg.norm(rows, axis=1).max())

    def actuator_forces(self) -> np.ndarray:
        """(n, 6) forces the actuators exert now [N], tension positive."""
        return -self.data.actuator_force.reshape(self.am.n, 6).copy()

    def end_stop_forces(self) -> np.ndarray:
        """(n, 6) forces the slides' end stops exert now [N], tension positive."""
        m, d = self.model, self.data
        out = np.zeros(m.nv)
        rows = np.flatnonzero(d.efc_type[: d.nefc] == self.mujoco.mjtConstraint.mjCNSTR_LIMIT_JOINT)
        if rows.size:
            J = d.efc_J[: d.nefc * m.nv].reshape(d.nefc, m.nv)[rows]
            out = J.T @ d.efc_force[rows]
        return -out[self.actuated_dofs].reshape(self.am.n, 6)


def mujoco_statics(
    am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray, stack: MujocoStack | None = None
) -> MujocoStatics:
    """Actuator forces holding a pose at rest, from MuJoCo's gravity and constraint Jacobian.

    Solves ``qfrc_bias = Bᵀ τ + efc_Jᵀ λ`` (``B`` selects the actuated slides) at zero
    velocity: 24n equations, 6n actuator and 18n ball-joint unknowns. Nothing of our
    statics is used, only MuJoCo's model of the exported MJCF.

    Raises:
        SingularConfigurationError: the pose is singular (the system has no unique solution).
    """
    stack = stack or MujocoStack(am)
    stack.set_plates(plates)
    m, d = stack.model, stack.data
    rows = stack.n_closure_rows
    J = d.efc_J[: rows * m.nv].reshape(rows, m.nv)
    A = np.zeros((m.nv, m.nu + rows))
    A[stack.actuated_dofs, np.arange(m.nu)] = 1.0
    A[:, m.nu :] = J.T
    try:
        x = np.linalg.solve(A, d.qfrc_bias)
    except np.linalg.LinAlgError:
        cond, platform = _singular_system(A, am.n, m.nu)
        raise SingularConfigurationError(
            f"MuJoCo's statics system is singular at this pose (condition number {cond:.3g}, worst: platform "
            f"{platform})",
            condition_number=cond,
            platform=platform,
        ) from None
    # efc forces act along +efc_J; the constraint's force on the shaft is its first body's row
    return MujocoStatics(
        forces=-x[: m.nu].reshape(am.n, 6),
        ball_forces=-x[m.nu :].reshape(am.n, 6, 3),
        closure_residual=stack.closure_residual(),
    )


def _singular_system(A: np.ndarray, n: int, nu: int) -> tuple[float, int]:
    """(condition number, platform) of a singular statics system ``A x = b`` of
    :func:`mujoco_statics`: the platform owning the unknown (an actuator force, 6 per
    platform, or a ball-joint force, 18 per platform) that weighs most in A's null vector."""
    s, vh = np.linalg.svd(A)[1:]
    cond = float(s[0] / s[-1]) if s[-1] > 0 else math.inf
    k = int(np.argmax(np.abs(vh[-1])))
    platform = k // 6 if k < nu else (k - nu) // 18
    return cond, min(platform, n - 1)


def hold_pose(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    seconds: float = 2.0,
    samples: int = 50,
    drift_tolerance: float = HOLD_DRIFT_TOLERANCE,
    joint_limits: bool = True,
    stack: MujocoStack | None = None,
) -> HoldResult:
    """Simulate the position actuators holding a pose, starting at rest in that pose.

    Args:
        plates: the pose; the actuators are commanded to its leg lengths.
        seconds: simulated time [s], in [1e-3, 600] (bounds ``simulate.seconds``).
        samples: number of stored samples, evenly spaced, in [2, 100000].
        drift_tolerance: largest EE displacement [m] of a held pose, in [1e-9, 1].
        joint_limits: keep the joints' limits (slide end stops at the stroke, hinge stops at
            the deflection limit) as MuJoCo constraints; False lets the servos alone hold the
            pose, which is what the statics describe.

    Returns:
        The time series and the verdict (:class:`HoldResult`).

    Raises:
        SimulationError: a count or duration outside its bound (:data:`~assembler_pin.bounds.BOUNDS`).
    """
    check_bound("simulate.seconds", seconds, "seconds", SimulationError)
    check_bound("simulate.samples", samples, "samples", SimulationError)
    tolerance_mm = 1e3 * drift_tolerance if is_number(drift_tolerance) else drift_tolerance
    check_bound("simulate.drift_tolerance", tolerance_mm, "drift tolerance [mm]", SimulationError)
    stack = stack or MujocoStack(am)
    target = stack.set_plates(plates)
    m, d = stack.model, stack.data
    limit_flag = int(stack.mujoco.mjtDisableBit.mjDSBL_LIMIT)
    m.opt.disableflags = (m.opt.disableflags & ~limit_flag) | (0 if joint_limits else limit_flag)
    steps = max(1, round(seconds / m.opt.timestep))
    sample_steps = np.unique(np.linspace(0, steps, samples).round().astype(int))
    lo, hi = m.actuator_forcerange[:, 0], m.actuator_forcerange[:, 1]
    ee = target.se3(am.n)
    times, drift, rot, forces, sat, stops, closure, poses = [], [], [], [], [], [], [], []
    step = 0
    for s in sample_steps:
        while step < s:
            stack.mujoco.mj_step(m, d)
            step += 1
        pa = stack.plates()
        now = pa.se3(am.n)
        times.append(d.time)
        drift.append(float(np.linalg.norm(now.translation - ee.translation)))
        rot.append(float(np.linalg.norm(pin.log3(ee.rotation.T @ now.rotation))))
        f = d.actuator_force.copy()
        forces.append(-f.reshape(am.n, 6))
        sat.append(((f <= lo + 1e-9) | (f >= hi - 1e-9)).reshape(am.n, 6))
        stops.append(stack.end_stop_forces())
        closure.append(stack.closure_residual())
        poses.append(pa)
    still = float(np.abs(d.qvel).max()) < 1e-3
    reasons = []
    if drift[-1] > drift_tolerance:
        reasons.append(f"EE moved {1e3 * drift[-1]:.2f} mm (> {1e3 * drift_tolerance:g} mm)")
    if rot[-1] > HOLD_ROTATION_TOLERANCE:
        reasons.append(f"EE turned {np.rad2deg(rot[-1]):.2f} deg (> {np.rad2deg(HOLD_ROTATION_TOLERANCE):.2f} deg)")
    if sat[-1].any():
        reasons.append(f"{int(sat[-1].sum())} actuator(s) at their force limit")
    if not still:
        reasons.append(f"still moving (max joint speed {np.abs(d.qvel).max():.3g})")
    result = HoldResult(
        times=np.array(times),
        ee_drift=np.array(drift),
        ee_rotation_drift=np.array(rot),
        forces=np.array(forces),
        saturated=np.array(sat),
        end_stop_forces=np.array(stops),
        closure_residual=np.array(closure),
        plates=poses[-1],
        held=not reasons,
        message="held" if not reasons else "; ".join(reasons),
        samples=poses,
    )
    logger.info("hold: %s", result)
    return result


@dataclass
class FollowResult:
    """A planned trajectory run by MuJoCo's position actuators (:func:`follow_trajectory`).

    Attributes:
        times: (T,) the trajectory's sample times [s] (then the settling samples).
        ee_error: (T,) distance of MuJoCo's EE from the trajectory's EE pose at that time [m].
        ee_rotation_error: (T,) angle between them [rad].
        max_abs_force: (T,) MuJoCo's largest actuator force [N].
        planned_max_abs_force: (T,) the trajectory's max|F| (our statics) [N].
        saturated: (T,) actuators at their force limit.
        final_forces: (n, 6) MuJoCo's actuator forces after settling [N, tension positive].
        followed: no sample off by more than ``tolerance`` and no actuator saturated.
        message: why not, or "followed".
    """

    times: np.ndarray
    ee_error: np.ndarray
    ee_rotation_error: np.ndarray
    max_abs_force: np.ndarray
    planned_max_abs_force: np.ndarray
    saturated: np.ndarray
    final_forces: np.ndarray
    followed: bool
    message: str

    def to_dict(self) -> dict:
        """JSON of ``assembler-pin simulate --trajectory --json``."""
        return {
            "followed": self.followed,
            "message": self.message,
            "seconds": float(self.times[-1]),
            "max_ee_error_m": float(self.ee_error.max()),
            "max_ee_rotation_error_rad": float(self.ee_rotation_error.max()),
            "times": self.times.tolist(),
            "ee_error_m": self.ee_error.tolist(),
            "max_abs_force": self.max_abs_force.tolist(),
            "planned_max_abs_force": self.planned_max_abs_force.tolist(),
            "saturated_actuators": self.saturated.tolist(),
            "final_forces": self.final_forces.tolist(),
        }

    def __repr__(self) -> str:
        return (
            f"FollowResult(followed={self.followed}, {self.times[-1]:.2f} s, EE off the plan by at most "
            f"{1e3 * self.ee_error.max():.2f} mm, message={self.message!r})"
        )


def follow_trajectory(
    am: AssemblerModel,
    traj,
    settle: float = 0.5,
    tolerance: float = HOLD_DRIFT_TOLERANCE,
    stack: MujocoStack | None = None,
) -> FollowResult:
    """Run a trajectory (:class:`~assembler_pin.motion.timing.Trajectory`) on MuJoCo's
    position actuators: the stack starts at rest at the first sample (rebuilt by stack FK),
    the commands are the leg lengths interpolated linearly in time at every 1 ms step, and
    the EE is compared with the trajectory's at each of its samples; then it settles for
    ``settle`` seconds at the last command.

    Args:
        settle: time held at the last command after the motion [s] (>= 0).
        tolerance: largest EE distance from the planned pose at any sample [m].

    Raises:
        SimulationError: a duration over the ``simulate.seconds`` bound, or bad settings.
        TrajectoryError: a row that fails :func:`~assembler_pin.motion.timing.check_trajectory`
            (every row is held to the model before the first step).
    """
    from .bounds import check_bound
    from .motion.timing import trajectory_states

    if not (np.isfinite(settle) and 0.0 <= settle <= 60.0):
        raise SimulationError(f"settle must be in [0, 60] s, got {settle}")
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise SimulationError(f"tolerance must be > 0 m, got {tolerance}")
    check_bound("simulate.seconds", traj.duration, "the trajectory's duration", SimulationError)
    _, first = trajectory_states(am, traj, frames=2)  # every row held to stack FK of its lengths
    stack = stack or MujocoStack(am)
    stack.set_plates(first[0].plates)
    m, d = stack.model, stack.data
    dt = m.opt.timestep
    lengths = traj.lengths.reshape(len(traj.times), -1)
    sample_times = np.concatenate([traj.times, traj.times[-1] + np.linspace(0.0, settle, 6)[1:]])
    planned = np.concatenate([traj.max_abs_force, np.full(5, traj.max_abs_force[-1])])
    poses = [pin.SE3(pin.exp3(traj.ee[k, 3:]), traj.ee[k, :3]) for k in range(len(traj.times))]
    poses += [poses[-1]] * 5
    lo, hi = m.actuator_forcerange[:, 0], m.actuator_forcerange[:, 1]
    err, rot, peak, sat = [], [], [], []
    for t_sample, target in zip(sample_times, poses, strict=True):
        while d.time < t_sample - 0.5 * dt:
            t = d.time + dt
            d.ctrl[:] = [np.interp(t, traj.times, lengths[:, a]) for a in range(lengths.shape[1])]
            stack.mujoco.mj_step(m, d)
        now = stack.plates().se3(am.n)
        err.append(float(np.linalg.norm(now.translation - target.translation)))
        rot.append(float(np.linalg.norm(pin.log3(target.rotation.T @ now.rotation))))
        f = d.actuator_force
        peak.append(float(np.abs(f).max()))
        sat.append(int(((f <= lo + 1e-9) | (f >= hi - 1e-9)).sum()))
    err_a, sat_a = np.array(err), np.array(sat)
    reasons = []
    if err_a.max() > tolerance:
        k = int(err_a.argmax())
        reasons.append(
            f"EE {1e3 * err_a[k]:.2f} mm off the plan at t = {sample_times[k]:.2f} s (> {1e3 * tolerance:g} mm)"
        )
    if sat_a.any():
        reasons.append(f"actuators at their force limit at {int((sat_a > 0).sum())} samples")
    result = FollowResult(
        sample_times,
        err_a,
        np.array(rot),
        np.array(peak),
        planned,
        sat_a,
        stack.actuator_forces(),
        not reasons,
        "; ".join(reasons) or "followed",
    )
    logger.info("follow: %s", result)
    return result
