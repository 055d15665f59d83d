"""assembler_pin: the Assembler — serialized Stewart platforms — on Pinocchio.

Closed-loop kinematic model (generated URDF + closure sidecar), exact statics under
gravity and payload, constraint evaluation, and the command ``assembler-pin``.

Quick start::

    import assembler_pin as ap
    am = ap.AssemblerModel.from_config()          # default 4-platform stack
    state = ap.evaluate_state(am, am.home)        # statics of the home pose
    state.forces                                  # (4, 6) [N], tension positive
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .common.lazy import lazy_attributes

#: public name -> the module that defines it; imported on first use, so that
#: ``import assembler_pin`` (and ``assembler-pin --help``) stays light. These are the names a
#: user types; everything else is one level down (``ap.kinematics.q_from_plates``,
#: ``ap.carrier.solve_on_carrier``, ``ap.viz.StackViewer``, ``ap.exceptions.PoseError``).
_LAZY: dict[str, str] = {
    # model and configuration
    "AssemblerModel": ".model",
    "AssemblerConfig": ".config",
    "load_config": ".config",
    # poses and state
    "PlateArrays": ".kinematics",
    "StackState": ".state",
    "evaluate_state": ".state",
    # kinematics and statics
    "stack_forward_kinematics": ".kinematics",
    "solve_statics": ".statics",
    "StaticsResult": ".statics",
    # the helper arm, the optimizer, solving
    "initial_condition": ".helper_arm",
    "HelperArmOptions": ".helper_arm",
    "optimize_internal_poses": ".optimize",
    "OptimizeOptions": ".optimize",
    "OptimizeResult": ".optimize",
    "solve": ".solver",
    "SolveResult": ".solver",
    "payload_capacity": ".solver",
    # dynamics
    "inverse_dynamics": ".dynamics",
    # the compliant truss, two-point support, walking
    "stiffness": ".compliance",
    "loaded_pose": ".compliance",
    "compensated_lengths": ".compliance",
    "two_point_statics": ".supports",
    "plan_walk": ".walk",
    # motion
    "EEPath": ".motion",
    "PlanOptions": ".motion",
    "plan_trajectory": ".motion.timing",
    "MotionResult": ".motion.result",
    "Trajectory": ".motion.trajfile",
    "read_trajectory": ".motion.trajfile",
    # scenarios and errors
    "scenario": ".scenarios",
    "SCENARIOS": ".scenarios",
    "AssemblerError": ".exceptions",
}

__all__ = sorted(_LAZY)


__getattr__, __dir__ = lazy_attributes(__name__, globals(), _LAZY, submodules=True)

if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from .compliance import compensated_lengths, loaded_pose, stiffness
    from .config import AssemblerConfig, load_config
    from .dynamics import inverse_dynamics
    from .exceptions import AssemblerError
    from .helper_arm import HelperArmOptions, initial_condition
    from .kinematics import PlateArrays, stack_forward_kinematics
    from .model import AssemblerModel
    from .motion import EEPath, PlanOptions
    from .motion.result import MotionResult
    from .motion.timing import plan_trajectory
    from .motion.trajfile import Trajectory, read_trajectory
    from .optimize import OptimizeOptions, OptimizeResult, optimize_internal_poses
    from .scenarios import SCENARIOS, scenario
    from .solver import SolveResult, payload_capacity, solve
    from .state import StackState, evaluate_state
    from .statics import StaticsResult, solve_statics
    from .supports import two_point_statics
    from .walk import plan_walk
