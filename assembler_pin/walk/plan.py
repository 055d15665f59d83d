"""The inchworm walk: the stack steps from foothold to foothold, a foot held at every instant.

Footholds are world frames on a surface, their z the surface's outward normal [m, rad]. The
base plate (plate 0) stands on one as its pose; the EE plate (plate n) stands on one turned
over, its +z into the surface: plate n's pose is ``foothold · Ry(π)`` (a foothold's x points
along the step onto it, the way the stack arrives). ``footholds[0]`` is
where the base stands at the start; the feet then land in turn, the EE on ``footholds[1]``,
the base on ``footholds[2]``, the EE on ``footholds[3]`` ... Each step is two phases:

* **reach** (support ``base``: plate 0 held) or **swing** (support ``ee``: plate n held, the
  stack planned on the turned model, :mod:`assembler_pin.supports.turned`): the free foot lifts
  ``clearance`` off its foothold along the surface normal (not at the first step, which starts
  from the home pose), moves to ``clearance`` above the next foothold (the pre-contact pose)
  and lands, every sample a force-optimal valid pose of
  :func:`~assembler_pin.motion.planner.plan_path` (FK of its lengths, every limit, the forces
  of the support held in that phase);
* **transfer** (support ``both``): both feet held at the landed pose, the load moves from the
  old foot to the new: the EE support's wrench ``w`` goes from zero (the base carries all) to
  the whole weight (the EE carries all), or back, in ``transfer_samples`` steps, the forces
  ``F(w)`` set by length offsets ``−F / k`` (:mod:`assembler_pin.supports.choice`); each sample
  within the force limits and the stroke, and the commanded lengths applied through the
  elastic solve (:func:`~assembler_pin.supports.two_point.two_point_statics`) give its forces back. The
  chosen distribution (min max|F|) of the pose is reported with the phase.

Reach and swing samples are rigid poses (commanded = pin-to-pin lengths), like the package's
trajectories; a walk that cannot go on ends with ``success`` false, the reason, and the valid
prefix (the phases done, and the valid samples of the one that failed).

**Among obstacles** (``scene=``): every reach and swing sample keeps its clearance from the
scene's obstacles and floor and from the stack's own bodies, at the samples and between them
(:func:`~assembler_pin.motion.planner.plan_path` with the scene). The feet stand on the
scene's floor (every foothold on it): the held foot's plate, and the moving foot's while it
lifts off or lands (on its foothold's normal, at most ``clearance`` from it), are not checked
against the floor, nor are their legs' ``leg.node_zone`` at them
(:attr:`~assembler_pin.collision.scene.Scene.standing`); every other body is, the moving
foot's plate included from its lift-off height on. The swing is planned on the turned model,
whose bodies are the stack's own (:func:`~assembler_pin.collision.check.clearance`).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..collision.check import Clearance, clearance
from ..collision.scene import Scene, read_scene
from ..common.progress import ProgressCallback, checked_progress
from ..config.bounds import check_bound
from ..config.numbers import finite_float
from ..config.options import checked_options
from ..constraints import Violation
from ..exceptions import WalkError, short_repr
from ..kinematics import PlateArrays, leg_vectors, plate_arrays
from ..model.assembler import AssemblerModel, checked_model
from ..motion.paths import EEPath
from ..motion.planner import PlanOptions, check_plan_work, plan_path
from ..state import StackState
from ..supports.choice import CHECK_TOLERANCE, ChosenDistribution, chosen_distribution, force_bounds, held_equilibrium
from ..supports.turned import turned_model
from ..supports.two_point import two_point_statics
from .footholds import checked_footholds, plate_target
from .path import foot_waypoints, path_pieces
from .verify import verify_walk

__all__ = ["WalkOptions", "WalkPhase", "WalkResult", "plan_walk"]

logger = logging.getLogger(__name__)


def _walk_plan_options() -> PlanOptions:
    return PlanOptions(position_step=0.02, rotation_step=math.radians(4.0), max_leg_step=0.02)


@dataclass(frozen=True)
class WalkOptions:
    """Settings of :func:`plan_walk`.

    Attributes:
        clearance: lift-off and pre-contact height above a foothold, along its normal [m].
        transfer_samples: samples of each load transfer (both feet held), ends included.
        floor_z: the height of a level floor the footholds must lie on (None: any surface);
            with it, no joint centre of any sample may go below it.
        plan: the motion planner's settings for reach and swing.
    """

    clearance: float = 0.03
    transfer_samples: int = 5
    floor_z: float | None = None
    plan: PlanOptions = field(default_factory=_walk_plan_options)

    def __post_init__(self) -> None:
        check_bound("walk.clearance", self.clearance, "clearance", error=WalkError)
        check_bound("walk.transfer_samples", self.transfer_samples, "transfer_samples", error=WalkError)
        if self.floor_z is not None and finite_float(self.floor_z) is None:
            raise WalkError(f"floor_z must be a finite number [m] or None, got {short_repr(self.floor_z, 40)}")
        if not isinstance(self.plan, PlanOptions):
            raise WalkError(f"plan must be a PlanOptions, got {type(self.plan).__name__}")


@dataclass(frozen=True)
class WalkPhase:
    """One phase of a walk (module doc); every per-sample array is in the original model's
    plate and leg order, world frame.

    Attributes:
        kind: ``reach``, ``transfer`` or ``swing``; support: ``base``, ``both`` or ``ee``.
        step: the foothold the phase's moving foot goes to (a transfer: the one it landed on).
        plates: the samples' plate poses; lengths: (m, n, 6) pin-to-pin lengths [m];
        commanded: (m, n, 6) the lengths to command [m]; forces: (m, n, 6) leg forces [N],
            tension positive, with the phase's support.
        complete: the phase reached its end; reason: why not ("" when complete).
        chosen: a transfer's chosen distribution (min max|F|) at its pose, else None.
        clearance: the smallest clearance of its samples (the stack's own bodies, and the
            scene's with one), None without a sample.
    """

    kind: str
    support: str
    step: int
    plates: list[PlateArrays]
    lengths: np.ndarray
    commanded: np.ndarray
    forces: np.ndarray
    complete: bool
    reason: str = ""
    chosen: ChosenDistribution | None = None
    clearance: Clearance | None = None

    @property
    def max_abs_forces(self) -> np.ndarray:
        """(m,) max|F| of each sample [N]."""
        return np.abs(self.forces).reshape(len(self.forces), -1).max(axis=1) if len(self.forces) else np.zeros(0)

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "support": self.support,
            "step": self.step,
            "complete": self.complete,
            "reason": self.reason,
            "samples": len(self.plates),
            "max_abs_force": float(self.max_abs_forces.max()) if len(self.plates) else None,
            "max_abs_forces": self.max_abs_forces.tolist(),
            "chosen": None if self.chosen is None else self.chosen.to_dict(),
            "clearance": None if self.clearance is None else self.clearance.to_dict(),
        }


@dataclass(frozen=True)
class WalkResult:
    """A planned walk (:func:`plan_walk`).

    Attributes:
        success: every phase to the last foothold is complete and valid.
        reason: "reached the last foothold" or why the walk stops.
        footholds: the footholds (world frames).
        phases: the phases planned, in order (the valid prefix when it failed: the last one
            may be incomplete).
        scene: the obstacles and floor the walk was planned among (None: none).
        lift: the lift-off and pre-contact height it was planned with [m].
    """

    success: bool
    reason: str
    footholds: tuple[pin.SE3, ...]
    phases: list[WalkPhase]
    scene: Scene | None = None
    lift: float = 0.0

    @property
    def max_abs_force(self) -> float:
        """max |F| over every sample of the walk [N] (NaN with no sample)."""
        peaks = [p.max_abs_forces.max() for p in self.phases if len(p.plates)]
        return float(max(peaks)) if peaks else math.nan

    def __repr__(self) -> str:
        kinds = "/".join(p.kind for p in self.phases)
        return f"WalkResult(success={self.success}, {len(self.phases)} phases ({kinds}), reason={self.reason!r})"

    def to_dict(self) -> dict:
        return {
            "success": self.success,
            "reason": self.reason,
            "footholds": [f.homogeneous.tolist() for f in self.footholds],
            "max_abs_force": None if math.isnan(self.max_abs_force) else self.max_abs_force,
            "phases": [p.to_dict() for p in self.phases],
            "units": "N (tension positive), m; plates world frame",
        }


def _other(foot: str) -> str:
    return "ee" if foot == "base" else "base"


def _start_plates(am: AssemblerModel, base: pin.SE3, start: PlateArrays | list | None) -> PlateArrays:
    """The physical plates at the start: ``start``, or the home pose standing on ``base``."""
    if start is None:
        return PlateArrays.from_se3([base * p for p in am.home])
    pa = plate_arrays(am, start)
    gap = float(np.linalg.norm(pin.log6(base.actInv(pa.se3(0))).vector))
    if gap > 1e-6:
        raise WalkError(f"the start pose's plate 0 is {gap:.3g} (m, rad) from footholds[0]; it must stand on it")
    return pa


def _out_of_reach(am: AssemblerModel, held: pin.SE3, target: pin.SE3) -> str:
    """Why no pose puts the moving plate on ``target`` ("" when that is not excluded): a platform
    moves its top plate's centre at most ``max_length + 2 node_radius`` from its bottom's."""
    reach = am.n * (am.config.leg.max_length + 2.0 * am.config.plate.node_radius)
    d = float(np.linalg.norm(target.translation - held.translation))
    return f"out of reach: {d:.4g} m from the held foot, the stack reaches at most {reach:.4g} m" if d > reach else ""


def _below_floor(am: AssemblerModel, pa: PlateArrays, floor_z: float | None) -> str:
    if floor_z is None:
        return ""
    bottom, top = leg_vectors(am, pa)[:2]
    low = float(min(bottom[..., 2].min(), top[..., 2].min()))
    return f"a joint centre goes {1e3 * (floor_z - low):.3g} mm below the floor" if low < floor_z - 1e-6 else ""


def _move_phase(
    am: AssemblerModel,
    cur: PlateArrays,
    stance: str,
    step: int,
    foothold: pin.SE3,
    lift: bool,
    opts: WalkOptions,
    scene: Scene | None = None,
) -> WalkPhase:
    """Reach (base held, the EE moves) or swing (EE held, the base moves, on the turned model)
    from the physical pose ``cur`` to the foothold ``step``, among ``scene``'s bodies."""
    tm = turned_model(am)
    turned = stance == "ee"
    model = tm.model if turned else am
    start = tm.plates(cur) if turned else cur
    target = plate_target(foothold, "base") * tm.flip if turned else plate_target(foothold, "ee")
    kind = "swing" if turned else "reach"
    far = _out_of_reach(am, start.se3(0), target)
    if far:
        empty = np.zeros((0, am.n, 6))
        return WalkPhase(kind, stance, step, [], empty, empty, empty, False, far)
    apex = start.se3(0) * model.home[-1]
    points = foot_waypoints(start.se3(0), apex, start.se3(am.n), target, opts.clearance, lift)
    states: list[StackState] = []
    reason = ""
    begin: StackState | PlateArrays = start
    for piece, where in path_pieces(points, lift, scene, am.n):
        plan = plan_path(model, EEPath(piece, kind="linear"), start=begin, options=opts.plan, scene=where)
        states += plan.states[1:] if states else plan.states
        if not plan.success:
            reason = plan.reason
            break
        begin = plan.states[-1]
    plates: list[PlateArrays] = []
    lengths: list[np.ndarray] = []
    forces: list[np.ndarray] = []
    nearest: Clearance | None = None
    for state in states:
        pa = tm.original_plates(state.plates) if turned else state.plates
        low = _below_floor(am, pa, opts.floor_z)
        if low:
            reason = f"sample {len(plates)}: {low}"
            break
        plates.append(pa)
        lengths.append(tm.original_legs(state.leg_lengths) if turned else state.leg_lengths)
        forces.append(tm.original_legs(state.forces) if turned else state.forces)
        if state.clearance is not None and (nearest is None or state.clearance.min_distance < nearest.min_distance):
            nearest = state.clearance
    L, F = np.array(lengths).reshape(-1, am.n, 6), np.array(forces).reshape(-1, am.n, 6)
    return WalkPhase(kind, stance, step, plates, L, L.copy(), F, not reason, reason, clearance=nearest)


def _transfer_phase(
    am: AssemblerModel, pose: PlateArrays, stance: str, step: int, opts: WalkOptions, scene: Scene | None = None
) -> WalkPhase:
    """Both feet held at ``pose``: the load moves from the ``stance`` foot to the other one."""
    n, k = am.n, float(am.config.leg.stiffness)
    near = clearance(am, pose, None if scene is None else dataclasses.replace(scene, standing=(0, n)))
    if not near.clear:
        why = str(Violation("collision", None, None, near.min_distance, near.limit, near.between))
        return WalkPhase(
            "transfer", "both", step, [], np.zeros((0, n, 6)), np.zeros((0, n, 6)), np.zeros((0, n, 6)), False, why
        )
    eq = held_equilibrium(am, pose, "both")
    if isinstance(eq, str):
        return WalkPhase(
            "transfer", "both", step, [], np.zeros((0, n, 6)), np.zeros((0, n, 6)), np.zeros((0, n, 6)), False, eq
        )
    ends = (np.zeros(6), eq.total) if stance == "base" else (eq.total, np.zeros(6))
    L = leg_vectors(am, pose)[3]
    lo, hi = force_bounds(am, L)
    forces, commanded, reason = [], [], ""
    for i, s in enumerate(np.linspace(0.0, 1.0, opts.transfer_samples)):
        F = eq.particular + eq.null @ ((1.0 - s) * ends[0] + s * ends[1])
        if not np.all((lo <= F) & (F <= hi)):
            reason = f"sample {i}: leg forces beyond the force limits or the stroke ({np.abs(F).max():.4g} N)"
            break
        cmd = L - F / k
        el = two_point_statics(am, pose, cmd)
        error = float(np.abs(el.forces - F).max()) if el.success else math.inf
        if not error <= CHECK_TOLERANCE:
            reason = f"sample {i}: the elastic solve of its lengths does not hold ({el.message}, {error:.3g} N)"
            break
        forces.append(F)
        commanded.append(cmd)
    m = len(forces)
    chosen = chosen_distribution(am, pose)
    return WalkPhase(
        "transfer",
        "both",
        step,
        [pose] * m,
        np.broadcast_to(L, (m, n, 6)).copy(),
        np.array(commanded).reshape(m, n, 6),
        np.array(forces).reshape(m, n, 6),
        not reason,
        reason,
        chosen,
        near if m else None,
    )


def _check_walk_work(am: AssemblerModel, start: PlateArrays, feet: Sequence[pin.SE3], opts: WalkOptions) -> None:
    """Refuse, before planning, a walk one of whose reach or swing phases needs more planned
    samples than ``plan.work`` allows: each moving foot goes at least the straight distance
    from where it stands to its next foothold, at ``opts.plan.position_step`` per sample.

    Raises:
        PathError: naming the phase's samples and the limit.
    """
    step = opts.plan.position_step
    where = [start.se3(0).translation, start.se3(am.n).translation]  # base, EE
    for k in range(1, len(feet)):
        foot = k % 2  # the EE lands on odd footholds, the base on even ones
        distance = float(np.linalg.norm(feet[k].translation - where[foot]))
        check_plan_work(1 + math.ceil(distance / step), am.n)
        where[foot] = feet[k].translation


def _walk_scene(scene: Scene | None, opts: WalkOptions) -> Scene | None:
    """The scene a walk is planned among: ``scene`` with the walk's floor (module doc)."""
    if scene is None:
        return None
    if opts.clearance <= 0.0:
        raise WalkError("with a scene the feet lift off and land along their normals: clearance must be > 0 m")
    if scene.floor_z is None:
        return scene if opts.floor_z is None else dataclasses.replace(scene, floor_z=float(opts.floor_z))
    if opts.floor_z is not None and abs(opts.floor_z - scene.floor_z) > 1e-9:
        raise WalkError(f"the walk's floor z = {opts.floor_z:g} m is not the scene's floor z = {scene.floor_z:g} m")
    return scene


def plan_walk(
    am: AssemblerModel,
    footholds: object,
    start: PlateArrays | list | None = None,
    options: WalkOptions | None = None,
    progress: ProgressCallback | None = None,
    scene: Scene | str | None = None,
) -> WalkResult:
    """The inchworm walk over ``footholds`` (module doc): reach / transfer / swing / transfer ...

    Args:
        footholds: world frames (pin.SE3 or 4×4) [m]: ``footholds[0]`` the base's at the start,
            then the EE's, the base's ... (see :func:`~assembler_pin.walk.footholds.plate_target`).
        start: the physical plates at the start (plate 0 on ``footholds[0]``); default the home
            pose standing on it.
        options: :class:`WalkOptions`.
        progress: called as ``(phases done, phases, note)``.
        scene: obstacles and floor (:class:`~assembler_pin.collision.scene.Scene`, a scene file
            or None): every reach and swing sample, and the motion between samples, keep the
            configuration's ``clearance`` from them (module doc). With a floor in the scene the
            footholds must lie on it; ``options.floor_z``, when given, must be its height, and
            without a floor in the scene it becomes the scene's floor.

    Returns:
        A :class:`WalkResult`; ``success`` false with the reason and the valid prefix when a
        foothold cannot be reached or a load cannot be moved. Every sample is checked again by
        :func:`verify_walk` before success is reported.

    Raises:
        WalkError: malformed or overlapping footholds, off the floor, a start off footholds[0],
            a scene whose floor is not the walk's, or a scene with ``clearance`` 0 (the feet
            must lift off and land along their normals).
        SceneError: a scene file that is not one.
    """
    am = checked_model(am)
    progress = checked_progress(progress)
    opts = checked_options(options, WalkOptions, "options")
    scene = _walk_scene(read_scene(scene), opts)
    floor_z = opts.floor_z if scene is None else scene.floor_z
    feet = checked_footholds(am, footholds, floor_z)
    cur = _start_plates(am, feet[0], start)
    _check_walk_work(am, cur, feet, opts)
    stance, phases, total = "base", [], 2 * (len(feet) - 1)
    for step in range(1, len(feet)):
        moving = _other(stance)
        for make in ("move", "transfer"):
            if make == "move":
                phase = _move_phase(am, cur, stance, step, feet[step], step >= 2, opts, scene)
            else:
                phase = _transfer_phase(am, cur, stance, step, opts, scene)
            phases.append(phase)
            if progress is not None:
                progress(len(phases), total, f"walk: {phase.kind} to foothold {step}")
            if not phase.complete:
                foot = "EE" if stance == "base" else "base"
                what = "the load cannot move to" if make == "transfer" else f"the {foot} foot cannot reach"
                reason = f"step {step}: {what} foothold {step}: {phase.reason}"
                return WalkResult(False, reason, feet, phases, scene, opts.clearance)
            cur = phase.plates[-1]
        stance = moving
    result = WalkResult(True, "reached the last foothold", feet, phases, scene, opts.clearance)
    problems = verify_walk(am, result)
    if problems:
        return dataclasses.replace(result, success=False, reason=f"a sample does not check: {problems[0]}")
    logger.info("walk: %s", result)
    return result
