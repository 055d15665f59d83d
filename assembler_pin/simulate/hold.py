"""A pose held by the position actuators, simulated in MuJoCo (:func:`hold_pose`).

The actuators are commanded to our leg lengths and MuJoCo integrates until the stack is
still: the forces the actuators end up exerting [N, tension positive], and how far the end
effector sagged [m, rad].
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..config.bounds import check_bound
from ..config.numbers import is_number
from ..exceptions import SimulationError
from ..kinematics import PlateArrays
from ..model.assembler import AssemblerModel
from .stack import MujocoStack

__all__ = ["HOLD_DRIFT_TOLERANCE", "HOLD_ROTATION_TOLERANCE", "HoldResult", "hold_pose"]

logger = logging.getLogger(__name__)

#: Largest EE displacement [m] of a held pose. The position loops (1 µm/N per leg) and the
#: soft ball joints let the default stack sag 0.1–4 mm under 16–130 N; a pose whose
#: forces exceed the actuators' limits sags by centimetres.
HOLD_DRIFT_TOLERANCE = 5.0e-3
#: Largest EE rotation [rad] of a held pose (1°).
HOLD_ROTATION_TOLERANCE = float(np.deg2rad(1.0))


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


def saturated_actuators(stack: MujocoStack) -> np.ndarray:
    """(nu,) True where an actuator sits at its force limit now."""
    m, f = stack.model, stack.data.actuator_force
    lo, hi = m.actuator_forcerange[:, 0], m.actuator_forcerange[:, 1]
    return (f <= lo + 1e-9) | (f >= hi - 1e-9)


def pose_errors(now: pin.SE3, target: pin.SE3) -> tuple[float, float]:
    """Distance [m] and angle [rad] of ``now`` from ``target``."""
    return (
        float(np.linalg.norm(now.translation - target.translation)),
        float(np.linalg.norm(pin.log3(target.rotation.T @ now.rotation))),
    )


def _hold_series(stack: MujocoStack, ee: pin.SE3, sample_steps: np.ndarray) -> dict[str, list]:
    """Step MuJoCo to each of ``sample_steps`` and record the time series of :class:`HoldResult`."""
    n, m, d = stack.am.n, stack.model, stack.data
    out: dict[str, list] = {k: [] for k in ("times", "drift", "rot", "forces", "sat", "stops", "closure", "poses")}
    step = 0
    for s in sample_steps:
        while step < s:
            stack.mujoco.mj_step(m, d)
            step += 1
        pa = stack.plates()
        drift, rot = pose_errors(pa.se3(n), ee)
        out["times"].append(d.time)
        out["drift"].append(drift)
        out["rot"].append(rot)
        out["forces"].append(-d.actuator_force.reshape(n, 6).copy())
        out["sat"].append(saturated_actuators(stack).reshape(n, 6))
        out["stops"].append(stack.end_stop_forces())
        out["closure"].append(stack.closure_residual())
        out["poses"].append(pa)
    return out


def _not_held(series: dict[str, list], qvel: np.ndarray, drift_tolerance: float) -> list[str]:
    """Why the end of a hold is not a held pose (empty when it is)."""
    drift, rot, sat = series["drift"][-1], series["rot"][-1], series["sat"][-1]
    reasons = []
    if drift > drift_tolerance:
        reasons.append(f"EE moved {1e3 * drift:.2f} mm (> {1e3 * drift_tolerance:g} mm)")
    if rot > HOLD_ROTATION_TOLERANCE:
        reasons.append(f"EE turned {np.rad2deg(rot):.2f} deg (> {np.rad2deg(HOLD_ROTATION_TOLERANCE):.2f} deg)")
    if sat.any():
        reasons.append(f"{int(sat.sum())} actuator(s) at their force limit")
    if not float(np.abs(qvel).max()) < 1e-3:
        reasons.append(f"still moving (max joint speed {np.abs(qvel).max():.3g})")
    return reasons


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
        SimulationError: a count or duration outside its bound (:data:`~assembler_pin.config.bounds.BOUNDS`).
    """
    check_bound("simulate.seconds", seconds, "seconds", SimulationError)
    check_bound("simulate.samples", samples, "samples", SimulationError)
    tolerance_mm = 1e3 * drift_tolerance if is_number(drift_tolerance) else drift_tolerance
    check_bound("simulate.drift_tolerance", tolerance_mm, "drift tolerance [mm]", SimulationError)
    stack = stack or MujocoStack(am)
    target = stack.set_plates(plates)
    m = stack.model
    limit_flag = int(stack.mujoco.mjtDisableBit.mjDSBL_LIMIT)
    m.opt.disableflags = (m.opt.disableflags & ~limit_flag) | (0 if joint_limits else limit_flag)
    steps = max(1, round(seconds / m.opt.timestep))
    sample_steps = np.unique(np.linspace(0, steps, samples).round().astype(int))
    series = _hold_series(stack, target.se3(am.n), sample_steps)
    reasons = _not_held(series, stack.data.qvel, drift_tolerance)
    result = HoldResult(
        times=np.array(series["times"]),
        ee_drift=np.array(series["drift"]),
        ee_rotation_drift=np.array(series["rot"]),
        forces=np.array(series["forces"]),
        saturated=np.array(series["sat"]),
        end_stop_forces=np.array(series["stops"]),
        closure_residual=np.array(series["closure"]),
        plates=series["poses"][-1],
        held=not reasons,
        message="held" if not reasons else "; ".join(reasons),
        samples=series["poses"],
    )
    logger.info("hold: %s", result)
    return result
