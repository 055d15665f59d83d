"""The initial condition (paper §III): the d scan of the helper arm, the repair, the result.

See the package docstring for the method. Units: metres and radians; poses are world poses.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..constraints import GoalTolerance, evaluate_constraints
from ..geometry import reach_bound
from ..kinematics import PlateArrays, leg_state, to_se3
from ..messages import binding, describe, number, one_line
from ..model import AssemblerModel
from ..options import checked_options
from ..state import StackState, evaluate_state
from ..threads import one_blas_thread
from .cache import ArmCache, arm_cache
from .limits import cluster_limits, height_range
from .link_lengths import link_length_scan
from .options import HelperArmOptions
from .repair import perturbed_plates, repair_stack

__all__ = [
    "KINEMATIC_VIOLATIONS",
    "Candidate",
    "InitialConditionResult",
    "arm_cache",
    "even_screw_pose",
    "initial_condition",
]

logger = logging.getLogger(__name__)

#: Arm solves of the d scan before a first, cheap repair (closest arm pose, even screw pose)
#: is tried; the rest of the scan and the full repair follow only when it fails.
CHEAP_SCAN = 2

#: Violation kinds that make an initial condition invalid (force limits are reported only).
KINEMATIC_VIOLATIONS = frozenset(
    {
        "min_length",
        "max_length",
        "deflection_bottom",
        "deflection_top",
        "continuous_translation",
        "ee_position",
        "ee_rotation",
        "singular",
    }
)


@dataclass
class InitialConditionResult:
    """The initial pose of the stack for a goal, from the helper arm.

    Attributes:
        success: True only when the state satisfies every kinematic constraint
            (:data:`KINEMATIC_VIOLATIONS`: leg limits, joint deflection, continuous
            translation, EE at the goal, no singular platform). Force limits are *not*
            required: they are reported in ``state`` (``state.feasible`` requires them too).
        message: what happened; on failure one line naming the binding cause
            (:mod:`~assembler_pin.messages`).
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


def _kinematic_problems(
    am: AssemblerModel, pa: PlateArrays, goal: pin.SE3, tolerance: GoalTolerance
) -> tuple[StackState | None, str]:
    """The state of plates ``pa`` if it meets every kinematic constraint, else (None, why)."""
    kin = evaluate_constraints(am.config, leg_state(am, pa), None, pa, goal, tolerance)
    if kin:
        return None, describe(binding(kin))
    state = evaluate_state(am, pa, goal=goal, tolerance=tolerance)
    bad = [v for v in state.violations if v.kind in KINEMATIC_VIOLATIONS]
    if bad:
        return None, describe(binding(bad))
    return state, ""


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
class _Scan:
    """What the d scan met, for the repair and the failure message."""

    attempts: int = 0
    broken: list[str] = field(default_factory=list)  # the arm reached the goal, the plates were invalid
    closest: str = ""
    closest_error: float = math.inf
    closest_position: float = math.inf  # [m]
    closest_rotation: float = math.inf  # [rad]
    last_q: np.ndarray | None = None
    last_points: np.ndarray | None = None
    candidates: list[Candidate] = field(default_factory=list)


