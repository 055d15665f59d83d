"""Goal pose → internal poses: the helper-arm initial condition, then force optimization.

:func:`solve` is the whole pipeline behind ``assembler-pin solve``: a fast valid initial
pose from the helper arm (paper §III), then, unless told not to, the force-optimized
internal poses (paper §IV). An unreachable goal is an answer (``success=False`` with the
reason), not an exception.
"""

from __future__ import annotations

import math
import time
import zlib
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from ..collision.scene import Scene, read_scene
from ..common.messages import binding, describe, one_line
from ..common.threads import one_blas_thread
from ..config.options import checked_options
from ..constraints import leg_limit_margins
from ..exceptions import ArgumentError, OptionsError
from ..helper_arm import HelperArmOptions, initial_condition, perturbed_plates, repair_stack
from ..helper_arm.initial import even_screw_pose, lean_poses
from ..kinematics import PlateArrays, se3_to_taa, to_se3
from ..model.assembler import AssemblerModel, checked_model
from ..optimize import OptimizeOptions, OptimizeResult, optimize_internal_poses
from ..state import StackState, evaluate_state

if TYPE_CHECKING:
    from ..helper_arm import InitialConditionResult

__all__ = [
    "AT_LIMIT",
    "COMPRESSED_SHARE",
    "STARTS",
    "START_MODES",
    "SolveResult",
    "needs_other_starts",
    "optimizer_starts",
    "solve",
]

#: The starts the optimizer runs from, in order: the helper arm's valid initial condition,
#: the home pose's internal plates, and the even screw pose (every platform the same
#: relative transform). Each converges in a few tens of ms; the best feasible optimum wins.
STARTS = ("helper_arm", "home", "screw")

#: The values of ``solve(starts=...)``: ``first`` runs the helper arm's start, then the
#: screw start only when the helper arm's optimum needs it (:func:`needs_other_starts`) and
#: every start when the helper arm's run failed; ``all`` runs every start.
START_MODES = ("first", "all")

#: Extra starts tried only when every start in :data:`STARTS` failed: the helper arm's pose
#: (or the screw pose) with its internal plates perturbed and repaired onto the leg limits
#: (seeded, so the answer is reproducible).
FALLBACK_STARTS = 4


