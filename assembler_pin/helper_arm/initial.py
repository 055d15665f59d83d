"""The initial condition (paper §III): the d scan of the helper arm, the repair, the result.

See the package docstring for the method. Units: metres and radians; poses are world poses.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Iterator

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..common.messages import binding, describe, number
from ..common.threads import one_blas_thread
from ..config.options import GoalTolerance, HelperArmOptions, checked_options
from ..constraints import evaluate_constraints
from ..kinematics import PlateArrays, even_screw_pose, leg_state, to_se3
from ..model.assembler import AssemblerModel
from ..model.geometry import reach_bound
from ..state import StackState, evaluate_state
from .cache import ArmCache, arm_cache
from .limits import cluster_limits, height_range
from .link_lengths import link_length_scan
from .outcome import Candidate, InitialConditionResult, Scan, failure_result, success_result, why_not
from .repair import perturbed_plates, repair_stack

__all__ = ["KINEMATIC_VIOLATIONS", "initial_condition"]

logger = logging.getLogger(__name__)

#: Arm solves of the d scan before a first, cheap repair (the closest arm pose, the even screw
#: pose and its perturbed copies) is tried; the rest of the scan and the repair of its closest
#: arm poses follow only when it fails.
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
        return failure_result(am, goal_se3, opts, why, Scan(), t0)
    scan = Scan()
    d_values = link_length_scan(am.config.home_height, distance, am.n, opts.d_step, height_range(am.config))
    tried: set[tuple] = set()
    for limit in (min(CHEAP_SCAN, opts.max_attempts), opts.max_attempts):
        found = _scan_link_lengths(am, goal_se3, opts, arms, d_values, scan, limit)
        if found is not None:
            return success_result(found[0], goal_se3, found[1], scan.attempts, t0, repaired=False)
        # cheap first: the closest arm pose so far and the (perturbed) even screw pose, before the rest of the scan
        repairs = _repair_starts(am, goal_se3, opts, scan, cheap=limit < opts.max_attempts)
        done = _try_repairs(am, goal_se3, opts, repairs, tried, scan.attempts, t0)
        if done is not None:
            return done
    return failure_result(am, goal_se3, opts, why_not(scan, repairs, opts), scan, t0, distance)


def _scan_link_lengths(
    am: AssemblerModel,
    goal: pin.SE3,
    opts: HelperArmOptions,
    arms: ArmCache,
    d_values: Iterator[float],
    scan: Scan,
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
    am: AssemblerModel, goal: pin.SE3, opts: HelperArmOptions, scan: Scan, cheap: bool = False
) -> list[Candidate]:
    """The poses the repair starts from: the arm's ``repair_starts`` closest poses, the even
    screw pose, and ``perturbed_starts`` seeded perturbations of it (the even pose is often a
    saddle of the leg limits: every platform alike); with ``cheap``, the closest arm pose
    only. The screw poses do not depend on the scan: tried once in the cheap stage, they are
    skipped after the rest of it (:func:`_try_repairs`)."""
    if opts.repair_starts == 0 or scan.last_q is None:
        return []
    starts = sorted(scan.candidates, key=lambda c: c.score)[: 1 if cheap else opts.repair_starts]
    screw = even_screw_pose(am, goal)
    starts.append(Candidate(math.inf, screw))
    starts += [Candidate(math.inf, plates) for plates in perturbed_plates(screw, opts.perturbed_starts)]
    return starts


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
            return success_result(state, goal, cand, attempts, t0, repaired=True)
        logger.debug("repair from the pose at d=%s: %s", cand.link_length, why)
    return None