@one_blas_thread
def initial_condition(
    am: AssemblerModel,
    goal: pin.SE3 | npt.ArrayLike,
    options: HelperArmOptions | None = None,
    arms: ArmCache | None = None,
) -> InitialConditionResult:
    """A valid initial pose of the whole stack for an EE goal, by the helper arm (paper §III).

    See the package docstring for the algorithm. Plate 0 stays at ``am.home[0]``; plate n is
    put exactly at ``goal``; plates 1..n-1 at the arm's link midpoints (or near them, when
    the arm's closest pose had to be repaired).

    Args:
        am: the stack model.
        goal: world pose of the EE (``pin.SE3`` or 4×4).
        options: scan step, recursion limit, tolerances.
        arms: the helper arms to use and fill, owned by the caller (default: the
            per-thread cache of this configuration, :func:`~assembler_pin.helper_arm.arm_cache`).

    Returns:
        An :class:`InitialConditionResult` (``success`` False with the reason when no valid
        pose was found: the state is then the home pose).

    Raises:
        PoseError: the goal is not a finite SE(3) pose.
    """
    t0 = time.perf_counter()
    goal_se3 = to_se3(goal, "goal")
    opts = checked_options(options, HelperArmOptions, "options")
    arms = arm_cache(am) if arms is None else arms
    distance = math.hypot(*(goal_se3.translation - am.home[0].translation))  # no overflow for huge goals
    reach = reach_bound(am.config)
    if not distance <= reach:
        why = (
            f"no valid initial condition: unreachable: the goal is {number(distance, 'm')} from the base, "
            f"out of reach: farther than the stack can span ({reach:.4g} m)"
        )
        return _failure(am, goal_se3, opts, why, _Scan(), t0)
    scan = _Scan()
    d_values = link_length_scan(am.config.home_height, distance, am.n, opts.d_step, height_range(am.config))
    tried: set[tuple] = set()
    for limit in (min(CHEAP_SCAN, opts.max_attempts), opts.max_attempts):
        found = _scan_link_lengths(am, goal_se3, opts, arms, d_values, scan, limit)
        if found is not None:
            return _success(found[0], goal_se3, found[1], scan.attempts, t0, repaired=False)
        # cheap first: the closest arm pose so far and the even screw pose, before the rest of the scan
        repairs = _repair_starts(am, goal_se3, opts, scan, cheap=limit < opts.max_attempts)
        done = _try_repairs(am, goal_se3, opts, repairs, tried, scan.attempts, t0)
        if done is not None:
            return done
    return _failure(am, goal_se3, opts, _why_not(scan, repairs, opts), scan, t0, distance)


def _scan_link_lengths(
    am: AssemblerModel,
    goal: pin.SE3,
    opts: HelperArmOptions,
    arms: ArmCache,
    d_values: Iterator[float],
    scan: _Scan,
    limit: int,
) -> tuple[StackState, Candidate] | None:
    """The paper's recursion over d: solve the arm from each next scan value of ``d_values``
    until its plates are a valid stack pose (returned with the arm pose) or ``scan`` counts
    ``limit`` attempts, recording what failed in ``scan``."""
    cfg, base, n = am.config, am.home[0], am.n
    d_range = height_range(cfg)
    while scan.attempts < limit:
        d_start = next(d_values, None)
        if d_start is None:
            break
        tilt, twist = cluster_limits(cfg, d_start)
        if tilt <= 0.0 or twist <= 0.0:  # a level SP (nearly) cannot stand at this height
            continue
        scan.attempts += 1
        arm = arms.get(d_start)
        ik = arm.ik(goal, base, options=opts, link_range=d_range if opts.free_link_length else None)
        d = float(ik.link_length if ik.link_length is not None else d_start)
        plates, points = arm.forward(ik.q, base, d)
        plates[n] = goal.copy()
        scan.last_q, scan.last_points = ik.q, points
        if not ik.success:
            viol = float(arm.stack_violation(ik.q, 0.0, d).max())
            scan.candidates.append(Candidate(ik.position_error + ik.rotation_error + viol, plates, ik.q, d, points))
            if ik.position_error <= opts.arm_tolerance and ik.rotation_error <= opts.arm_tolerance:
                scan.broken.append(f"d={d:.4f}: leg stroke or joint deflection: the plates break the stack's limits")
            elif ik.position_error + ik.rotation_error < scan.closest_error:
                scan.closest_error = ik.position_error + ik.rotation_error
                scan.closest = f"closest: {ik.position_error:.3g} m, {ik.rotation_error:.3g} rad away at d = {d:.4f} m"
                scan.closest_position, scan.closest_rotation = ik.position_error, ik.rotation_error
            logger.debug("initial condition: %s", ik.message)
            continue
        state, why = _kinematic_problems(am, PlateArrays.from_se3(plates), goal, opts.tolerance)
        if state is None:
            scan.broken.append(f"d={d:.4f}: {why}")
            scan.candidates.append(Candidate(0.0, plates, ik.q, d, points))
            logger.debug("initial condition at d=%.4f: kinematic violation(s) %s", d, why)
            continue
        return state, Candidate(0.0, plates, ik.q, d, points)
    return None


