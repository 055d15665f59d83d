"""Payload capacity: the heaviest payload the stack can hold at a goal within every limit.

For a fixed pose the actuator forces are affine in the payload mass ``m`` (the payload is a
point mass at a fixed place on the EE plate, and the statics are linear in the loads):
``F(m) = F0 + m·F1``, with ``F0`` the forces without payload and ``F1`` the forces per kg.
Only the force limits depend on ``m`` (the kinematic ones do not), so the capacity of a
pose is the largest ``m`` keeping every ``F0_i + m·F1_i`` within ``[-max_compression,
max_tension]`` — a ratio per leg (:func:`pose_capacity`).

The capacity of a goal is the largest ``m`` for which *some* valid internal pose exists
(:func:`payload_capacity`). It is found by alternating the two: the internal poses are
force-optimized for a mass ``m_k`` (the package's optimizer, on the model with that payload),
and ``m_{k+1}`` is the capacity of that pose; a pose optimized for ``m`` holds at least ``m``,
so the sequence rises until the optimum pose is exactly at its force limit. A mass the
optimizer cannot hold bounds the search from above, and bisection takes over inside the
bracket.
"""

from __future__ import annotations

import copy
import dataclasses
import logging
import math
import time
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..collision.scene import Scene, read_scene
from ..common.labels import leg_label
from ..common.messages import binding, describe, one_line
from ..common.threads import one_blas_thread
from ..config.bounds import check_bound
from ..config.numbers import is_number
from ..exceptions import ArgumentError, OptionsError, PoseError, short_repr
from ..helper_arm import initial_condition
from ..kinematics import PlateArrays, plate_arrays, to_se3
from ..model.assembler import AssemblerModel, checked_model
from ..model.geometry import DIMENSIONS
from ..model.platform import PlatformModel, StackPlan
from ..optimize import optimize_internal_poses
from ..state import evaluate_state
from ..statics.engine import solve_statics
from .pipeline import solve
from .starts import optimizer_starts

__all__ = [
    "GLOBAL_PROBE",
    "KEPT_PAYLOAD_MODELS",
    "CapacityResult",
    "PayloadModels",
    "payload_capacity",
    "pose_capacity",
    "with_payload",
]

GLOBAL_PROBE = 0.01
"""At a fixed point of the iteration, the solver's starts are optimized for this much more
payload (relative); only when none holds it is the capacity final, so it is within this of
what a bisection on the payload with the ordinary solve finds."""

KEPT_PAYLOAD_MODELS = 4
"""How many payload variants :class:`PayloadModels` keeps besides 0 kg and 1 kg."""

logger = logging.getLogger(__name__)


def _payload_inertia(mass: float, offset: float) -> pin.Inertia:
    """The payload's inertia in the EE plate's frame, as the URDF writes it: a box of
    :data:`~assembler_pin.model.geometry.DIMENSIONS` ``payload_size`` and ``mass`` [kg] centred
    ``offset`` [m] above the plate's origin."""
    own = np.full(3, mass * DIMENSIONS.payload_size**2 / 6.0)
    return pin.SE3(np.eye(3), np.array([0.0, 0.0, offset])).act(pin.Inertia(mass, np.zeros(3), np.diag(own)))


def with_payload(am: AssemblerModel, mass: float) -> AssemblerModel:
    """``am`` with a payload of ``mass`` [kg]: a shallow copy sharing the geometry, the index
    maps and the whole-stack ``Data`` (its contents are recomputed by every
    call), with its own configuration, its own copy of the Pinocchio model whose EE plate
    body has the other payload's inertia, and its own last-platform model (the helper arms
    are shared: their cache is keyed on the configuration without its payload). No URDF of the
    whole stack is generated and no ``Data`` of the whole stack is created."""
    cfg = am.config
    payload = dataclasses.replace(cfg.payload, mass=float(mass))
    variant = copy.copy(am)
    variant.config = dataclasses.replace(cfg, payload=payload)
    variant.model = pin.Model(am.model)
    ee_joint = int(am.plate_joint_ids[-1])
    # the dynamic parameters (m, m·c, I) are linear in the payload mass
    params = am.model.inertias[ee_joint].toDynamicParameters()
    params += (payload.mass - cfg.payload.mass) * _payload_inertia(1.0, payload.offset).toDynamicParameters()
    variant.model.inertias[ee_joint] = pin.Inertia.FromDynamicParameters(params)
    # same structure: the whole-stack Data, if one was made for inspection, serves both models
    variant._data = am._data
    variant.platform_models = (am.platform_models[0], PlatformModel(variant.config, payload))
    variant.stack_plan = StackPlan(*variant.platform_models, am.n)
    return variant


