"""Goal pose → internal poses: the helper-arm initial condition, then force optimization.

:func:`solve` is the whole pipeline behind ``assembler-pin solve``: a fast valid initial
pose from the helper arm (paper §III), then, unless told not to, the force-optimized
internal poses (paper §IV). An unreachable goal is an answer (``success=False`` with the
reason), not an exception.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from .kinematics import se3_to_taa, to_se3
from .model import AssemblerModel
from .optimize import OptimizeOptions, OptimizeResult, optimize_internal_poses
from .state import StackState

if TYPE_CHECKING:
    from .helper_arm import HelperArmOptions, InitialConditionResult

__all__ = ["SolveResult", "solve"]


@dataclass
class SolveResult:
    """Outcome of :func:`solve`.

    Attributes:
        goal: the EE goal pose.
        success: the initial condition is valid and, when optimizing, the optimization
            converged to a state that satisfies every constraint.
        message: what happened, or why not.
        initial_result: the helper-arm result (arm configuration, d used, attempts).
        optimization: the optimizer's result (None with ``optimize=False`` or when the
            initial condition failed).
        timing_s: wall times ``initial`` and ``optimize`` [s].
    """

    goal: pin.SE3
    success: bool
    message: str
    initial_result: InitialConditionResult
    optimization: OptimizeResult | None = None
    timing_s: dict[str, float] = field(default_factory=dict)

    @property
    def initial(self) -> StackState | None:
        """The valid initial state (None when the helper arm found none)."""
        return self.initial_result.state if self.initial_result.success else None

    @property
    def optimized(self) -> StackState | None:
        """The best feasible optimized state (None without optimization)."""
        return self.optimization.optimized if self.optimization is not None else None

    @property
    def best(self) -> StackState | None:
        """The optimized state when there is one, else the initial one."""
        return self.optimized or self.initial

    def to_dict(self) -> dict[str, Any]:
        """JSON of ``assembler-pin solve --json``."""
        out: dict[str, Any] = {
            "goal": se3_to_taa(self.goal).tolist(),
            "success": self.success,
            "message": self.message,
            # the helper arm's state: the home pose, flagged by success false, when it failed
            "initial": self.initial_result.state.to_dict(),
        }
        if self.optimization is not None or "optimize" in self.timing_s:
            opt = self.optimization
            out["optimized"] = self.optimized.to_dict() if self.optimized is not None else None
            out["objective"] = {
                "initial": opt.objective_initial if opt else None,
                "optimized": opt.objective_optimized if opt else None,
            }
            out["timing_s"] = dict(self.timing_s)
            if opt is not None:
                out["optimizer"] = {
                    "method": opt.method,
                    "status": opt.status,
                    "message": opt.solver_message,
                    "iterations": opt.iterations,
                    "evaluations": opt.evaluations,
                }
        else:
            out["timing_s"] = dict(self.timing_s)
        return out


def solve(
    am: AssemblerModel,
    goal: pin.SE3 | np.ndarray,
    optimize: bool = True,
    options: OptimizeOptions | None = None,
    helper_options: HelperArmOptions | None = None,
) -> SolveResult:
    """Internal poses of the stack for an EE goal pose.

    Args:
        goal: EE pose in the base (world) frame, ``pin.SE3`` or 4×4.
        optimize: run the force optimization after the initial condition.
        options: optimizer settings; helper_options: helper-arm settings.

    Raises:
        PoseError: the goal is not a valid SE(3) pose.
    """
    from .helper_arm import initial_condition

    goal = to_se3(goal, "goal")
    t0 = time.perf_counter()
    init = initial_condition(am, goal, helper_options)
    timing = {"initial": time.perf_counter() - t0}
    if not init.success:
        if optimize:
            timing["optimize"] = 0.0
        return SolveResult(goal, False, f"no valid initial condition: {init.message}", init, None, timing)
    if not optimize:
        return SolveResult(goal, True, init.message, init, None, timing)
    opts = options or OptimizeOptions()
    result = optimize_internal_poses(am, init.state, goal, opts)
    timing["optimize"] = result.time_s
    message = result.message
    return SolveResult(goal, result.success, message, init, result, timing)