@dataclass
class SolveResult:
    """Outcome of :func:`solve`.

    Attributes:
        goal: the EE goal pose.
        success: a valid pose is returned: it meets every constraint, re-checked with the
            Pinocchio statics (the optimized pose when optimizing, else the helper arm's).
            Whether it is also the optimum is :attr:`optimal`.
        message: what happened, or why not: one line naming the binding cause
            (:mod:`~assembler_pin.common.messages`); the long form in ``details``.
        initial_result: the helper-arm result (arm configuration, d used, attempts).
        optimization: the optimizer's result from the winning start (None with
            ``optimize=False`` or when no start gave a feasible state).
        timing_s: wall times ``initial`` and ``optimize`` (all starts) [s].
        start: name of the start the returned optimum came from (see :data:`STARTS`;
            ``perturbed_k`` for a fallback start), None without one.
        runs: every start tried → its optimization result.
    """

    goal: pin.SE3
    success: bool
    message: str
    initial_result: InitialConditionResult
    optimization: OptimizeResult | None = None
    timing_s: dict[str, float] = field(default_factory=dict)
    start: str | None = None
    runs: dict[str, OptimizeResult] = field(default_factory=dict)
    details: str = ""
    """What every step met: the helper arm's scan, each start's result (may be long)."""

    @property
    def optimal(self) -> bool:
        """The returned pose is an optimum: the first-order conditions hold at it
        (:func:`~assembler_pin.optimize.certificate.optimality`); False without optimization."""
        return self.success and self.optimization is not None and self.optimization.optimal

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

    def __repr__(self) -> str:
        init = f"{self.initial.max_abs_force:.3f} N" if self.initial is not None else "-"
        opt = f"{self.optimized.max_abs_force:.3f} N" if self.optimized is not None else "-"
        times = ", ".join(f"{k} {1e3 * v:.0f} ms" for k, v in self.timing_s.items())
        return (
            f"SolveResult(success={self.success}, optimal={self.optimal}, "
            f"goal {np.round(self.goal.translation, 4).tolist()} m, max|F| "
            f"initial {init} → optimized {opt} (start {self.start}), {times}, "
            f"message={self.message!r})"
        )

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
            helper_run = self.runs.get("helper_arm")
            out["optimized"] = self.optimized.to_dict() if self.optimized is not None else None
            out["objective"] = {
                # Ω of the helper arm's initial condition (None when it found none)
                "initial": helper_run.objective_initial if helper_run else None,
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
                out["optimality"] = opt.optimality.to_dict() if opt.optimality is not None else None
            out["start"] = self.start
            out["starts"] = {
                name: {
                    "success": r.success,
                    "optimal": r.optimal,
                    "max_abs_force": r.optimized.max_abs_force,
                    "message": r.message,
                }
                for name, r in self.runs.items()
            }
        else:
            out["timing_s"] = dict(self.timing_s)
        out["optimal"] = self.optimal  # the returned pose is a certified optimum (docs/contract.md)
        out["details"] = self.details  # the long form of message: every step met (may be long)
        return out


@one_blas_thread
def solve(
    am: AssemblerModel,
    goal: pin.SE3 | np.ndarray,
    optimize: bool = True,
    options: OptimizeOptions | None = None,
    helper_options: HelperArmOptions | None = None,
    starts: str = "first",
    scene: Scene | str | None = None,
) -> SolveResult:
    """Internal poses of the stack for an EE goal pose.

    The helper arm gives a valid initial condition; the optimizer then runs from it and,
    with ``starts="all"`` or when that run needs them (:func:`needs_other_starts`), from the
    cheap starts of :data:`STARTS` (and, when every one fails, from perturbed screw starts);
    the best feasible optimum is returned with the name of its start. A goal the helper arm
    cannot reach may still be solved from another start.

    Args:
        goal: EE pose in the base (world) frame, ``pin.SE3`` or 4×4.
        optimize: run the force optimization after the initial condition.
        options: optimizer settings; helper_options: helper-arm settings.
        starts: ``"first"`` (default): the helper arm's start alone when its optimum is
            final by :func:`needs_other_starts`, else every start; ``"all"``: every start.
        scene: obstacles and floor (:class:`~assembler_pin.collision.scene.Scene`, a scene
            file or None): every run keeps every checked pair of bodies at least the
            configuration's ``clearance`` apart (the optimizer's clearance rows), and a goal
            no start reaches without a collision is answered ``success=False`` with the cause
            ``collision``. The helper arm does not see the scene: its pose is only a start.

    Returns:
        A :class:`SolveResult`: ``success`` (a valid pose was found, every constraint
        re-checked) and ``message`` (why not, when not); ``optimized`` the force-optimized
        :class:`~assembler_pin.state.StackState` (``.plates``, ``.forces`` [N],
        ``.max_abs_force``), ``initial`` the helper arm's, ``best`` the first of the two that
        exists; ``optimal`` whether the pose is proven an optimum. An unreachable goal is an
        answer (``success=False``), not an exception.

    Raises:
        PoseError: the goal is not a valid SE(3) pose.
        OptionsError: ``starts`` is not one of :data:`START_MODES`.
    """
    goal, options, helper_options = _checked_inputs(am, goal, optimize, options, helper_options, starts)
    scene = read_scene(scene)
    t0 = time.perf_counter()
    init = initial_condition(am, goal, helper_options)
    timing = {"initial": time.perf_counter() - t0}
    helper = f"helper arm: {init.details or init.message}"
    if not optimize:
        if scene is not None and init.success:  # the helper arm's pose, checked in the scene
            state = evaluate_state(am, init.state.plates, goal=goal, tolerance=helper_options.tolerance, scene=scene)
            if not state.feasible:
                why = one_line(f"{describe(binding(state.violations))} (the helper arm's pose, in the scene)")
                return SolveResult(goal, False, why, init, None, timing, details=helper)
        return SolveResult(goal, init.success, init.message, init, None, timing, details=helper)
    if init.attempts == 0 and not init.success:  # out of reach: nothing to start from
        timing["optimize"] = 0.0
        return SolveResult(goal, False, init.message, init, None, timing, details=helper)
    t1 = time.perf_counter()
    runs = _run_starts(am, goal, init, options, starts, scene)
    timing["optimize"] = time.perf_counter() - t1
    return _answer(goal, init, runs, timing)


def _checked_inputs(
    am: AssemblerModel,
    goal: pin.SE3 | np.ndarray,
    optimize: bool,
    options: OptimizeOptions | None,
    helper_options: HelperArmOptions | None,
    starts: str,
) -> tuple[pin.SE3, OptimizeOptions, HelperArmOptions]:
    """(goal, options, helper options) of :func:`solve`, or the error naming what is wrong."""
    checked_model(am)
    if starts not in START_MODES:
        raise OptionsError(f"starts must be one of {', '.join(START_MODES)}, got {starts!r}")
    goal = to_se3(goal, "goal")
    options = checked_options(options, OptimizeOptions, "options")
    helper_options = checked_options(helper_options, HelperArmOptions, "helper_options")
    if not isinstance(optimize, bool):
        raise ArgumentError(f"optimize must be True or False, got {type(optimize).__name__}")
    return goal, options, helper_options


def _answer(
    goal: pin.SE3, init: InitialConditionResult, runs: dict[str, OptimizeResult], timing: dict[str, float]
) -> SolveResult:
    """The :class:`SolveResult` of the optimizer's runs: the best run (:func:`_best_run`) or
    why none reached a feasible pose."""
    name, best = _best_run(runs)
    helper = f"helper arm: {init.details or init.message}"
    details = "; ".join([helper, *(f"{k} start: {r.message}" for k, r in runs.items())])
    if best is None:
        return SolveResult(goal, False, _no_start_message(init, runs), init, None, timing, None, runs, details=details)
    message = f"{best.message} (from the {name} start)"
    if not init.success:
        message += "; the helper arm found no valid initial condition"
    return SolveResult(goal, best.success, one_line(message), init, best, timing, name, runs, details=details)


def _no_start_message(init: InitialConditionResult, runs: dict[str, OptimizeResult]) -> str:
    """One line when no start reached a feasible pose: the helper arm's cause when it
    failed, else the binding violation of the closest start (smallest Ω)."""
    if not init.success:
        return one_line(f"{init.message}; no optimizer start reached a feasible pose")
    feasible = [r for r in runs.values() if r.optimized.feasible]
    closest = min(feasible or runs.values(), key=lambda r: r.objective_optimized, default=None)
    if closest is not None and closest.optimized.feasible:  # kept out by the sag limit or a motion step
        return one_line(f"{closest.message} (closest of {len(runs)} optimizer starts)")
    worst = None if closest is None else binding(closest.optimized.violations)
    why = describe(worst) if worst is not None else "no feasible pose"
    return one_line(f"{why} (closest of {len(runs)} optimizer starts)")


def _run_starts(
    am: AssemblerModel,
    goal: pin.SE3,
    init: InitialConditionResult,
    opts: OptimizeOptions,
    starts: str,
    scene: Scene | None = None,
) -> dict[str, OptimizeResult]:
    """The optimizer's runs, lazily with ``starts="first"``: the helper arm's start; when it
    succeeds, the screw start too only when :func:`needs_other_starts` says so; when it
    fails, every start of :data:`STARTS`. With ``"all"`` every start. Then the fallback
    starts when no run reached an optimum, and the lean starts when no run met every
    constraint (until one does) or the helper arm's optimum is compressed (all of them)."""
    helper_plates = init.plates_if_valid()
    runs: dict[str, OptimizeResult] = {}
    cheap = optimizer_starts(am, goal, None)
    order = list(cheap)
    if helper_plates is not None:
        runs["helper_arm"] = optimize_internal_poses(am, helper_plates, goal, opts, scene=scene)
        if starts == "first" and runs["helper_arm"].optimal:
            order = ["screw"] if needs_other_starts(am, runs["helper_arm"], opts) else []
    for name in order:
        runs[name] = optimize_internal_poses(am, cheap[name], goal, opts, scene=scene)
    if not any(r.optimal for r in runs.values()):
        around = init.state.plates if init.success else cheap["screw"]
        for name, start in _fallback_starts(am, goal, around):
            runs[name] = optimize_internal_poses(am, start, goal, opts, scene=scene)
            if runs[name].optimal:
                break
    # the lean starts: every one when the helper arm's optimum is compressed (it asked for the
    # screw start: several local optima lie around it, and which start reaches the best one
    # must not depend on a run that SLSQP finishes on some BLAS kernels and not on others);
    # else until one meets every constraint, when no run has
    compressed = order == ["screw"] and "helper_arm" in runs
    if compressed or not any(r.optimized.feasible for r in runs.values()):
        for name, start in _lean_starts(am, goal):
            runs[name] = optimize_internal_poses(am, start, goal, opts, scene=scene)
            if not compressed and runs[name].optimized.feasible:
                break
    return runs


#: A leg within this much [m or cos] of the optimizer's own margin counts as at its limit: a
#: tenth of a millimetre, so that a leg SLSQP left 1e-6 off its limit on one BLAS kernel and
#: on it on another is counted alike.
AT_LIMIT = 1e-4

#: The share of the legs at their minimum stroke from which the helper arm's optimum calls
#: for the screw start (:func:`needs_other_starts`): 5 of the 24 legs of the default stack.
COMPRESSED_SHARE = 0.2


def needs_other_starts(am: AssemblerModel, run: OptimizeResult, opts: OptimizeOptions) -> bool:
    """Whether the helper arm's optimum calls for the screw start: it failed, or at least
    :data:`COMPRESSED_SHARE` of the legs are at their minimum stroke.

    A stack that many legs hold at their shortest is compressed against its stroke: the valid
    poses around the optimum are a thin set cut by many active limits, and starts on both
    sides of it end in different local optima. Measured with every start (``starts="all"``)
    on the default stack: each goal where the screw start gave a better optimum had 7-16 legs
    at the minimum stroke (8 of the bench's 120 grid goals, 3 of 90 goals of a shifted grid),
    and no random goal did (0 of 140, at most 4 legs at the minimum stroke). An optimum with
    fewer legs at their minimum is kept alone; ``starts="all"`` runs every start."""
    if not run.optimal:
        return True
    legs = run.optimized.legs  # the state's own leg state (evaluate_state: leg_state of its plates)
    margins = leg_limit_margins(am.config.leg, legs.lengths, np.cos(legs.deflection), legs.rise, opts.limit_margin)
    at_min_stroke = int(np.count_nonzero(margins[0] <= AT_LIMIT))
    return at_min_stroke >= math.ceil(COMPRESSED_SHARE * margins[0].size)


def optimizer_starts(am: AssemblerModel, goal: pin.SE3, helper_plates: PlateArrays | None) -> dict[str, PlateArrays]:
    """The optimizer's starts (:data:`STARTS`): plate 0 at home, plate n at the goal."""
    home = list(am.home)
    home[am.n] = goal
    starts = {"home": PlateArrays.from_se3(home), "screw": PlateArrays.from_se3(even_screw_pose(am, goal))}
    if helper_plates is not None:
        starts = {"helper_arm": helper_plates, **starts}
    return starts


def _fallback_starts(am: AssemblerModel, goal: pin.SE3, around: PlateArrays) -> Iterator[tuple[str, PlateArrays]]:
    """Valid starts near ``around`` (the helper arm's pose, else the screw pose): its internal
    plates moved by seeded random twists, then repaired onto the leg limits (:func:`_repaired`)."""
    copies = perturbed_plates(around.as_se3(), FALLBACK_STARTS, seed=_seed_of(goal))
    return _repaired(am, "perturbed", copies)


def _lean_starts(am: AssemblerModel, goal: pin.SE3) -> Iterator[tuple[str, PlateArrays]]:
    """The last starts, when no run met every constraint: the lean poses
    (:func:`~assembler_pin.helper_arm.initial.lean_poses`) repaired onto the leg limits
    (:func:`_repaired`). On the default stack they solve the low goals (±0.2, 0.2, 0.5) m,
    which every other start leaves unsolved; on a goal without a valid pose they cost ~0.5 s
    (12 repairs)."""
    return _repaired(am, "lean", lean_poses(am, goal))


def _repaired(am: AssemblerModel, name: str, poses: Iterable[list[pin.SE3]]) -> Iterator[tuple[str, PlateArrays]]:
    """``(name_k, pose k repaired onto the leg limits)`` for each of ``poses`` whose repair
    holds (the others are skipped), lazily: a caller that stops early repairs no more."""
    for k, plates in enumerate(poses):
        repaired, violation = repair_stack(am, plates)
        if violation <= 0.0:
            yield f"{name}_{k}", repaired


def _seed_of(goal: pin.SE3) -> int:
    """A seed of the goal alone, read to 1e-9 (the same goal gives the same fallback starts
    on every machine, whatever the rounding of the poses computed on the way)."""
    rounded = np.round(goal.homogeneous, 9) + 0.0  # + 0.0: -0.0 and 0.0 alike
    return zlib.crc32(rounded.tobytes())


def _best_run(runs: dict[str, OptimizeResult]) -> tuple[str | None, OptimizeResult | None]:
    """The run to answer with: of the proven optima (else of the valid runs) the one with the
    smallest Ω (each run's ``objective_optimized``, :func:`assembler_pin.optimize.objective.objective_value`
    of its Pinocchio-checked state). Optima within :data:`SAME_OPTIMUM` of the smallest count as
    the same, and the first run in the order tried is named.

    A proven optimum wins over a lower valid state where a run stalled: where a run stalls
    depends on the machine's rounding, an optimum does not."""
    valid = [(name, r) for name, r in runs.items() if r.success]
    pool = [(name, r) for name, r in valid if r.optimal] or valid
    if not pool:
        return None, None
    lowest = min(r.objective_optimized for _, r in pool)
    return next((name, r) for name, r in pool if r.objective_optimized <= lowest + SAME_OPTIMUM * max(1.0, abs(lowest)))


#: Two runs whose objectives differ by less than this (relative) reach the same optimum.
SAME_OPTIMUM = 1e-6
