"""assembler_pin: the Assembler — serialized Stewart platforms — on Pinocchio.

Closed-loop kinematic model (generated URDF + closure sidecar), exact statics under
gravity and payload, constraint evaluation, and the command ``assembler-pin``.

Quick start::

    import assembler_pin as ap
    am = ap.AssemblerModel.from_config()          # default 4-platform stack
    state = ap.evaluate_state(am, am.home)        # statics of the home pose
    state.forces                                  # (4, 6) [N], tension positive
"""

from .capacity import CapacityResult, payload_capacity
from .carrier import Carrier, carrier_statics, solve_on_carrier
from .config import AssemblerConfig, LegConfig, PayloadConfig, PlateConfig, load_config
from .constraints import GoalTolerance, Violation, evaluate_constraints
from .exceptions import (
    AssemblerError,
    CLIError,
    ConfigError,
    ConvergenceError,
    ModelFileError,
    OptionsError,
    PoseError,
    SingularConfigurationError,
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
from .solve import SolveResult, solve
from .state import StackState, evaluate_state
from .statics import StaticsResult, solve_statics, solve_statics_batch
from .urdf import assembler_urdf, closure_sidecar

__all__ = [
    "SCENARIOS",
    "AssemblerConfig",
    "AssemblerError",
    "AssemblerModel",
    "CLIError",
    "CapacityResult",
    "Carrier",
    "ConfigError",
    "ConvergenceError",
    "EEPath",
    "FKResult",
    "GoalTolerance",
    "HelperArm",
    "HelperArmOptions",
    "InitialConditionResult",
    "LegConfig",
    "LegState",
    "ModelFileError",
    "MotionResult",
    "OptimizeOptions",
    "OptimizeResult",
    "OptionsError",
    "PayloadConfig",
    "PlateArrays",
    "PlateConfig",
    "PoseError",
    "Scenario",
    "SingularConfigurationError",
    "SolveResult",
    "StackFKResult",
    "StackState",
    "StaticsResult",
    "Trajectory",
    "UnknownScenarioError",
    "ViewerError",
    "Violation",
    "assembler_urdf",
    "carrier_statics",
    "closure_sidecar",
    "ee_jacobian_wrt_lengths",
    "evaluate_constraints",
    "evaluate_state",
    "export_model_files",
    "helper_arm_urdf",
    "home_plates",
    "initial_condition",
    "leg_geometry",
    "leg_state",
    "load_config",
    "optimize_internal_poses",
    "payload_capacity",
    "plan_trajectory",
    "plate_arrays",
    "plates_from_q",
    "q_from_plates",
    "read_trajectory",
    "scenario",
    "se3_to_taa",
    "solve",
    "solve_on_carrier",
    "solve_statics",
    "solve_statics_batch",
    "sp_forward_kinematics",
    "stack_forward_kinematics",
    "taa_to_se3",
    "to_se3",
]

__version__ = "0.1.0"
