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

import importlib
from typing import TYPE_CHECKING, Any

#: public name -> the module that defines it; imported on first use, so that
#: ``import assembler_pin`` (and ``assembler-pin --help``) stays light.
_LAZY: dict[str, str] = {
    "assembler_urdf": ".urdf",
    "AssemblerConfig": ".config",
    "AssemblerError": ".exceptions",
    "AssemblerModel": ".model",
    "CapacityResult": ".capacity",
    "Carrier": ".carrier",
    "carrier_statics": ".carrier",
    "CLIError": ".exceptions",
    "chosen_distribution": ".support_choice",
    "ChosenDistribution": ".support_choice",
    "compensated_lengths": ".compliance",
    "CompensatedLengths": ".compliance",
    "closure_sidecar": ".urdf",
    "ConfigError": ".exceptions",
    "ConvergenceError": ".exceptions",
    "ee_jacobian_wrt_lengths": ".kinematics",
    "EEPath": ".motion",
    "inverse_dynamics": ".dynamics",
    "inverse_dynamics_from_lengths": ".dynamics",
    "DynamicsResult": ".dynamics",
    "evaluate_constraints": ".constraints",
    "evaluate_state": ".state",
    "export_model_files": ".export",
    "FKResult": ".kinematics",
    "GoalTolerance": ".constraints",
    "helper_arm_urdf": ".helper_arm",
    "HelperArm": ".helper_arm",
    "HelperArmOptions": ".helper_arm",
    "home_plates": ".geometry",
    "initial_condition": ".helper_arm",
    "InitialConditionResult": ".helper_arm",
    "leg_geometry": ".geometry",
    "leg_state": ".kinematics",
    "loaded_pose": ".compliance",
    "LoadedPose": ".compliance",
    "LoadError": ".exceptions",
    "SupportError": ".exceptions",
    "two_point_statics": ".supports",
    "TwoPointStatics": ".supports",
    "LegConfig": ".config",
    "LegState": ".kinematics",
    "load_config": ".config",
    "ModelFileError": ".exceptions",
    "MotionResult": ".motion.timing",
    "optimize_internal_poses": ".optimize",
    "OptimizeOptions": ".optimize",
    "OptimizeResult": ".optimize",
    "OptionsError": ".exceptions",
    "payload_capacity": ".capacity",
    "PayloadConfig": ".config",
    "plan_trajectory": ".motion.timing",
    "plate_arrays": ".kinematics",
    "PlateArrays": ".kinematics",
    "PlateConfig": ".config",
    "plates_from_q": ".kinematics",
    "PoseError": ".exceptions",
    "q_from_plates": ".kinematics",
    "read_trajectory": ".motion.timing",
    "Scenario": ".scenarios",
    "scenario": ".scenarios",
    "SCENARIOS": ".scenarios",
    "se3_to_taa": ".kinematics",
    "SingularConfigurationError": ".exceptions",
    "solve": ".solver",
    "solve_on_carrier": ".carrier",
    "solve_statics": ".statics",
    "solve_statics_batch": ".statics",
    "SolveResult": ".solver",
    "sp_forward_kinematics": ".kinematics",
    "stack_forward_kinematics": ".kinematics",
    "StackFKResult": ".kinematics",
    "StackState": ".state",
    "StaticsResult": ".statics",
    "stiffness": ".ee_stiffness",
    "StiffnessResult": ".ee_stiffness",
    "taa_to_se3": ".kinematics",
    "to_se3": ".kinematics",
    "Trajectory": ".motion.timing",
    "UnknownScenarioError": ".exceptions",
    "ViewerError": ".exceptions",
    "Violation": ".constraints",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'assembler_pin' has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from .capacity import CapacityResult, payload_capacity
    from .carrier import Carrier, carrier_statics, solve_on_carrier
    from .compliance import CompensatedLengths, LoadedPose, compensated_lengths, loaded_pose
    from .config import AssemblerConfig, LegConfig, PayloadConfig, PlateConfig, load_config
    from .constraints import GoalTolerance, Violation, evaluate_constraints
    from .dynamics import DynamicsResult, inverse_dynamics, inverse_dynamics_from_lengths
    from .ee_stiffness import StiffnessResult, stiffness
    from .exceptions import (
        AssemblerError,
        CLIError,
        ConfigError,
        ConvergenceError,
        LoadError,
        ModelFileError,
        OptionsError,
        PoseError,
        SingularConfigurationError,
        SupportError,
        UnknownScenarioError,
        ViewerError,
    )
    from .export import export_model_files
    from .geometry import home_plates, leg_geometry
    from .helper_arm import (
        HelperArm,
        HelperArmOptions,
        InitialConditionResult,
        helper_arm_urdf,
        initial_condition,
    )
    from .kinematics import (
        FKResult,
        LegState,
        PlateArrays,
        StackFKResult,
        ee_jacobian_wrt_lengths,
        leg_state,
        plate_arrays,
        plates_from_q,
        q_from_plates,
        se3_to_taa,
        sp_forward_kinematics,
        stack_forward_kinematics,
        taa_to_se3,
        to_se3,
    )
    from .model import AssemblerModel
    from .motion import EEPath
    from .motion.timing import MotionResult, Trajectory, plan_trajectory, read_trajectory
    from .optimize import OptimizeOptions, OptimizeResult, optimize_internal_poses
    from .scenarios import SCENARIOS, Scenario, scenario
    from .solver import SolveResult, solve
    from .state import StackState, evaluate_state
    from .statics import StaticsResult, solve_statics, solve_statics_batch
    from .support_choice import ChosenDistribution, chosen_distribution
    from .supports import TwoPointStatics, two_point_statics
    from .urdf import assembler_urdf, closure_sidecar
