"""What :func:`~assembler_pin.helper_arm.initial_condition` answers: its result, the arm
poses it keeps as repair starts, what its scan met, and the messages of success and failure.

Lengths in metres,
angles in radians, times in seconds.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..common.messages import binding, describe, number, one_line
from ..config.options import HelperArmOptions
from ..kinematics import PlateArrays
from ..model.assembler import AssemblerModel
from ..state import StackState, evaluate_state
from .limits import height_range

__all__ = ["Candidate", "InitialConditionResult", "Scan", "failure_result", "success_result", "why_not"]

#: The records of :func:`~assembler_pin.helper_arm.initial_condition`, whichever module writes them.
logger = logging.getLogger("assembler_pin.helper_arm.initial")


@dataclass
class InitialConditionResult:
    """The initial pose of the stack for a goal, from the helper arm.

    Attributes:
        success: True only when the state satisfies every kinematic constraint
            (:data:`~assembler_pin.helper_arm.initial.KINEMATIC_VIOLATIONS`: leg limits, joint deflection, continuous
            translation, EE at the goal, no singular platform). Force limits are *not*
            required: they are reported in ``state`` (``state.feasible`` requires them too).
        message: what happened; on failure one line naming the binding cause
            (:mod:`~assembler_pin.common.messages`).
        goal: the EE goal (world pose).
        state: the valid state, or the home state (checked against the goal) on failure.
        leg_lengths: (n, 6) leg lengths of ``state`` [m].
        arm_q: (3n,) helper-arm joint angles used [rad] (on failure: of the last arm
            solution tried, if any; None after a repair from the even screw pose).
        link_length: the d of the arm used [m] (None on failure, and after a repair from
            the even screw pose).
        attempts: arm solves (values of d) tried.
        time_s: wall time [s].
        arm_points: (n+2, 3) world points of the arm used: base, the n clusters, tip
            (None when no arm pose was used).
        repaired: the plates are the arm's closest pose moved onto a valid stack pose
            (then they are near, not exactly at, the arm's link midpoints).
    """

    success: bool
    message: str
    goal: pin.SE3
    state: StackState
    leg_lengths: np.ndarray
    arm_q: np.ndarray | None
    link_length: float | None
    attempts: int
    time_s: float
    arm_points: np.ndarray | None = None
    repaired: bool = False
    details: str = ""
    """Everything the scan and the repair met (the long form of a failure's message)."""

    def __repr__(self) -> str:
        d = f"{self.link_length:.4f} m" if self.link_length is not None else "-"
        return (
            f"InitialConditionResult(success={self.success}, max|F| {self.state.max_abs_force:.3f} N, d {d}, "
            f"{self.attempts} attempts, {1e3 * self.time_s:.1f} ms{', repaired' if self.repaired else ''}, "
            f"message={self.message!r})"
        )

    def plates_if_valid(self) -> PlateArrays | None:
        """The valid state's plate poses, None when no valid initial condition was found."""
        return self.state.plates if self.success else None


@dataclass
class Candidate:
    """An arm pose that gave no valid stack, kept as a start for the repair.

    Attributes:
        score: goal error [m + rad] plus the largest leg violation; lower is closer.
        plates: world poses of plates 0..n (plate n at the goal).
        q, link_length, points: the arm's joint angles [rad], d [m] and world points, or
            None for a pose that did not come from the arm (the screw poses).
    """

    score: float
    plates: list[pin.SE3]
    q: np.ndarray | None = None
    link_length: float | None = None
    points: np.ndarray | None = None


@dataclass
class Scan:
    """What the d scan of :func:`~assembler_pin.helper_arm.initial_condition` met, for the
    repair and the failure message."""

    attempts: int = 0
    broken: list[str] = field(default_factory=list)  # the arm reached the goal, the plates were invalid
    closest: str = ""
    closest_error: float = math.inf
    closest_position: float = math.inf  # [m]
    closest_rotation: float = math.inf  # [rad]
    last_q: np.ndarray | None = None
    last_points: np.ndarray | None = None
    candidates: list[Candidate] = field(default_factory=list)


def success_result(
    state: StackState, goal: pin.SE3, cand: Candidate, attempts: int, t0: float, repaired: bool
) -> InitialConditionResult:
    """The result of a valid state found from ``cand`` (``t0``: the start, ``time.perf_counter``)."""
    dt = time.perf_counter() - t0
    d = cand.link_length
    if d is None:
        how = "repaired on the stack from the even screw pose (the arm's poses were not)"
    elif repaired:
        how = f"repaired on the stack from the helper arm's closest pose at link length d = {d:.4f} m"
    else:
        how = f"with link length d = {d:.4f} m"
    logger.info("initial condition found (%s) after %d attempt(s) in %.1f ms", how, attempts, 1e3 * dt)
    worst = binding(state.violations)
    forces = "" if worst is None else f"; not feasible: {describe(worst)}"
    how = how if worst is None else how.replace(" from the helper arm's closest pose at link length", " from")
    return InitialConditionResult(
        True,
        one_line(f"valid initial condition {how} after {attempts} attempt(s){forces}"),
        goal,
        state,
        state.leg_lengths.copy(),
        None if cand.q is None else cand.q.copy(),
        d,
        attempts,
        dt,
        cand.points,
        repaired,
    )


def why_not(scan: Scan, repairs: list[Candidate], opts: HelperArmOptions) -> str:
    """The long form of a failure: what the scan and the repair met."""
    if scan.attempts == 0:
        why = "no link length within the heights an SP can have was tried"
    elif scan.broken:
        more = "; …" if len(scan.broken) > 3 else ""
        listed = "; ".join(scan.broken[:3]) + more
        why = f"the helper arm reached the goal only with plates that break a kinematic constraint ({listed})"
    else:
        why = f"the goal is out of the helper arm's reach within its joint limits ({scan.closest})"
    if repairs:
        why += (
            f"; repairing {len(repairs) - 1 - opts.perturbed_starts} of its closest pose(s), the even screw pose "
            f"and {opts.perturbed_starts} perturbed copies on the stack failed"
        )
    return why


def short_why(scan: Scan, repaired: bool) -> str:
    """The one-line cause of a failed scan (:mod:`~assembler_pin.common.messages`); ``repaired``:
    a repair of the stack was tried too."""
    tried = f"after {scan.attempts} attempt(s){', repair failed' if repaired else ''}"
    head = "no valid initial condition: "
    if scan.broken:
        return f"{head}{scan.broken[0].split(': ', 1)[-1]} (where the helper arm reaches the goal; {tried})"
    if math.isfinite(scan.closest_error):
        pos, rot = number(1e3 * scan.closest_position, "mm"), number(math.degrees(scan.closest_rotation), "°")
        return f"{head}unreachable: the helper arm comes no closer than {pos} and {rot} to the goal ({tried})"
    return f"{head}unreachable: no link length within the heights an SP can have"


def failure_result(
    am: AssemblerModel,
    goal: pin.SE3,
    opts: HelperArmOptions,
    why: str,
    scan: Scan,
    t0: float,
    distance: float | None = None,
) -> InitialConditionResult:
    """The home pose, checked against the goal, with the reason."""
    state = evaluate_state(am, am.home, goal=goal, tolerance=opts.tolerance)
    if distance is None:  # answered before the scan
        message = details = why
    else:
        d0, (lo, hi) = am.config.home_height, height_range(am.config)
        details = (
            f"no valid initial condition after {scan.attempts} attempt(s) (d from {d0:.4f} m, then from "
            f"{min(max(distance / am.n, lo), hi):.4f} m, step {opts.d_step} m): {why}"
        )
        message = one_line(short_why(scan, "repairing" in why))
    logger.info("initial condition failed: %s", details)
    return InitialConditionResult(
        False,
        message,
        goal,
        state,
        state.leg_lengths.copy(),
        scan.last_q,
        None,
        scan.attempts,
        time.perf_counter() - t0,
        scan.last_points,
        details=details,
    )
