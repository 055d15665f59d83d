"""The stack in MuJoCo: the exported MJCF (:mod:`assembler_pin.model.mjcf`) set to our poses, its
statics from MuJoCo's own gravity and constraint Jacobian, and a held pose simulated.

Two independent checks of :func:`~assembler_pin.statics.engine.solve_statics` come from here:

* :func:`mujoco_statics` — MuJoCo's generalized gravity ``qfrc_bias`` (zero velocity) is
  balanced by the actuator forces on the slides and the ball-joint forces through MuJoCo's
  equality-constraint Jacobian ``efc_J``: one square linear system, exact up to rounding.
* :func:`hold_pose` — the position actuators are commanded to our leg lengths and MuJoCo
  integrates until the stack is still: the forces the actuators end up exerting, and how far
  the end effector sagged. It differs from the exact statics by the compliance of the
  position loop (:data:`~assembler_pin.model.mjcf.ACTUATOR_KP`) and of MuJoCo's soft constraints.
  With the actuators' force limits (``forcerange``) a pose whose forces exceed them cannot be
  held: the stack sags and :attr:`HoldResult.held` is false.

MuJoCo's actuator force is positive when it pushes the shaft out (compression); forces here
are the package's: tension positive.

Modules: :mod:`.stack` (:class:`MujocoStack`, :func:`mujoco_statics`), :mod:`.hold`
(:func:`hold_pose`), :mod:`.follow` (:func:`follow_trajectory`).
"""

from __future__ import annotations

from ..exceptions import SimulationError
from .follow import FollowResult, follow_trajectory
from .hold import HOLD_DRIFT_TOLERANCE, HOLD_ROTATION_TOLERANCE, HoldResult, hold_pose
from .stack import MujocoStack, MujocoStatics, mujoco_statics

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
