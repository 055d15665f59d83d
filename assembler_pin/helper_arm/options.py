"""Options of the helper arm's initial condition (:func:`~assembler_pin.helper_arm.initial_condition`),
the one source of its defaults (the arm IK and the CLI read them from here)."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field

from ..constraints import GoalTolerance
from ..exceptions import OptionsError
from ..validation import is_number

__all__ = ["HelperArmOptions"]


@dataclass
class HelperArmOptions:
    """Options of :func:`initial_condition`.

    Attributes:
        d_step: step s of the link-length scan [m] (see :func:`initial_condition`).
        max_attempts: recursion limit: the most arm solves (scan values of d) tried.
        tolerance: EE goal tolerance of the returned state [m, rad].
        regularization: weight w of the pull of the joints toward 0 [m/rad].
        constraint_weight: weight of the stack's leg constraints in the arm IK
            (:meth:`HelperArm.ik`).
        arm_tolerance: the arm counts as reaching the goal within this error [m, rad].
        restarts: extra deterministic starts of the arm IK per d.
        free_link_length: let the arm IK move d continuously over the whole
            :func:`height_range`, starting at each scan value (False: d fixed at the scan
            values, the paper's scan exactly).
        repair_starts: after a scan without success, how many of the arm's closest poses
            (fewest goal error plus leg violation) are repaired on the stack itself
            (0: no repair).
        perturbed_starts: how many randomly perturbed copies of the even screw pose are
            repaired too, after the even pose itself (seeded).
    """

    d_step: float = 0.01
    max_attempts: int = 15
    tolerance: GoalTolerance = field(default_factory=lambda: GoalTolerance(1e-9, 1e-9))
    regularization: float = 0.05
    constraint_weight: float = 10.0
    arm_tolerance: float = 1e-10
    restarts: int = 0
    free_link_length: bool = True
    repair_starts: int = 2
    perturbed_starts: int = 8

    def __post_init__(self) -> None:
        for name in ("d_step", "regularization", "constraint_weight", "arm_tolerance"):
            value = getattr(self, name)
            if not (is_number(value) and math.isfinite(value) and value >= 0):
                raise OptionsError(f"{name} must be a finite number >= 0, got {value!r}")
        if not self.d_step > 0:
            raise OptionsError(f"d_step must be a positive number of metres, got {self.d_step!r}")
        for name, low in (("max_attempts", 1), ("restarts", 0), ("repair_starts", 0), ("perturbed_starts", 0)):
            value = getattr(self, name)
            if not (isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= low):
                raise OptionsError(f"{name} must be an integer >= {low}, got {value!r}")
        if not isinstance(self.tolerance, GoalTolerance):
            raise OptionsError(f"tolerance must be a GoalTolerance, got {self.tolerance!r}")
