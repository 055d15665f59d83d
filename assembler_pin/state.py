"""A full state of the stack: plate poses, legs, statics and constraint check.

:func:`evaluate_state` is the one call that turns plate poses into everything a user
asks about a pose; :meth:`StackState.to_dict` is the JSON contract of
``assembler-pin statics --json`` (and of the ``initial`` / ``optimized`` states of
``assembler-pin solve``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from .collision.check import Clearance, clearance
from .collision.scene import Scene
from .config.options import DEFAULT_GOAL_TOLERANCE, GoalTolerance
from .constraints import Violation, evaluate_constraints
from .exceptions import OptionsError
from .kinematics import LegState, PlateArrays, checked_goal, leg_state, plate_arrays
from .model.assembler import AssemblerModel, checked_model
from .statics.engine import solve_statics
from .statics.result import StaticsResult

__all__ = ["StackState", "evaluate_state"]


@dataclass
class StackState:
    """Everything about one pose of the stack.

    Attributes:
        plates: world poses of plates 0..n.
        legs: lengths [m], joint centres, directions, deflections [rad].
        statics: actuator forces [N, tension positive], ball forces, base wrench.
        violations: every violated constraint (empty when feasible).
        goal: the EE goal it was checked against, if any.
        clearance: the smallest distance between two bodies that must not touch and which
            two (:func:`~assembler_pin.collision.check.clearance`), None when not computed.
    """

    plates: PlateArrays
    legs: LegState
    statics: StaticsResult
    violations: list[Violation] = field(default_factory=list)
    goal: pin.SE3 | None = None
    clearance: Clearance | None = None

    @property
    def feasible(self) -> bool:
        """True only when every constraint holds."""
        return not self.violations

    @property
    def forces(self) -> np.ndarray:
        """(n, 6) actuator forces [N], tension positive."""
        return self.statics.forces

    @property
    def leg_lengths(self) -> np.ndarray:
        """(n, 6) pin-to-pin leg lengths [m]."""
        return self.legs.lengths

    @property
    def max_abs_force(self) -> float:
        return self.statics.max_abs_force

    @property
    def mean_abs_force(self) -> float:
        return self.statics.mean_abs_force

    def __repr__(self) -> str:
        ee = self.plates.p[-1]
        kinds = sorted({v.kind for v in self.violations})
        verdict = "feasible" if self.feasible else f"{len(self.violations)} violations ({', '.join(kinds)})"
        return (
            f"StackState({len(self.plates) - 1} platforms, EE at {np.round(ee, 4).tolist()} m, max|F| "
            f"{self.max_abs_force:.3f} N, legs {self.leg_lengths.min():.4f}–{self.leg_lengths.max():.4f} m, "
            f"{verdict})"
        )

    def to_dict(self) -> dict:
        """The JSON contract: plates, leg_lengths, forces, bottom_points, top_points,
        max_abs_force, mean_abs_force, feasible, violations — then extras: joint
        deflections [deg], base wrench, condition numbers, and ``clearance``
        (``{"min_distance_m", "between"}``) when it was computed."""
        doc = {
            "plates": self.plates.as_matrices().tolist(),
            "leg_lengths": self.legs.lengths.tolist(),
            "forces": self.statics.forces.tolist(),
            "bottom_points": self.legs.bottom_points.tolist(),
            "top_points": self.legs.top_points.tolist(),
            "max_abs_force": self.max_abs_force,
            "mean_abs_force": self.mean_abs_force,
            "feasible": self.feasible,
            "violations": [v.to_dict() for v in self.violations],
            "deflection_deg": np.rad2deg(self.legs.deflection).tolist(),
            "base_wrench": self.statics.base_wrench.tolist(),
            "condition": self.statics.condition.tolist(),
        }
        if self.clearance is not None:
            doc["clearance"] = self.clearance.to_dict()
        return doc


def evaluate_state(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    goal: pin.SE3 | None = None,
    tolerance: GoalTolerance = DEFAULT_GOAL_TOLERANCE,
    data: pin.Data | None = None,
    scene: Scene | str | None = None,
) -> StackState:
    """Leg state, statics, clearance and constraint check of the given plate poses.

    A pose whose clearance (:func:`~assembler_pin.collision.check.clearance`) is below the
    configuration's ``clearance`` gets a ``collision`` violation naming the two bodies.

    Args:
        plates: world poses of plates 0..n, plate 0 first, or a :class:`StackState`.
        goal: optional EE goal to check plate n against.
        tolerance: EE goal tolerance.
        data: a whole-stack Pinocchio ``Data`` the caller owns, for the statics
            (:func:`~assembler_pin.statics.engine.solve_statics`); default one model per platform.
        scene: obstacles and floor (:class:`~assembler_pin.collision.scene.Scene` or a scene file),
            None for the stack's own bodies only.
    """
    checked_model(am)
    if goal is not None:
        goal = checked_goal(goal, "goal")
    if not isinstance(tolerance, GoalTolerance):
        raise OptionsError(f"tolerance must be a GoalTolerance, got {type(tolerance).__name__}")
    pa = plate_arrays(am, plates)
    legs = leg_state(am, pa)
    statics = solve_statics(am, pa, legs=legs, data=data)
    violations = evaluate_constraints(am.config, legs, statics, pa, goal, tolerance)
    near = clearance(am, pa, scene)
    if not near.min_distance >= near.limit:  # NaN is a violation, never a pass
        violations.append(Violation("collision", None, None, near.min_distance, near.limit, near.between))
    return StackState(pa, legs, statics, violations, goal, near)