class PayloadModels:
    """The stack's model with other payload masses (same geometry).

    The models are cheap variants of the configured one (:func:`with_payload`); the most
    recent :data:`KEPT_PAYLOAD_MODELS` are kept (and the ones without payload and with
    1 kg, used by every capacity), so the memory stays flat however many masses are tried.

    Attributes:
        base: the model as configured.
    """

    def __init__(self, am: AssemblerModel) -> None:
        self.base = am
        self._models: OrderedDict[float, AssemblerModel] = OrderedDict()
        self._fixed: dict[float, AssemblerModel] = {round(float(am.config.payload.mass), 9): am}

    def at(self, mass: float) -> AssemblerModel:
        """The model with a payload of ``mass`` [kg]."""
        key = round(float(mass), 9)
        if key in self._fixed:
            return self._fixed[key]
        if key in (0.0, 1.0):
            self._fixed[key] = with_payload(self.base, key)
            return self._fixed[key]
        if key in self._models:
            self._models.move_to_end(key)
        else:
            self._models[key] = with_payload(self.base, key)
            while len(self._models) > KEPT_PAYLOAD_MODELS:
                self._models.popitem(last=False)
        return self._models[key]

    def __len__(self) -> int:
        return len(self._fixed) + len(self._models)


def force_per_kg(models: PayloadModels, plates: PlateArrays) -> tuple[np.ndarray, np.ndarray]:
    """(F0, F1): actuator forces without payload and per kg of payload at these plates [N, N/kg]."""
    f0 = solve_statics(models.at(0.0), plates).forces
    f1 = solve_statics(models.at(1.0), plates).forces - f0
    return f0, f1


def pose_capacity(models: PayloadModels, plates: PlateArrays) -> tuple[float, tuple[int, int] | None, str]:
    """Largest payload [kg] these plates hold within the force limits, the leg that binds
    (None when nothing does) and its limit (``tension``/``compression``); -1 when even no
    payload is within the limits.

    Args:
        plates: world poses of plates 0..n (kinematic limits are not checked here).
    """
    leg = models.base.config.leg
    f0, f1 = force_per_kg(models, plates)
    if np.any(f0 > leg.max_tension) or np.any(f0 < -leg.max_compression):
        return -1.0, None, "over the limit without payload"
    with np.errstate(divide="ignore", invalid="ignore"):
        room = np.where(f1 > 0, (leg.max_tension - f0) / f1, np.where(f1 < 0, (leg.max_compression + f0) / -f1, np.inf))
    k = int(np.argmin(room))
    j, i = divmod(k, 6)
    if not np.isfinite(room.flat[k]):
        return math.inf, None, ""
    return float(room.flat[k]), (j, i), "tension" if f1.flat[k] > 0 else "compression"


@dataclass
class CapacityResult:
    """The payload capacity of a goal (:func:`payload_capacity`).

    Attributes:
        success: a capacity was found (some valid pose holds the goal).
        capacity_kg: the largest payload held [kg], certified by ``plates`` (nan when no
            valid pose holds the goal even without payload).
        binding: the leg at its force limit at capacity, as ``"SPj leg i tension"``.
        plates: the internal poses that hold it (world), None without.
        message: what happened.
        iterations: optimizations run.
        history: (mass optimized for [kg], capacity of the pose found [kg]) per optimization.
        time_s: wall time [s].
    """

    success: bool
    capacity_kg: float
    binding: str
    plates: PlateArrays | None
    message: str
    iterations: int
    history: list[tuple[float, float]] = field(default_factory=list)
    time_s: float = 0.0

    def to_dict(self) -> dict:
        return {
            "success": self.success,
            "capacity_kg": self.capacity_kg,
            "binding": self.binding,
            "message": self.message,
            "iterations": self.iterations,
            "history": self.history,
            "time_s": self.time_s,
        }

    def __repr__(self) -> str:
        return (
            f"CapacityResult(success={self.success}, capacity {self.capacity_kg:.3f} kg, binding "
            f"{self.binding or '-'}, {self.iterations} optimizations, {self.time_s:.2f} s, "
            f"message={self.message!r})"
        )


