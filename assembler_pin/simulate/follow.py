"""A planned trajectory run by MuJoCo's position actuators (:func:`follow_trajectory`).

Times [s], EE errors [m, rad], forces [N, tension positive].
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from ..config.bounds import check_bound
from ..exceptions import SimulationError
from ..model.assembler import AssemblerModel
from ..motion.timing import trajectory_states
from .hold import HOLD_DRIFT_TOLERANCE, pose_errors, saturated_actuators
from .stack import MujocoStack

__all__ = ["FollowResult", "follow_trajectory"]

logger = logging.getLogger(__name__)


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


def _follow_series(
    stack: MujocoStack, traj: Any, sample_times: np.ndarray, poses: list[pin.SE3]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Step MuJoCo with the leg lengths of ``traj`` interpolated linearly in time at every
    step, and at each of ``sample_times`` [s] compare the EE with ``poses``: the distances [m],
    angles [rad], largest actuator force [N] and count of saturated actuators."""
    n, m, d = stack.am.n, stack.model, stack.data
    dt = m.opt.timestep
    lengths = traj.lengths.reshape(len(traj.times), -1)
    err, rot, peak, sat = [], [], [], []
    for t_sample, target in zip(sample_times, poses, strict=True):
        while d.time < t_sample - 0.5 * dt:
            t = d.time + dt
            d.ctrl[:] = [np.interp(t, traj.times, lengths[:, a]) for a in range(lengths.shape[1])]
            stack.mujoco.mj_step(m, d)
        e, r = pose_errors(stack.plates().se3(n), target)
        err.append(e)
        rot.append(r)
        peak.append(float(np.abs(d.actuator_force).max()))
        sat.append(int(saturated_actuators(stack).sum()))
    return np.array(err), np.array(rot), np.array(peak), np.array(sat)


def _check_follow_inputs(traj: Any, settle: float, tolerance: float) -> None:
    """SimulationError for a settling time outside [0, 60] s, a tolerance not > 0 m, or a
    trajectory longer than the ``simulate.seconds`` bound."""
    if not (np.isfinite(settle) and 0.0 <= settle <= 60.0):
        raise SimulationError(f"settle must be in [0, 60] s, got {settle}")
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise SimulationError(f"tolerance must be > 0 m, got {tolerance}")
    check_bound("simulate.seconds", traj.duration, "the trajectory's duration", SimulationError)


def follow_trajectory(
    am: AssemblerModel,
    traj: Any,
    settle: float = 0.5,
    tolerance: float = HOLD_DRIFT_TOLERANCE,
    stack: MujocoStack | None = None,
) -> FollowResult:
    """Run a trajectory (:class:`~assembler_pin.motion.trajfile.Trajectory`) on MuJoCo's
    position actuators: the stack starts at rest at the first sample (rebuilt by stack FK),
    the commands are the leg lengths interpolated linearly in time at every 1 ms step, and
    the EE is compared with the trajectory's at each of its samples; then it settles for
    ``settle`` seconds at the last command.

    Args:
        settle: time held at the last command after the motion [s] (>= 0).
        tolerance: largest EE distance from the planned pose at any sample [m].

    Raises:
        SimulationError: a duration over the ``simulate.seconds`` bound, or bad settings.
        TrajectoryError: a row that fails :func:`~assembler_pin.motion.rows.check_trajectory`
            (every row is held to the model before the first step).
    """
    _check_follow_inputs(traj, settle, tolerance)
    _, first = trajectory_states(am, traj, frames=2)  # every row held to stack FK of its lengths
    stack = stack or MujocoStack(am)
    stack.set_plates(first[0].plates)
    sample_times = np.concatenate([traj.times, traj.times[-1] + np.linspace(0.0, settle, 6)[1:]])
    planned = np.concatenate([traj.max_abs_force, np.full(5, traj.max_abs_force[-1])])
    poses = [pin.SE3(pin.exp3(traj.ee[k, 3:]), traj.ee[k, :3]) for k in range(len(traj.times))]
    poses += [poses[-1]] * 5
    err_a, rot_a, peak_a, sat_a = _follow_series(stack, traj, sample_times, poses)
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
        rot_a,
        peak_a,
        planned,
        sat_a,
        stack.actuator_forces(),
        not reasons,
        "; ".join(reasons) or "followed",
    )
    logger.info("follow: %s", result)
    return result
