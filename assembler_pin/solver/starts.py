"""The optimizer's start portfolio: which starts, in which order, when to stop, which answer.

The one home of the policy and of the poses it starts from. The starts run in the fixed order
of :data:`STARTS` (the helper arm's valid pose, the even screw pose, the home pose), then,
when no run reached an optimum, the perturbed fallback starts, and, when no run met every
constraint or no second run confirmed a compressed optimum, the lean starts
(:func:`lean_runs`). ``starts="all"`` runs every start of :data:`STARTS`;
``starts="first"`` (the default) runs the first ones of the same order and stops as soon as
the runs so far settle the answer (:func:`settled`), so it never runs a start that ``all``
does not. Which run answers is decided by a tolerance and a fixed rule (:func:`best_run`),
not by the last digits of the objectives.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Iterable, Iterator

import numpy as np
import pinocchio as pin

from ..collision.scene import Scene
from ..constraints import leg_limit_margins
from ..helper_arm import InitialConditionResult, height_range, perturbed_plates, repair_stack
from ..kinematics import PlateArrays, even_screw_pose
from ..model.assembler import AssemblerModel
from ..optimize import OptimizeOptions, OptimizeResult, optimize_internal_poses

__all__ = [
    "AT_LIMIT",
    "COMPRESSED_SHARE",
    "FALLBACK_STARTS",
    "LEAN_DIRECTIONS",
    "LEAN_SHEARS",
    "LEAN_TILTS",
    "SAME_OPTIMUM",
    "STARTS",
    "START_MODES",
    "agreeing",
    "best_run",
    "compressed",
    "fallback_starts",
    "lean_poses",
    "lean_runs",
    "lean_starts",
    "optimizer_starts",
    "run_starts",
    "same_optimum",
    "settled",
]

#: The starts the optimizer runs from, in this order: the helper arm's valid initial
#: condition, the even screw pose (every platform the same relative transform) and the home
#: pose's internal plates. Each converges in a few tens of ms.
STARTS = ("helper_arm", "screw", "home")

#: The values of ``solve(starts=...)``: ``first`` runs the starts of :data:`STARTS` in order
#: and stops once the answer is settled (:func:`settled`); ``all`` runs every one.
START_MODES = ("first", "all")

#: Extra starts tried only when no start of :data:`STARTS` reached an optimum: the helper
#: arm's pose (or the screw pose) with its internal plates perturbed and repaired onto the leg
#: limits (seeded by the goal, so the answer is reproducible).
FALLBACK_STARTS = 4

#: A leg within this much [m] of the optimizer's own margin above its minimum stroke counts
#: as at it: a tenth of a millimetre, so that a leg SLSQP left 1e-6 off its limit on one BLAS
#: kernel and on it on another is counted alike.
AT_LIMIT = 1e-4

#: The share of the legs at their minimum stroke from which a pose is :func:`compressed`:
#: 5 of the 24 legs of the default stack.
COMPRESSED_SHARE = 0.2

#: Two optima whose objectives differ by at most this share of the smaller are the same
#: optimum: the answer names the first of them in the order tried, and they agree
#: (:func:`agreeing`). 1e-4 lies above the spread of one optimum reached from several starts
#: or under several BLAS kernels and below the gaps between distinct local optima measured on
#: the default stack (0.01 % to 10 %).
SAME_OPTIMUM = 1e-4


def optimizer_starts(am: AssemblerModel, goal: pin.SE3, helper_plates: PlateArrays | None) -> dict[str, PlateArrays]:
    """The starts of :data:`STARTS` in order (plate 0 at home, plate n at the goal); the
    helper arm's only when it found a valid pose (``helper_plates``)."""
    home = list(am.home)
    home[am.n] = goal
    starts = {"screw": PlateArrays.from_se3(even_screw_pose(am, goal)), "home": PlateArrays.from_se3(home)}
    return starts if helper_plates is None else {"helper_arm": helper_plates, **starts}


def same_optimum(a: float, b: float) -> bool:
    """Whether two objective values are one optimum (:data:`SAME_OPTIMUM`, relative)."""
    return abs(a - b) <= SAME_OPTIMUM * max(1.0, min(abs(a), abs(b)))


