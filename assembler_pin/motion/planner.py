"""Force-optimal motion along an EE path: every sample a valid, force-optimized internal
pose, each warm-started from the previous one and kept close to it.

For each sample the optimizer (:func:`~assembler_pin.optimize.optimize_internal_poses`)
starts from the previous optimum with its EE plate moved to the new goal (when that run
fails, again with the EE's move spread over the stack, :func:`_spread`), with a
:class:`~assembler_pin.optimize.MotionTerm`: no leg moves more than ``max_leg_step`` from
the previous sample (so the plan cannot jump to another assembly mode or local minimum),
and, with ``w3 > 0``, the paper's minimum-movement term ``w3·Σ ΔL²`` in the objective.
Between two samples the leg lengths are interpolated and the stack checked there
(``checks_between`` points: stack FK of the lengths, every limit, the EE within
``path_tolerance`` of the path). A step that fails any of this is halved, up to
``max_refinements`` times; a sample that still cannot be made valid ends the plan with the
reason and the valid prefix — never a gap.

With a scene (``plan_path(..., scene=...)``) every sample keeps its clearance (the optimizer's
clearance rows) and so does the motion between samples: between two checked poses each pair
of bodies stays at least ``(d_A + d_B − m_a − m_b) / 2`` apart
(:func:`~assembler_pin.collision.sweep.swept_bound`, ``m`` each body's move), and where the
smallest of these is below the clearance the interval is bisected (stack FK of the midpoint
lengths) up to :data:`SWEEP_DEPTH` times; an interval still not proven clear is a
``collision`` between samples.
"""

from __future__ import annotations

import dataclasses
import itertools
import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..collision.scene import Scene, read_scene
from ..collision.sweep import body_moves, swept_bound
from ..common.messages import binding, describe, one_line
from ..common.progress import ProgressCallback, checked_progress
from ..config.bounds import BOUNDS
from ..config.numbers import finite_float
from ..config.options import GEOMETRIC_MARGIN, SMOOTH_METHODS, GoalTolerance, checked_options
from ..constraints import leg_limit_margins
from ..exceptions import OptionsError, PathError, short_repr
from ..kinematics import PlateArrays, plate_arrays, stack_forward_kinematics
from ..model.assembler import AssemblerModel
from ..optimize import MotionTerm, OptimizeOptions, OptimizeResult, optimize_internal_poses
from ..solver.pipeline import solve
from ..state import StackState, evaluate_state
from .guess import on_se3
from .paths import EEPath