def _probe(model: AssemblerModel, goal: pin.SE3, arm: PlateArrays | None, scene: Scene | None) -> PlateArrays | None:
    """A valid pose holding ``model``'s payload from the solver's starts (or None)."""
    for start in optimizer_starts(model, goal, arm).values():
        result = optimize_internal_poses(model, start, goal, scene=scene)
        if result.success:
            return result.optimized.plates
    return None


@one_blas_thread
def payload_capacity(
    am: AssemblerModel,
    goal: pin.SE3 | np.ndarray,
    models: PayloadModels | None = None,
    rtol: float = 1e-3,
    max_iterations: int = 12,
    start: PlateArrays | None = None,
    configured_failed: bool = False,
    arm_start: PlateArrays | None = None,
    scene: Scene | str | None = None,
) -> CapacityResult:
    """The heaviest payload [kg] some valid internal pose holds at ``goal``.

    A valid pose for the goal is found at the configured payload (or without payload when
    that fails); its capacity ``c`` is certified by the pose itself. The internal poses are
    then optimized again for a payload of ``c`` from that pose (which holds ``c``, so the
    start is feasible): the new optimum holds ``c' >= c``. This repeats until ``c'`` gains
    less than ``rtol`` — the pose optimized for ``c`` is at its force limit. The optimizer
    may stop in a local optimum there, so the solver's starts (the helper arm's pose, the home
    pose, the even screw pose) are then optimized for :data:`GLOBAL_PROBE` more payload; the
    iteration goes on from the first that holds it.

    Args:
        goal: EE goal pose in the world.
        models: the payload models to reuse (maps keep one per worker).
        rtol: relative gain at which the iteration stops.
        start: a valid pose for the goal at the configured payload, if the caller has one.
        configured_failed: the caller's solve at the configured payload failed (start from
            the solve without payload).
        arm_start: the helper arm's valid pose for the goal, if the caller has it (a start
            only: it need not be clear of the stack's own bodies or of the scene).
        scene: obstacles and floor (:class:`~assembler_pin.collision.scene.Scene` or a scene
            file): every optimization keeps its clearance from them, and ``start`` must too.
    """
    am = checked_model(am)
    if not (is_number(rtol) and 0 < rtol < 0.5):
        raise OptionsError(f"rtol must be a number in (0, 0.5), got {short_repr(rtol)}")
    check_bound("capacity.max_iterations", max_iterations, "max_iterations", OptionsError)
    if models is not None and not isinstance(models, PayloadModels):
        raise ArgumentError(f"models must be PayloadModels(am) (or None), got {type(models).__name__}")
    t0 = time.perf_counter()
    goal = to_se3(goal, "goal")
    scene = read_scene(scene)
    start = _checked_start(am, goal, start, "start", forces=not configured_failed, scene=scene)
    arm_start = _checked_start(am, goal, arm_start, "arm_start", forces=False, clear=False)
    models = models or PayloadModels(am)
    plates, why = _valid_start(am, goal, models, start, configured_failed, scene)
    if plates is None:
        message = one_line(f"no valid pose for the goal even without payload: {why or 'none given'}")
        return CapacityResult(False, math.nan, "", None, message, 1, [], time.perf_counter() - t0)
    climb = _Climb(models, goal, plates, _ArmStart(am, goal, arm_start), float(am.config.payload.mass), scene)
    message = climb.run(rtol, max_iterations)
    label = f"{leg_label(*climb.binding)} {climb.kind}" if climb.binding is not None else ""
    answer = CapacityResult(
        True,
        max(climb.cap, 0.0),
        label,
        climb.plates,
        message,
        climb.iterations,
        climb.history,
        time.perf_counter() - t0,
    )
    logger.info("capacity: %s", answer)
    return answer


#: The kinds of violation a kinematically valid pose may have (its forces at a payload).
_FORCE_KINDS = frozenset({"tension", "compression", "non_finite_force"})