def settled(runs: dict[str, OptimizeResult]) -> bool:
    """Whether the answer of ``runs`` (the runs so far, in order) is settled: two of them
    reached the answer's proven optimum (:func:`best_run`, :func:`agreeing`). ``starts="first"``
    stops the starts of :data:`STARTS` there. A failed or stalled run never settles; two
    disagreeing optima call for the third start.

    The budget is fixed: at most the starts ``"all"`` runs, stopping at the second when it
    agrees with the first. Measured on the default stack with every start run on each goal:
    the screw start found a lower optimum than the helper arm's on 2 of 40 random goals over
    the whole stroke (1.0 %, 1.2 % of Ω) and on 9 of the 120 grid goals (0.5 % to 9.0 %);
    where the two agreed, the home start found a lower one on 2 of the 40 goals of the bench's
    ``default_starts`` row (0.36 %, 0.80 %) and on none of 200 others (40 random goals near
    mid-stroke, 40 over the whole stroke, the grid). That is the price of the budget
    (``starts="all"`` pays the third run on every goal instead); no cheaper sign told those
    goals apart: every optimum measured touched leg limits, as many as where the starts
    agreed, and the starts' own Ω told nothing either."""
    return agreeing(runs, best_run(runs)[1]) >= 2


def compressed(am: AssemblerModel, run: OptimizeResult, opts: OptimizeOptions) -> bool:
    """Whether the run's pose is compressed against the stroke: at least
    :data:`COMPRESSED_SHARE` of the legs within :data:`AT_LIMIT` of their minimum stroke (the
    optimizer's margin above it). There the valid poses are a thin set cut by many active
    limits, and which start reaches the lowest optimum depends on runs that SLSQP finishes
    on some BLAS kernels and not on others."""
    legs = run.optimized.legs  # the state's own leg state (evaluate_state: leg_state of its plates)
    margins = leg_limit_margins(am.config.leg, legs.lengths, np.cos(legs.deflection), legs.rise, opts.limit_margin)
    at_min_stroke = int(np.count_nonzero(margins[0] <= AT_LIMIT))
    return at_min_stroke >= math.ceil(COMPRESSED_SHARE * margins[0].size)


def run_starts(
    am: AssemblerModel,
    goal: pin.SE3,
    init: InitialConditionResult,
    opts: OptimizeOptions,
    starts: str,
    scene: Scene | None = None,
) -> dict[str, OptimizeResult]:
    """The optimizer's runs, in the order tried: the starts of :data:`STARTS` (with
    ``"first"`` until :func:`settled`), then the fallback starts until one reaches an optimum
    when none did, then the lean starts (:func:`lean_runs`). ``"first"`` runs the first runs
    of ``"all"``: where it stops early, the answer is settled and no later stage runs."""
    runs: dict[str, OptimizeResult] = {}
    cheap = optimizer_starts(am, goal, init.plates_if_valid())
    for name, start in cheap.items():
        runs[name] = optimize_internal_poses(am, start, goal, opts, scene=scene)
        if starts == "first" and settled(runs):
            break
    if not any(r.optimal for r in runs.values()):
        around = init.state.plates if init.success else cheap["screw"]
        for name, start in fallback_starts(am, goal, around):
            runs[name] = optimize_internal_poses(am, start, goal, opts, scene=scene)
            if runs[name].optimal:
                break
    lean_runs(am, goal, runs, opts, scene)
    return runs


def lean_runs(
    am: AssemblerModel, goal: pin.SE3, runs: dict[str, OptimizeResult], opts: OptimizeOptions, scene: Scene | None
) -> None:
    """The lean starts' runs, added to ``runs``: when no run met every constraint, until one
    does; when the best optimum is :func:`compressed` and no second run reached it, until one
    does (:func:`settled`; all 12 at most). The second case holds the answer on every BLAS
    kernel: on the goal (-0.3, 0.2, 0.5) m the screw start reaches the lowest optimum
    (73.50 N) on one kernel and fails on another, where the helper arm's optimum (80.79 N) is
    compressed; the lean starts reach 73.50 N on both."""
    best = best_run(runs)[1]
    unsolved = not any(r.optimized.feasible for r in runs.values())
    unconfirmed = best is not None and best.optimal and compressed(am, best, opts) and not settled(runs)
    if not (unsolved or unconfirmed):
        return
    for name, start in lean_starts(am, goal):
        runs[name] = optimize_internal_poses(am, start, goal, opts, scene=scene)
        if (unsolved and runs[name].optimized.feasible) or (unconfirmed and settled(runs)):
            return


def best_run(runs: dict[str, OptimizeResult]) -> tuple[str | None, OptimizeResult | None]:
    """The run to answer with: of the proven optima (else of the valid runs) the first in the
    order tried whose Ω (``objective_optimized``, of its Pinocchio-checked state) is the same
    optimum (:func:`same_optimum`) as the smallest.

    A proven optimum wins over a lower valid state where a run stalled: where a run stalls
    depends on the machine's rounding, an optimum does not."""
    valid = [(name, r) for name, r in runs.items() if r.success]
    pool = [(name, r) for name, r in valid if r.optimal] or valid
    if not pool:
        return None, None
    lowest = min(r.objective_optimized for _, r in pool)
    return next((name, r) for name, r in pool if same_optimum(r.objective_optimized, lowest))