def _repair_starts(
    am: AssemblerModel, goal: pin.SE3, opts: HelperArmOptions, scan: _Scan, cheap: bool = False
) -> list[Candidate]:
    """The poses the repair starts from: the arm's ``repair_starts`` closest poses, the even
    screw pose, and ``perturbed_starts`` seeded perturbations of it (the even pose is often a
    saddle of the leg limits: every platform alike); with ``cheap``, the closest arm pose
    and the even screw pose only."""
    if opts.repair_starts == 0 or scan.last_q is None:
        return []
    starts = sorted(scan.candidates, key=lambda c: c.score)[: 1 if cheap else opts.repair_starts]
    starts.append(Candidate(math.inf, even_screw_pose(am, goal)))
    if not cheap:
        starts += [Candidate(math.inf, plates) for plates in perturbed_plates(starts[-1].plates, opts.perturbed_starts)]
    return starts


def even_screw_pose(am: AssemblerModel, goal: pin.SE3) -> list[pin.SE3]:
    """The even screw pose: plate k at ``base·exp6(k/n · log6(base⁻¹·goal))`` (every platform
    the same relative transform), plate n at the goal; the one definition (the helper arm's
    last repair start and the solver's ``screw`` start)."""
    base, n = am.home[0], am.n
    screw = pin.log6(base.actInv(goal))
    return [base * pin.exp6(screw * (k / n)) for k in range(n)] + [goal.copy()]


def _start_key(cand: Candidate) -> tuple:
    """Repair starts already tried are not tried again: the same plate positions [m]."""
    return tuple(np.round(np.concatenate([m.translation for m in cand.plates]), 12))


def _try_repairs(
    am: AssemblerModel,
    goal: pin.SE3,
    opts: HelperArmOptions,
    repairs: list[Candidate],
    tried: set[tuple],
    attempts: int,
    t0: float,
) -> InitialConditionResult | None:
    """The first valid repair of the ``repairs`` not yet ``tried`` (recorded there), or None."""
    for cand in repairs:
        key = _start_key(cand)
        if key in tried:
            continue
        tried.add(key)
        pa, viol = repair_stack(am, cand.plates)
        if viol > 0.0:
            logger.debug("repair from the pose at d=%s: %.3g left", cand.link_length, viol)
            continue
        state, why = _kinematic_problems(am, pa, goal, opts.tolerance)
        if state is not None:
            return _success(state, goal, cand, attempts, t0, repaired=True)
        logger.debug("repair from the pose at d=%s: %s", cand.link_length, why)
    return None


def _success(
    state: StackState, goal: pin.SE3, cand: Candidate, attempts: int, t0: float, repaired: bool
) -> InitialConditionResult:
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


def _why_not(scan: _Scan, repairs: list[Candidate], opts: HelperArmOptions) -> str:
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


def _short_why(scan: _Scan, repaired: bool) -> str:
    """The one-line cause of a failed scan (:mod:`~assembler_pin.messages`); ``repaired``:
    a repair of the stack was tried too."""
    tried = f"after {scan.attempts} attempt(s){', repair failed' if repaired else ''}"
    head = "no valid initial condition: "
    if scan.broken:
        return f"{head}{scan.broken[0].split(': ', 1)[-1]} (where the helper arm reaches the goal; {tried})"
    if math.isfinite(scan.closest_error):
        pos, rot = number(1e3 * scan.closest_position, "mm"), number(math.degrees(scan.closest_rotation), "°")
        return f"{head}unreachable: the helper arm comes no closer than {pos} and {rot} to the goal ({tried})"
    return f"{head}unreachable: no link length within the heights an SP can have"


def _failure(
    am: AssemblerModel,
    goal: pin.SE3,
    opts: HelperArmOptions,
    why: str,
    scan: _Scan,
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
        message = one_line(_short_why(scan, "repairing" in why))
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
