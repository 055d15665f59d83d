"""The stack in MuJoCo: this module is :mod:`assembler_pin.sim` under its former name (every
name of :mod:`assembler_pin.sim` is importable from here)."""

from __future__ import annotations

from .sim import (
    HOLD_DRIFT_TOLERANCE,
    HOLD_ROTATION_TOLERANCE,
    FollowResult,
    HoldResult,
    MujocoStack,
    MujocoStatics,
    SimulationError,
    follow_trajectory,
    hold_pose,
    mujoco_statics,
)

__all__ = [
    "HOLD_DRIFT_TOLERANCE",
    "HOLD_ROTATION_TOLERANCE",
    "FollowResult",
    "HoldResult",
    "MujocoStack",
    "MujocoStatics",
    "SimulationError",
    "follow_trajectory",
    "hold_pose",
    "mujoco_statics",
]