def agreeing(runs: dict[str, OptimizeResult], answer: OptimizeResult | None) -> int:
    """How many runs reached a proven optimum that is the answer's (:func:`same_optimum`)."""
    if answer is None or not answer.optimal:
        return 0
    return sum(r.optimal and same_optimum(r.objective_optimized, answer.objective_optimized) for r in runs.values())


def fallback_starts(am: AssemblerModel, goal: pin.SE3, around: PlateArrays) -> Iterator[tuple[str, PlateArrays]]:
    """Valid starts near ``around`` (the helper arm's pose, else the screw pose): its internal
    plates moved by seeded random twists, then repaired onto the leg limits (:func:`repaired`)."""
    copies = perturbed_plates(around.as_se3(), FALLBACK_STARTS, seed=_seed_of(goal))
    return repaired(am, "perturbed", copies)


def lean_starts(am: AssemblerModel, goal: pin.SE3) -> Iterator[tuple[str, PlateArrays]]:
    """The last starts, when no run met every constraint: the :func:`lean_poses` repaired onto
    the leg limits (:func:`repaired`). On the default stack they solve the low goals
    (±0.2, 0.2, 0.5) m, which every other start leaves unsolved; on a goal without a valid
    pose they cost ~0.5 s (12 repairs)."""
    return repaired(am, "lean", lean_poses(am, goal))


def repaired(am: AssemblerModel, name: str, poses: Iterable[list[pin.SE3]]) -> Iterator[tuple[str, PlateArrays]]:
    """``(name_k, pose k repaired onto the leg limits)`` for each of ``poses`` whose repair
    holds (the others are skipped), lazily: a caller that stops early repairs no more."""
    for k, plates in enumerate(poses):
        pa, violation = repair_stack(am, plates)
        if violation <= 0.0:
            yield f"{name}_{k}", pa


def _seed_of(goal: pin.SE3) -> int:
    """A seed of the goal alone, read to 1e-9 (the same goal gives the same fallback starts
    on every machine, whatever the rounding of the poses computed on the way)."""
    rounded = np.round(goal.homogeneous, 9) + 0.0  # + 0.0: -0.0 and 0.0 alike
    return zlib.crc32(rounded.tobytes())


#: The lean poses of :func:`lean_poses`: tilts of the lower plates [rad] and the shear of the
#: middle platforms in units of a level platform's smallest height, measured on the default
#: stack's valid poses for the low goals (±0.2, 0.2, 0.5) m that no other start reaches.
LEAN_TILTS = (0.65, 0.5)
LEAN_SHEARS = (1.06, 0.8)

#: Lean directions tried per goal: the goal's own horizontal direction and its neighbours
#: 45° to either side.
LEAN_DIRECTIONS = (0.0, np.pi / 4, -np.pi / 4)


def lean_poses(am: AssemblerModel, goal: pin.SE3) -> Iterator[list[pin.SE3]]:
    """Stack poses that lean out past a low goal and back (n ≥ 4; none for shorter stacks):
    platform 0 tilts its top plate by α toward a horizontal direction ê, platforms
    1..n-3 shear their top plates along ê at near their smallest height h, platform n-2
    tilts back to level, and plate n is the goal. A stack too tall for a low goal can stand
    there only so. Tried for ê along the goal's horizontal offset from the base first
    (:data:`LEAN_DIRECTIONS`), each α of :data:`LEAN_TILTS` and shear of :data:`LEAN_SHEARS`;
    the poses are starts for the repair, not valid poses."""
    n = am.n
    if n < 4:
        return
    base = am.home[0]
    h = height_range(am.config)[0]
    offset = base.actInv(goal).translation
    heading = math.atan2(offset[1], offset[0]) if math.hypot(offset[0], offset[1]) > 1e-9 else 0.0
    for turn in LEAN_DIRECTIONS:
        phi = heading + turn
        toward = np.array([math.cos(phi), math.sin(phi), 0.0])
        for alpha in LEAN_TILTS:
            tilt = pin.exp3(alpha * np.array([-toward[1], toward[0], 0.0]))
            for shear in LEAN_SHEARS:
                plates = [base, base * pin.SE3(tilt, np.array([0.0, 0.0, h]))]
                for _ in range(n - 3):
                    plates.append(plates[-1] * pin.SE3(np.eye(3), shear * h * toward + np.array([0.0, 0.0, 0.86 * h])))
                plates.append(plates[-1] * pin.SE3(tilt.T, np.array([0.0, 0.0, 1.06 * h])))
                yield [*plates, goal.copy()]