__all__ = ["PlanOptions", "PlanResult", "plan_path"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class PlanOptions:
    """Settings of :func:`plan_path`.

    Attributes:
        position_step, rotation_step: largest EE move between samples [m], [rad].
        max_leg_step: largest change of any leg length between samples [m]. The defaults
            (5 mm, 1°, 5 mm) are steps whose samples interpolate within every limit on the
            paths of the docs, so that the first plan is the one kept (steps twice as long
            failed the checks between samples and were planned again).
        w3: weight of the motion term Σ ΔL² [1/m²] (0: force only); it also keeps the
            legs that do not set max|F| from wandering between samples.
        max_refinements: how many times a failing step may be halved.
        checks_between: interpolated checks between two samples.
        path_tolerance: how far the EE may leave the path between samples.
        limit_margin: how far inside the stroke [m] and deflection limit [rad] the samples
            stay, so that the interpolated legs between them stay inside too.
        optimize: the optimizer's settings (a smooth method: slsqp, ipopt or auto; its
            ``limit_margin`` is replaced).
    """

    position_step: float = 0.005
    rotation_step: float = math.radians(1.0)
    max_leg_step: float = 0.005
    w3: float = 100.0
    max_refinements: int = 4
    checks_between: int = 3
    path_tolerance: GoalTolerance = field(default_factory=lambda: GoalTolerance(2e-3, math.radians(0.5)))
    limit_margin: float = 2e-3
    optimize: OptimizeOptions = field(default_factory=OptimizeOptions)

    def __post_init__(self) -> None:
        for name in ("position_step", "rotation_step", "max_leg_step", "limit_margin"):
            value = getattr(self, name)
            if not ((finite_float(value) or 0.0) > 0):
                raise OptionsError(f"{name} must be a finite number > 0, got {short_repr(value, 40)}")
        if not (finite_float(self.w3) is not None and self.w3 >= 0):
            raise OptionsError(f"w3 must be a finite number >= 0 [1/m^2], got {short_repr(self.w3, 40)}")
        for name in ("max_refinements", "checks_between"):
            value = getattr(self, name)
            if not (isinstance(value, int) and 0 <= value <= 20):
                raise OptionsError(f"{name} must be an integer in [0, 20], got {short_repr(value, 40)}")
        if self.optimize.method not in SMOOTH_METHODS:
            raise OptionsError(f"motion planning needs a smooth optimizer method ({', '.join(SMOOTH_METHODS)})")
        object.__setattr__(self, "optimize", dataclasses.replace(self.optimize, limit_margin=self.limit_margin))


@dataclass
class PlanResult:
    """A planned motion: valid samples along the path (the whole path when successful).

    Attributes:
        success: every sample to the end of the path is valid and continuous.
        reason: why the plan stopped, or "reached the end of the path".
        path: the EE path.
        parameters: (m,) path parameter of each sample (0 … path.segments).
        states: the m valid, force-optimized states (the valid prefix when it failed).
        solve_times_s: (m,) optimization time of each sample [s] (0 for the start).
        refinements: number of halved steps.
        max_between_deviation: largest EE distance from the path at the checks between
            samples [m] and angle [rad].
        time_s: wall time of the plan [s].
        path_tolerance: how far the EE may leave the path between samples.
    """

    success: bool
    reason: str
    path: EEPath
    parameters: np.ndarray
    states: list[StackState]
    solve_times_s: np.ndarray
    refinements: int
    max_between_deviation: tuple[float, float]
    time_s: float
    path_tolerance: GoalTolerance = field(default_factory=lambda: GoalTolerance(2e-3, math.radians(0.5)))

    @property
    def lengths(self) -> np.ndarray:
        """(m, n, 6) leg lengths of the samples [m]."""
        return np.array([s.leg_lengths for s in self.states])

    @property
    def max_abs_forces(self) -> np.ndarray:
        """(m,) max|F| of each sample [N]."""
        return np.array([s.max_abs_force for s in self.states])

    def __repr__(self) -> str:
        peak = f"{self.max_abs_forces.max():.2f} N" if self.states else "-"
        return (
            f"PlanResult(success={self.success}, {len(self.states)} samples to u = "
            f"{self.parameters[-1] if len(self.parameters) else 0:.3f}/{self.path.segments}, peak max|F| {peak}, "
            f"{self.refinements} refinements, {self.time_s:.2f} s, reason={self.reason!r})"
        )


def _with_ee(plates: PlateArrays, goal: pin.SE3) -> PlateArrays:
    """The previous sample's plates with the EE plate at the new goal (the first start)."""
    R, p = plates.R.copy(), plates.p.copy()
    R[-1], p[-1] = goal.rotation, goal.translation
    return PlateArrays(R, p)


def _spread(plates: PlateArrays, goal: pin.SE3) -> PlateArrays:
    """The previous sample's plates with the EE's move spread over the stack (the second
    start): plate k moved by ``exp6(k/n · log6(T_goal · T_ee⁻¹))`` (world frame), so each
    platform takes a share of the move instead of the top one all of it."""
    n = len(plates) - 1
    move = pin.log6(goal * plates.se3(n).inverse())
    moved = [plates.se3(0)] + [pin.exp6(move * (k / n)) * plates.se3(k) for k in range(1, n)] + [goal]
    return PlateArrays.from_se3(moved)


#: How many times an interval between two checked poses is bisected to prove it clear.
SWEEP_DEPTH = 4


def _swept_problem(am: AssemblerModel, a: StackState, b: StackState, scene: Scene, depth: int = 0) -> str:
    """ "" when the motion from ``a`` to ``b`` (linear leg lengths) keeps the clearance by
    :func:`~assembler_pin.collision.sweep.swept_bound`, bisecting where it does not; else why."""
    if a.clearance is None or b.clearance is None:
        return ""
    limit = a.clearance.limit
    bound = swept_bound(a.clearance, b.clearance, body_moves(am, a.plates, b.plates))
    if bound >= limit:
        return ""
    if depth >= SWEEP_DEPTH:
        return one_line(
            f"collision: the clearance between samples is not proven: bound {bound:.4g} m, clearance {limit:g} m"
        )
    lengths = 0.5 * (a.leg_lengths + b.leg_lengths)
    fk = stack_forward_kinematics(am, lengths, base=a.plates.se3(0), guess=on_se3(a.plates))
    if not fk.success:
        return f"{fk.message}, between samples"
    mid = evaluate_state(am, fk.plates, scene=scene)
    if mid.clearance is not None and not mid.clearance.clear:
        return f"{describe(binding([v for v in mid.violations if v.kind == 'collision']))}, between samples"
    return _swept_problem(am, a, mid, scene, depth + 1) or _swept_problem(am, mid, b, scene, depth + 1)


def _between_problems(
    am: AssemblerModel,
    path: EEPath,
    u0: float,
    u1: float,
    a: StackState,
    b: StackState,
    opts: PlanOptions,
    scene: Scene | None = None,
) -> tuple[str, float, float]:
    """Checks at the interpolated leg lengths strictly between two samples: the first
    problem found ("" when none), and the largest EE deviation from the path [m], [rad].
    With a scene, the clearance is also bounded between the checked poses (:func:`_swept_problem`)."""
    dev_p = dev_r = 0.0
    guess = a.plates
    checked = [a]
    for t in np.arange(1, opts.checks_between + 1) / (opts.checks_between + 1):
        lengths = (1 - t) * a.leg_lengths + t * b.leg_lengths
        fk = stack_forward_kinematics(am, lengths, base=a.plates.se3(0), guess=on_se3(guess))
        if not fk.success:
            return f"{fk.message}, between samples", dev_p, dev_r
        guess = fk.plates
        target = path.at((1 - t) * u0 + t * u1)
        state = evaluate_state(am, fk.plates, goal=target, tolerance=opts.path_tolerance, scene=scene)
        checked.append(state)
        ee = fk.plates.se3(am.n)
        dev_p = max(dev_p, float(np.linalg.norm(ee.translation - target.translation)))
        dev_r = max(dev_r, float(np.linalg.norm(pin.log3(target.rotation.T @ ee.rotation))))
        if not state.feasible:
            return f"{describe(binding(state.violations))}, between samples", dev_p, dev_r
    if scene is not None:
        checked.append(b)
        for first, second in itertools.pairwise(checked):
            problem = _swept_problem(am, first, second, scene)
            if problem:
                return problem, dev_p, dev_r
    return "", dev_p, dev_r


def _step(
    am: AssemblerModel,
    path: EEPath,
    u0: float,
    u1: float,
    prev: StackState,
    opts: PlanOptions,
    scene: Scene | None = None,
) -> tuple[StackState | None, str, float, tuple[float, float]]:
    """One sample at ``u1`` from the valid sample ``prev`` at ``u0``: (state or None, why
    not, solve time [s], EE deviation between them).

    The optimizer starts from the previous plates with the EE moved (:func:`_with_ee`) and,
    when that run fails, from the move spread over the stack (:func:`_spread`): with the
    whole move on the top platform its legs can be past the motion step at the start, and
    SLSQP's linearization then fails where the spread start converges (a vertical path from
    the home pose to z = 1.6 m stopped 0.06–0.09 m above home; it now ends at the stack's
    full height, z = 1.29 m)."""
    goal = path.at(u1)
    motion = MotionTerm(prev.leg_lengths, opts.max_leg_step, opts.w3)
    result = optimize_internal_poses(am, _with_ee(prev.plates, goal), goal, opts.optimize, motion=motion, scene=scene)
    solve_s = result.time_s
    if not _kept(am, result, opts, scene):
        second = optimize_internal_poses(
            am, _spread(prev.plates, goal), goal, opts.optimize, motion=motion, scene=scene
        )
        solve_s += second.time_s
        if not _kept(am, second, opts, scene):
            return None, _not_kept_reason(am, result, opts, scene), solve_s, (0.0, 0.0)
        result = second
    state = result.optimized
    jump = float(np.abs(state.leg_lengths - prev.leg_lengths).max())
    if jump > opts.max_leg_step * (1 + 1e-9):  # held by the optimizer; checked again here
        why = f"motion step: a leg would move {1e3 * jump:.2f} mm, at most {1e3 * opts.max_leg_step:.3g} mm"
        return None, why, solve_s, (0.0, 0.0)
    problem, dev_p, dev_r = _between_problems(am, path, u0, u1, prev, state, opts, scene)
    if problem:
        return None, problem, solve_s, (dev_p, dev_r)
    return state, "", solve_s, (dev_p, dev_r)


def _not_kept_reason(am: AssemblerModel, result: OptimizeResult, opts: PlanOptions, scene: Scene | None = None) -> str:
    """Why a sample's run gave no sample: its own message, or for a valid state that came
    within the plan's margin of a limit, which leg and which limit, or which two bodies."""
    if not result.success:
        return result.message
    if _clearance_short(result, opts, scene) > GEOMETRIC_MARGIN:
        near = result.optimized.clearance
        assert near is not None
        a, b = near.between
        return (
            f"collision: {a} and {b} would come within the plan's margin ({opts.limit_margin:g} m) "
            f"of the clearance ({near.min_distance:.6g} m apart, clearance {near.limit:g} m)"
        )
    rows = _margin_rows(am, result, opts)
    kind, j, i = np.unravel_index(int(np.argmin(rows)), rows.shape)
    cause = ("leg stroke", "leg stroke", "joint deflection", "joint deflection", "leg stroke")[kind]
    return f"{cause}: SP{j} leg {i} would come within the plan's margin of its limit ({opts.limit_margin:g})"


def _margin_rows(am: AssemblerModel, result: OptimizeResult, opts: PlanOptions) -> np.ndarray:
    """(5, n, 6) margins of the returned state's legs to their limits less the plan's margin."""
    legs = result.optimized.legs
    return leg_limit_margins(am.config.leg, legs.lengths, np.cos(legs.deflection), legs.rise, opts.limit_margin)


def _clearance_short(result: OptimizeResult, opts: PlanOptions, scene: Scene | None) -> float:
    """How far [m] the returned state's clearance falls short of the clearance plus the plan's
    ``limit_margin`` (0 without a scene: the clearance is then checked, not kept)."""
    near = result.optimized.clearance
    if scene is None or near is None:
        return 0.0
    return max(0.0, near.limit + opts.limit_margin - near.min_distance)


def _kept(am: AssemblerModel, result: OptimizeResult, opts: PlanOptions, scene: Scene | None = None) -> bool:
    """Whether a sample's run gives a sample: an optimum, or a valid state whose legs keep the
    plan's ``limit_margin`` inside their limits and, with a scene, whose clearance is that much
    above the clearance (a valid state nearer a limit, such as a stalled run's start, could
    leave it between the samples)."""
    if not result.success:
        return False
    if result.optimal:
        return True
    return bool(np.all(_margin_rows(am, result, opts) >= -GEOMETRIC_MARGIN)) and (
        _clearance_short(result, opts, scene) <= GEOMETRIC_MARGIN
    )


def _start_state(
    am: AssemblerModel,
    path: EEPath,
    start: StackState | PlateArrays | list | None,
    opts: PlanOptions,
    scene: Scene | None = None,
) -> tuple[StackState | None, str]:
    """The valid state the plan starts from, or (None, why not)."""
    first = path.at(0.0)
    if start is None:
        solved = solve(am, first, options=opts.optimize, scene=scene)
        if not solved.success:
            return None, one_line(f"{solved.message}, at the path's start")
        return solved.optimized, ""
    pa = start.plates if isinstance(start, StackState) else plate_arrays(am, start)
    state = evaluate_state(am, pa, goal=first, tolerance=GoalTolerance(1e-6, 1e-6), scene=scene)
    if not state.feasible:
        why = describe(binding(state.violations))
        return None, one_line(f"the start state is not valid at the path's start: {why}")
    return state, ""


def check_plan_work(samples: int, platforms: int) -> None:
    """Refuse a plan whose samples would take too long to optimize (``plan.work``: samples x
    platforms², each sample an optimization whose cost grows with the platform count).

    Raises:
        PathError: naming the samples, the platforms and the limit.
    """
    limit = BOUNDS["plan.work"].high
    work = samples * platforms**2
    if work > limit:
        raise PathError(
            f"the path needs {samples:,} planned samples on {platforms} platforms ({work:,} samples x platforms²), "
            f"over the {limit:,.0f} of one plan (plan.work): shorten the path or use fewer platforms"
        )


def plan_path(
    am: AssemblerModel,
    path: EEPath,
    start: StackState | PlateArrays | list | None = None,
    options: PlanOptions | None = None,
    progress: ProgressCallback | None = None,
    scene: Scene | str | None = None,
) -> PlanResult:
    """Force-optimized internal poses along an EE path (see module docstring).

    Args:
        path: the EE path (:class:`~assembler_pin.motion.paths.EEPath`).
        start: the stack's state at the path's start (e.g. its current pose, or
            ``am.home`` for a motion from the home pose). Default: the force-optimized
            solution of the path's first pose (:func:`~assembler_pin.solver.pipeline.solve`).
        options: see :class:`PlanOptions`.
        progress: called as ``(permille of the path done, 1000, note)`` after each sample.
        scene: obstacles and floor (:class:`~assembler_pin.collision.scene.Scene`, a scene
            file or None): every sample and the motion between samples keep the clearance.
    """
    opts = checked_options(options, PlanOptions, "options")
    progress = checked_progress(progress)
    scene = read_scene(scene)
    t_start = time.perf_counter()
    targets = list(path.parameters(opts.position_step, opts.rotation_step)[1:])  # bounded before planning
    check_plan_work(len(targets) + 1, am.n)
    start_state, why = _start_state(am, path, start, opts, scene)
    if start_state is None:
        march = _March(False, why, [], [], [], 0, (0.0, 0.0))
    else:
        march = _march(am, path, targets, start_state, opts, progress, scene)
    result = PlanResult(
        march.success,
        march.reason,
        path,
        np.array(march.params),
        march.states,
        np.array(march.times),
        march.refinements,
        march.deviation,
        time.perf_counter() - t_start,
        opts.path_tolerance,
    )
    logger.info("plan: %s", result)
    return result


@dataclass
class _March:
    """The samples :func:`_march` placed along the path, and why it stopped."""

    success: bool
    reason: str
    params: list[float]
    states: list[StackState]
    times: list[float]
    refinements: int
    deviation: tuple[float, float]


def _march(
    am: AssemblerModel,
    path: EEPath,
    targets: list[float],
    start_state: StackState,
    opts: PlanOptions,
    progress: ProgressCallback | None,
    scene: Scene | None = None,
) -> _March:
    """Step from ``start_state`` through the path parameters ``targets``, halving a step
    that finds no valid sample up to ``opts.max_refinements`` times."""
    march = _March(True, "reached the end of the path", [0.0], [start_state], [0.0], 0, (0.0, 0.0))
    base_step = 1.0 / max(1, len(targets))
    smallest = base_step * path.segments / 2**opts.max_refinements + 1e-12
    while targets:
        u0, u1 = march.params[-1], targets[0]
        state, why, dt, d = _step(am, path, u0, u1, march.states[-1], opts, scene)
        if state is None:
            if (u1 - u0) <= smallest or opts.max_refinements == 0:
                where = f"no valid sample after u = {u0:.4f} of {path.segments}"
                where += f", step halved {opts.max_refinements} times"
                march.success, march.reason = False, one_line(f"{why} ({where})")
                break
            targets.insert(0, 0.5 * (u0 + u1))
            march.refinements += 1
            continue
        targets.pop(0)
        march.params.append(u1)
        march.states.append(state)
        march.times.append(dt)
        march.deviation = (max(march.deviation[0], d[0]), max(march.deviation[1], d[1]))
        if progress is not None:
            progress(round(1000 * u1 / path.segments), 1000, f"planning: {len(march.states)} samples")
    return march
