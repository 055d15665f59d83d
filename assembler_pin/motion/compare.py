"""Our force-optimal motion against two simple plans of the same EE path.

* ``optimized`` — :func:`~assembler_pin.motion.timing.plan_trajectory`: every sample
  force-optimized, warm-started and kept close to the previous one.
* ``helper_arm`` — the helper arm's initial condition (paper §III) at every sample of the
  same path parameters, no optimization. A sample where it finds no valid pose is invalid
  and left out of the leg-length sequence.
* ``linear_lengths`` — the leg lengths interpolated linearly between the two end poses
  (the start state and the optimized pose at the goal), the EE wherever stack FK puts it.

All three go through the same time law (:func:`~assembler_pin.motion.timing.time_parametrize`,
the legs' speed and acceleration limits) and the same check of every output sample (stack
FK of the commanded lengths, every limit, the EE within the path tolerance), so the table
compares what a robot commanded with each plan would do.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..helper_arm import initial_condition
from ..kinematics import stack_forward_kinematics
from ..model.assembler import AssemblerModel
from ..state import evaluate_state
from .guess import on_se3
from .paths import EEPath
from .planner import PlanOptions, PlanResult
from .result import MotionResult
from .timing import plan_trajectory, time_parametrize
from .trajfile import Trajectory

__all__ = ["METHODS", "MotionComparison", "PlanFigures", "compare_motion"]

logger = logging.getLogger(__name__)

#: The plans compared, in table order.
METHODS = ("optimized", "helper_arm", "linear_lengths")


@dataclass(frozen=True)
class PlanFigures:
    """What a robot commanded with one plan does, over its timed output samples.

    Attributes:
        method: one of :data:`METHODS`.
        peak_max_abs_force: largest max|F| over the output samples [N] (nan when none
            could be evaluated).
        total_leg_travel: Σ over legs of the distance travelled [m].
        duration: duration under the legs' speed and acceleration limits [s].
        valid_fraction: fraction of output samples where every constraint holds (EE on the
            path within tolerance included); samples the plan has no pose for count as invalid.
        limits_fraction: the same without the path tolerance (legs, joints, forces only).
        max_path_deviation: largest EE distance from the path [m].
        samples: output samples checked (plus the path samples with no pose at all).
    """

    method: str
    peak_max_abs_force: float
    total_leg_travel: float
    duration: float
    valid_fraction: float
    limits_fraction: float
    max_path_deviation: float
    samples: int

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclass
class MotionComparison:
    """The three plans of one path (see the module docstring).

    Attributes:
        name: a label for the path (e.g. the scenario's name).
        motion: our planned motion.
        figures: method → :class:`PlanFigures`, in :data:`METHODS` order.
    """

    name: str
    motion: MotionResult
    figures: dict[str, PlanFigures]

    def __repr__(self) -> str:
        inner = ", ".join(
            f"{m}: peak {f.peak_max_abs_force:.1f} N, {100 * f.valid_fraction:.0f}% valid"
            for m, f in self.figures.items()
        )
        return f"MotionComparison({self.name!r}: {inner})"


def _figures(method: str, traj: Trajectory, travel: float, tolerance: float, missing: int = 0) -> PlanFigures:
    """Figures of a timed plan; ``tolerance`` is the path's position tolerance [m] and
    ``missing`` path samples had no pose at all."""
    total = len(traj.times) + missing
    limits = ("stroke", "deflection", "rise", "force")
    limits_ok = np.all([np.nan_to_num(traj.margins[k], nan=-1.0) >= 0 for k in limits], axis=0)
    margin = traj.margins["path_position"]
    return PlanFigures(
        method=method,
        peak_max_abs_force=float(np.nanmax(traj.max_abs_force)) if np.isfinite(traj.max_abs_force).any() else math.nan,
        total_leg_travel=travel,
        duration=traj.duration,
        valid_fraction=float(traj.feasible.sum()) / total,
        limits_fraction=float(limits_ok.sum()) / total,
        max_path_deviation=float(tolerance - np.nanmin(margin)) if np.isfinite(margin).any() else math.nan,
        samples=total,
    )


def _timed(am: AssemblerModel, like: PlanResult, parameters: npt.ArrayLike, states: list, rate: float) -> Trajectory:
    """The time law and checks of the same path through other states."""
    plan = dataclasses.replace(like, parameters=np.asarray(parameters, dtype=float), states=states)
    return time_parametrize(am, plan, rate=rate, strict=False)


def _travel(states: list) -> float:
    lengths = np.array([s.leg_lengths for s in states])
    return float(np.abs(np.diff(lengths, axis=0)).sum()) if len(states) > 1 else 0.0


def compare_motion(
    am: AssemblerModel,
    path: EEPath,
    start=None,
    options: PlanOptions | None = None,
    rate: float = 20.0,
    name: str = "path",
    time_law: str = "auto",
) -> MotionComparison:
    """Plan ``path`` with :func:`~assembler_pin.motion.timing.plan_trajectory` and with the
    two simple plans, each timed and checked the same way (see the module docstring).

    Args:
        path: the EE path.
        start: the stack's state at the path's start (e.g. ``am.home``).
        options: the planner's settings.
        rate: output samples per second of the three trajectories [Hz].
        name: the path's label in the table.
        time_law: the time law of our plan (:func:`~assembler_pin.motion.timing.plan_trajectory`).
    """
    motion = plan_trajectory(am, path, start, options, rate=rate, time_law=time_law)
    plan = motion.plan
    figures: dict[str, PlanFigures] = {}
    if motion.trajectory is None:
        logger.warning("compare %s: our plan has no trajectory (%s)", name, motion.reason)
        return MotionComparison(name, motion, figures)
    tol = plan.path_tolerance.position
    figures["optimized"] = _figures("optimized", motion.trajectory, motion.total_leg_travel, tol)

    # (a) the helper arm at every sample, no optimization
    params, states = [plan.parameters[0]], [plan.states[0]]
    missing = 0
    for u in plan.parameters[1:]:
        result = initial_condition(am, path.at(u))
        if result.success:
            params.append(u)
            states.append(result.state)
        else:
            missing += 1
    if len(states) >= 2:
        figures["helper_arm"] = _figures(
            "helper_arm", _timed(am, plan, params, states, rate), _travel(states), tol, missing
        )

    # (b) leg lengths linear between the two end poses
    first, last = plan.states[0], plan.states[-1]
    guess, linear = first.plates, [first]
    for t in plan.parameters[1:] / plan.parameters[-1]:
        fk = stack_forward_kinematics(
            am, (1 - t) * first.leg_lengths + t * last.leg_lengths, base=first.plates.se3(0), guess=on_se3(guess)
        )
        if not fk.success:
            break
        guess = fk.plates
        linear.append(evaluate_state(am, fk.plates))
    if len(linear) == len(plan.states):
        figures["linear_lengths"] = _figures(
            "linear_lengths", _timed(am, plan, plan.parameters, linear, rate), _travel(linear), tol
        )
    return MotionComparison(name, motion, figures)