def _checked_start(
    am: AssemblerModel,
    goal: pin.SE3,
    start: PlateArrays | None,
    what: str,
    forces: bool,
    scene: Scene | None = None,
    clear: bool = True,
) -> PlateArrays | None:
    """``start`` as plates when it is a valid pose at ``goal`` (every limit, or every limit but
    the forces when not ``forces``, and but the clearance when not ``clear``: the helper arm's
    pose is a start only, which the optimizer's clearance rows move clear; its clearance
    measured with ``scene``); None stays None.

    Raises:
        PoseError: malformed plates, or a pose off the goal or beyond a limit (naming the first).
    """
    if start is None:
        return None
    pa = plate_arrays(am, start)
    state = evaluate_state(am, pa, goal=goal, scene=scene)
    ignored = (frozenset() if forces else _FORCE_KINDS) | (frozenset() if clear else {"collision"})
    bad = [v for v in state.violations if v.kind not in ignored]
    if bad:
        raise PoseError(one_line(f"{what} is not a valid pose at the goal: {describe(binding(bad))}"))
    return pa


def _valid_start(
    am: AssemblerModel,
    goal: pin.SE3,
    models: PayloadModels,
    start: PlateArrays | None,
    configured_failed: bool,
    scene: Scene | None,
) -> tuple[PlateArrays | None, str]:
    """A valid pose for the goal: ``start``, else the solve at the configured payload (unless
    it is known to fail), else the solve without payload; None when none exists. With it, the
    last solve's message ("" when none ran)."""
    why: list[str] = []

    def solved(mass: float) -> PlateArrays | None:
        result = solve(models.at(mass), goal, scene=scene)
        why.append(result.message)
        return result.optimized.plates if result.success and result.optimized is not None else None

    plates = start if start is not None or configured_failed else solved(float(am.config.payload.mass))
    if plates is None and am.config.payload.mass > 0:
        plates = solved(0.0)
    return plates, why[-1] if why else ""


class _ArmStart:
    """The helper arm's valid pose for the goal (kinematic: the same for every payload),
    computed on first use."""

    def __init__(self, am: AssemblerModel, goal: pin.SE3, known: PlateArrays | None) -> None:
        self.am, self.goal = am, goal
        self._plates: list[PlateArrays | None] = [] if known is None else [known]

    def plates(self) -> PlateArrays | None:
        if not self._plates:
            self._plates.append(initial_condition(self.am, self.goal).plates_if_valid())
        return self._plates[0]


class _Climb:
    """The alternation of :func:`payload_capacity`: optimize for the current capacity, take
    the new pose's capacity; at a fixed point, probe the solver's starts for
    :data:`GLOBAL_PROBE` more."""

    def __init__(
        self,
        models: PayloadModels,
        goal: pin.SE3,
        plates: PlateArrays,
        arm: _ArmStart,
        mass: float,
        scene: Scene | None = None,
    ) -> None:
        self.models, self.goal, self.arm, self.scene = models, goal, arm, scene
        self.iterations = 1
        self.take(plates)
        self.history = [(mass, self.cap)]

    def take(self, plates: PlateArrays) -> None:
        """Move to ``plates`` and its capacity."""
        self.plates = plates
        self.cap, self.binding, self.kind = pose_capacity(self.models, plates)

    def run(self, rtol: float, max_iterations: int) -> str:
        """Climb until the gain is below ``rtol`` and no start holds more; the message."""
        while self.iterations < max_iterations and np.isfinite(self.cap) and self.cap >= 0:
            cap = self.cap
            result = optimize_internal_poses(self.models.at(cap), self.plates, self.goal, scene=self.scene)
            self.iterations += 1
            new_cap = pose_capacity(self.models, result.optimized.plates)[0] if result.success else -1.0
            self.history.append((cap, new_cap))
            if new_cap > cap * (1 + rtol):
                self.take(result.optimized.plates)
                continue
            if result.success and new_cap > cap:
                self.take(result.optimized.plates)
            if not self.probe():
                return f"converged; no start holds {self.cap * (1 + GLOBAL_PROBE):.3f} kg"
        if self.iterations >= max_iterations:
            return f"stopped after {max_iterations} optimizations (still gaining)"
        return "converged"

    def probe(self) -> bool:
        """A local fixed point: do the solver's starts (helper arm, home, screw) hold
        :data:`GLOBAL_PROBE` more? Moves to the first that does."""
        probe = self.cap * (1 + GLOBAL_PROBE)
        found = _probe(self.models.at(probe), self.goal, self.arm.plates(), self.scene)
        self.iterations += 1
        self.history.append((probe, pose_capacity(self.models, found)[0] if found is not None else -1.0))
        if found is None:
            return False
        self.take(found)
        return True
