"""The stack on a carrier arm: a serial robot from example-robot-data holds the base plate.

The carrier is loaded from the URDFs that the ``example-robot-data`` wheel ships (under
``<site-packages>/cmeel.prefix/share/example-robot-data/robots/``), and the stack's base plate
is fixed to its tool frame through a mount transform (tool → base plate). The stack keeps
its own closed-loop model: its plates are given relative to the base plate and placed in
the world through the carrier's forward kinematics, so gravity acts along world −z whatever
way the carrier turns the stack (sideways, upside down).

* :class:`Carrier` — the carrier's Pinocchio model (its own ``Data``, of which it is the only
  writer), the visual model with its meshes, the mount, forward kinematics and a joint-limited
  inverse kinematics of the base plate.
* :func:`carrier_statics` — leg forces of the mounted stack and the carrier's joint torques
  holding the whole still: Pinocchio's ``computeStaticTorque`` with the stack's wrench on the
  tool joint as an external force.
* :func:`solve_on_carrier` — a world goal: the carrier's joints join the search (see its
  docstring), and the result says whether the stack or the carrier binds.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from .bounds import check_bound
from .choices import CARRIER_NAMES, check_names
from .exceptions import AssemblerError, OptionsError, PoseError, UnknownCarrierError
from .kinematics import PlateArrays, plate_arrays, to_se3
from .model import AssemblerModel
from .options import DEFAULT_GOAL_TOLERANCE, GoalTolerance, HelperArmOptions, OptimizeOptions
from .progress import ProgressCallback
from .state import StackState, evaluate_state
from .threads import one_blas_thread

__all__ = [
    "CARRIERS",
    "Carrier",
    "CarrierSolveResult",
    "CarrierSpec",
    "CarrierStatics",
    "UnknownCarrierError",
    "carrier_objective",
    "carrier_statics",
    "carrier_torques",
    "robots_directory",
    "solve_on_carrier",
]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class CarrierSpec:
    """A supported carrier.

    Attributes:
        urdf: path of its URDF under example-robot-data's ``robots`` directory.
        tool_frame: the frame the stack's base plate is mounted on.
        locked: joints held at zero (a gripper's fingers).
        upright_q: a joint configuration with the tool frame's z axis near world +z [rad]
            (the default, so the stack stands upright above the tool).
        description: what it is, and its rated payload where the maker gives one.
    """

    urdf: str
    tool_frame: str
    locked: tuple[str, ...] = ()
    upright_q: tuple[float, ...] = ()
    description: str = ""


CARRIERS: dict[str, CarrierSpec] = {
    "ur3": CarrierSpec(
        "ur_description/urdf/ur3_robot.urdf",
        "tool0",
        (),
        (-0.041, -0.693, 1.127, 1.138, -1.571, 1.612),
        "Universal Robots UR3, 6 joints (rated payload 3 kg)",
    ),
    "ur5": CarrierSpec(
        "ur_description/urdf/ur5_robot.urdf",
        "tool0",
        (),
        (-0.02, -1.127, 1.535, 1.164, -1.571, 1.591),
        "Universal Robots UR5, 6 joints (rated payload 5 kg)",
    ),
    "ur10": CarrierSpec(
        "ur_description/urdf/ur10_robot.urdf",
        "tool0",
        (),
        (-0.023, -1.205, 1.738, 1.038, -1.571, 1.594),
        "Universal Robots UR10, 6 joints (rated payload 10 kg)",
    ),
    "panda": CarrierSpec(
        "panda_description/urdf/panda.urdf",
        "panda_link8",
        ("panda_finger_joint1", "panda_finger_joint2"),
        (-1.003, -0.35, 1.067, -2.689, -2.649, 0.688, 0.356),
        "Franka Emika Panda, 7 joints, fingers locked (rated payload 3 kg)",
    ),
}
"""The supported carriers by name (see :class:`CarrierSpec`)."""
check_names(CARRIERS, CARRIER_NAMES, "carriers")

W_CARRIER = 200.0
"""Weight of the carrier term of Ω_c [N]: a joint at its effort limit costs as much as a leg
at the default force limit."""


@cache
def robots_directory() -> Path:
    """example-robot-data's ``robots`` directory (URDFs and meshes).

    Raises:
        AssemblerError: the package is not installed (``pip install example-robot-data``).
    """
    from importlib import metadata

    try:
        dist = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        raise AssemblerError(
            "carriers need example-robot-data: pip install 'assembler_pin[carrier]' (or example-robot-data)"
        ) from None
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    if not path.is_dir():
        raise AssemblerError(f"example-robot-data is installed but has no robots directory at {path}")
    return path


@dataclass(frozen=True)
class IKResult:
    """Joint-limited inverse kinematics of the base plate (:meth:`Carrier.ik`).

    Attributes:
        q: joint angles [rad] (the last iterate when it failed), within the joint limits.
        success: the base plate reaches the target within ``tolerance``.
        error: norm of the SE(3) log of the remaining error (m and rad mixed).
        iterations: iterations used.
    """

    q: np.ndarray
    success: bool
    error: float
    iterations: int


class Carrier:
    """A serial arm from example-robot-data with the stack's base plate on its tool frame.

    Args:
        name: one of :data:`CARRIERS`.
        mount: pose of the base plate in the tool frame (default identity: the plate's
            centre on the flange, its z axis along the tool's z).

    Attributes:
        name, spec: the carrier and its :class:`CarrierSpec`.
        model, data: its Pinocchio model (fingers locked) and data; this object is the
            only writer of ``data`` (``framesForwardKinematics``, ``computeStaticTorque``,
            ``computeFrameJacobian``).
        visual_model: its visual geometry (meshes from example-robot-data).
        base_frame: id of the frame ``assembler_base`` added at the mount (the base plate).
        effort_limit: (nv,) the URDF's joint effort limits [N·m].
    """

    def __init__(self, name: str, mount: pin.SE3 | npt.ArrayLike | None = None) -> None:
        key = str(name).lower()
        if key not in CARRIERS:
            raise UnknownCarrierError(f"unknown carrier {name!r}; supported: {', '.join(CARRIERS)}")
        self.name, self.spec = key, CARRIERS[key]
        self.mount = pin.SE3.Identity() if mount is None else to_se3(mount, "mount")
        robots = robots_directory()
        urdf = str(robots / self.spec.urdf)
        full = pin.buildModelFromUrdf(urdf)
        visual = pin.buildGeomFromUrdf(full, urdf, pin.GeometryType.VISUAL, package_dirs=[str(robots.parent.parent)])
        locked = [full.getJointId(j) for j in self.spec.locked]
        if locked:
            self.model, self.visual_model = pin.buildReducedModel(full, visual, locked, pin.neutral(full))
        else:
            self.model, self.visual_model = full, visual
        tool = self.model.getFrameId(self.spec.tool_frame)
        frame = self.model.frames[tool]
        self.base_frame = self.model.addFrame(
            pin.Frame("assembler_base", frame.parentJoint, tool, frame.placement * self.mount, pin.FrameType.OP_FRAME)
        )
        self.data = self.model.createData()
        self.effort_limit = np.asarray(self.model.effortLimit, dtype=float).copy()
        self.lower = np.asarray(self.model.lowerPositionLimit, dtype=float).copy()
        self.upper = np.asarray(self.model.upperPositionLimit, dtype=float).copy()

    def __repr__(self) -> str:
        return (
            f"Carrier({self.name!r}, {self.model.nv} joints, tool frame {self.spec.tool_frame!r}, effort limits "
            f"{np.round(self.effort_limit, 1).tolist()} N·m)"
        )

    @property
    def upright_q(self) -> np.ndarray:
        """The spec's upright configuration [rad]."""
        return np.array(self.spec.upright_q, dtype=float)

    def check_q(self, q: npt.ArrayLike, what: str = "carrier q") -> np.ndarray:
        """``q`` as an (nv,) array within the joint limits, or a :class:`PoseError`."""
        raw = np.asarray(q)
        if raw.dtype.kind not in "iuf":  # no strings, booleans or objects
            raise PoseError(f"{what} must be {self.model.nq} joint angles [rad] (numbers), got {raw.dtype} values")
        arr = raw.astype(float).ravel()
        if arr.shape != (self.model.nq,) or not np.all(np.isfinite(arr)):
            raise PoseError(f"{what} must be {self.model.nq} finite joint angles [rad] for {self.name}, got {arr}")
        outside = np.flatnonzero((arr < self.lower - 1e-9) | (arr > self.upper + 1e-9))
        if outside.size:
            k = int(outside[0])
            raise PoseError(
                f"{what}: joint {k} = {arr[k]:.4f} rad is outside [{self.lower[k]:.4f}, {self.upper[k]:.4f}]"
            )
        return arr

    def base_pose(self, q: npt.ArrayLike) -> pin.SE3:
        """World pose of the stack's base plate at joint angles ``q``."""
        pin.framesForwardKinematics(self.model, self.data, self.check_q(q))
        return self.data.oMf[self.base_frame].copy()

    def joint_points(self, q: npt.ArrayLike) -> np.ndarray:
        """(njoints, 3) world positions of the joints and the base frame [m] (for framing a view)."""
        pin.framesForwardKinematics(self.model, self.data, self.check_q(q))
        pts = [self.data.oMi[k].translation for k in range(self.model.njoints)]
        return np.array([*pts, self.data.oMf[self.base_frame].translation])

    def ik(self, target: pin.SE3, q0: npt.ArrayLike, tolerance: float = 1e-9, max_iterations: int = 200) -> IKResult:
        """Joint angles placing the base plate at ``target``, from ``q0``: damped least
        squares on the SE(3) log error (``Jlog6`` of the frame Jacobian), clipped to the
        joint limits at every step."""
        check_bound("carrier.ik_iterations", max_iterations, "max_iterations", OptionsError)
        q = np.clip(self.check_q(q0, "q0"), self.lower, self.upper)
        damping = 1e-6
        err = math.inf
        for it in range(1, max_iterations + 1):
            pin.framesForwardKinematics(self.model, self.data, q)
            current = self.data.oMf[self.base_frame]
            e = pin.log6(current.actInv(target)).vector
            err = float(np.linalg.norm(e))
            if err < tolerance:
                return IKResult(q, True, err, it)
            J = pin.Jlog6(current.actInv(target)) @ pin.computeFrameJacobian(
                self.model, self.data, q, self.base_frame, pin.ReferenceFrame.LOCAL
            )
            dq = J.T @ np.linalg.solve(J @ J.T + damping * np.eye(6), e)
            q = np.clip(pin.integrate(self.model, q, dq), self.lower, self.upper)
        return IKResult(q, False, err, max_iterations)


@dataclass
class CarrierStatics:
    """Statics of the stack on its carrier.

    Attributes:
        state: the stack in the world (plates, leg forces [N] under world gravity, limits).
        q: the carrier's joint angles [rad].
        torques: (nv,) joint torques the carrier's motors hold [N·m].
        torque_ratio: (nv,) |torque| / effort limit.
        stack_ratio: max over legs of |F| / its force limit (tension or compression).
        binding: ``"stack"`` or ``"carrier"``: whichever has the larger ratio.
    """

    state: StackState
    q: np.ndarray
    torques: np.ndarray
    torque_ratio: np.ndarray
    stack_ratio: float

    @property
    def carrier_ratio(self) -> float:
        return float(self.torque_ratio.max())

    @property
    def binding(self) -> str:
        return "carrier" if self.carrier_ratio > self.stack_ratio else "stack"

    @property
    def within_limits(self) -> bool:
        """Every stack constraint holds and no carrier joint exceeds its effort limit."""
        return self.state.feasible and self.carrier_ratio <= 1.0

    def to_dict(self) -> dict:
        return {
            "carrier_q": self.q.tolist(),
            "carrier_torques": self.torques.tolist(),
            "carrier_torque_ratio": self.torque_ratio.tolist(),
            "stack_ratio": self.stack_ratio,
            "carrier_ratio": self.carrier_ratio,
            "binding": self.binding,
            "within_limits": self.within_limits,
        }

    def __repr__(self) -> str:
        return (
            f"CarrierStatics(max|F| {self.state.max_abs_force:.2f} N ({100 * self.stack_ratio:.0f} % of its "
            f"limit), carrier torque up to {100 * self.carrier_ratio:.0f} % of its effort limit, binding "
            f"{self.binding}, within limits: {self.within_limits})"
        )


def _stack_ratio(am: AssemblerModel, state: StackState) -> float:
    leg = am.config.leg
    F = state.forces
    return float(max(F.max() / leg.max_tension, -F.min() / leg.max_compression, 0.0))


def carrier_statics(
    am: AssemblerModel,
    carrier: Carrier,
    q: npt.ArrayLike,
    plates: PlateArrays | list | np.ndarray,
    goal: pin.SE3 | None = None,
    tolerance: GoalTolerance = DEFAULT_GOAL_TOLERANCE,
) -> CarrierStatics:
    """Leg forces and carrier torques holding the mounted stack still.

    Args:
        q: carrier joint angles [rad].
        plates: poses of plates 0..n relative to the base plate (plate 0 the identity, e.g.
            ``am.home`` or a plates file); they are placed in the world by the carrier.
        goal: optional EE goal in the world, checked like any state's.
        tolerance: how close plate n must be to ``goal`` (m, rad).

    The torques are Pinocchio's ``computeStaticTorque``: the carrier's gravity torques minus
    the joint torques of the external force on the tool joint — the stack's reaction, the
    negative of the base wrench the mount applies to plate 0.
    """
    if not isinstance(carrier, Carrier):
        raise OptionsError(f'carrier must be a Carrier (Carrier("ur5")), got {type(carrier).__name__}')
    q = carrier.check_q(q)
    rel = plate_arrays(am, plates)
    if not (np.allclose(rel.R[0], np.eye(3), atol=1e-9) and np.allclose(rel.p[0], 0.0, atol=1e-12)):
        raise PoseError("plates are relative to the base plate: plate 0 must be the identity")
    base = carrier.base_pose(q)
    world = PlateArrays(np.einsum("ab,kbc->kac", base.rotation, rel.R), rel.p @ base.rotation.T + base.translation)
    state = evaluate_state(am, world, goal=goal, tolerance=tolerance)
    torques = carrier_torques(carrier, q, world.p[0], state.statics.base_wrench)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(carrier.effort_limit > 0, np.abs(torques) / carrier.effort_limit, 0.0)
    return CarrierStatics(state, q, torques, ratio, _stack_ratio(am, state))


def carrier_torques(carrier: Carrier, q: np.ndarray, base_origin: np.ndarray, base_wrench: np.ndarray) -> np.ndarray:
    """Joint torques [N·m] holding the carrier and the stack still: ``computeStaticTorque``
    with the stack's reaction on the tool joint (minus ``base_wrench``, the wrench the mount
    applies to plate 0, world axes, about ``base_origin``, plate 0's origin)."""
    on_carrier_world = pin.SE3(np.eye(3), base_origin).act(pin.Force(-base_wrench[:3], -base_wrench[3:]))
    model, data = carrier.model, carrier.data
    pin.framesForwardKinematics(model, data, q)
    joint = model.frames[carrier.base_frame].parentJoint
    fext = pin.StdVec_Force()
    for k in range(model.njoints):
        fext.append(data.oMi[k].actInv(on_carrier_world) if k == joint else pin.Force.Zero())
    return np.array(pin.computeStaticTorque(model, data, q, fext), dtype=float)


@dataclass
class CarrierSolveResult:
    """A world goal reached by the stack on its carrier (:func:`solve_on_carrier`).

    Attributes:
        success: the stack reaches the goal with every constraint holding and no carrier
            joint over its effort limit.
        message: what happened, or why not.
        goal: the EE goal in the world.
        statics: the chosen pose's :class:`CarrierStatics` (None when no pose was found).
        moved_carrier: whether the carrier's joints were searched.
        candidates: every carrier placement tried: ``(t, q, Ω_c or nan, note)`` with ``t``
            the blend from the goal seen from the start placement (0) to the home EE pose (1);
            the joint optimization's answer last, with ``t`` nan (its JSON row says
            ``"stage": "joint_optimization"``, the others ``"placement"``).
        time_s: wall time [s].
    """

    success: bool
    message: str
    goal: pin.SE3
    statics: CarrierStatics | None
    moved_carrier: bool
    candidates: list[tuple[float, np.ndarray, float, str]] = field(default_factory=list)
    time_s: float = 0.0

    @property
    def binding(self) -> str | None:
        return None if self.statics is None else self.statics.binding

    def to_dict(self) -> dict:
        out = {
            "success": self.success,
            "message": self.message,
            "moved_carrier": self.moved_carrier,
            "goal": self.goal.homogeneous.tolist(),
            "time_s": self.time_s,
            "candidates": [_candidate_dict(*c) for c in self.candidates],
        }
        if self.statics is not None:
            out |= self.statics.to_dict()
            out["state"] = self.statics.state.to_dict()
        return out

    def __repr__(self) -> str:
        detail = repr(self.statics) if self.statics is not None else "no pose"
        return (
            f"CarrierSolveResult(success={self.success}, moved_carrier={self.moved_carrier}, {detail}, "
            f"{self.time_s:.2f} s, message={self.message!r})"
        )


@dataclass(frozen=True)
class _Search:
    """What :func:`solve_on_carrier` solves with: the model, the carrier, the world goal and
    the settings, read once."""

    am: AssemblerModel
    carrier: Carrier
    goal: pin.SE3
    options: OptimizeOptions
    helper: HelperArmOptions | None
    optimize: bool
    w_carrier: float

    @property
    def tolerance(self) -> GoalTolerance:
        """How close plate n must be to the goal: the EE tolerance when the EE may move."""
        return self.options.ee_tolerance or DEFAULT_GOAL_TOLERANCE

    def score(self, statics: CarrierStatics | None) -> float:
        return math.nan if statics is None else carrier_objective(self.am, statics, self.w_carrier, self.options)

    def rank(self, statics: CarrierStatics) -> tuple[bool, float]:
        """Within limits first, then the lower Ω_c."""
        return (not statics.within_limits, self.score(statics))


def _candidate_dict(t: float, q: np.ndarray, score: float, note: str) -> dict:
    """One row of ``candidates`` in JSON: ``stage`` says a placement (with its blend ``t``)
    or the joint optimization (``t`` null)."""
    stage = "joint_optimization" if math.isnan(t) else "placement"
    t_value = None if math.isnan(t) else t
    score_value = None if math.isnan(score) else score
    return {"stage": stage, "t": t_value, "q": q.tolist(), "score": score_value, "note": note}


def _stack_on(s: _Search, q: np.ndarray) -> tuple[CarrierStatics | None, str]:
    """The stack for the world goal with the carrier held at ``q``: the helper arm and (with
    ``s.optimize``) the force optimization for the goal seen from the base, then optimized
    again under the world's gravity; without ``s.optimize`` the helper arm's pose as it is."""
    from .optimize import optimize_internal_poses
    from .solver import solve

    am = s.am
    base = s.carrier.base_pose(q)
    first = solve(am, base.actInv(s.goal), optimize=s.optimize, options=s.options, helper_options=s.helper)
    start = first.best  # with gravity along the base's −z
    if start is None:
        return None, f"the stack cannot reach the goal from this placement: {first.message}"
    world = [base * start.plates.se3(k) for k in range(am.n + 1)]
    why = "helper-arm pose (not optimized)"
    if s.optimize:
        result = optimize_internal_poses(am, world, s.goal, s.options)  # again, under the world's gravity
        if not result.success:
            return None, f"no valid stack pose under the mounted gravity: {result.message}"
        world, why = result.optimized.plates.as_se3(), "converged"
    rel = [pin.SE3.Identity()] + [base.actInv(world[k]) for k in range(1, am.n + 1)]
    return carrier_statics(am, s.carrier, q, rel, goal=s.goal, tolerance=s.tolerance), why


def _checked_settings(
    options: OptimizeOptions | None, helper_options: HelperArmOptions | None, blends: int, max_iterations: int | None
) -> tuple[OptimizeOptions, int]:
    """(options, joint-optimization iteration limit), or an :class:`OptionsError`."""
    from .bounds import check_bound

    if options is not None and not isinstance(options, OptimizeOptions):
        raise OptionsError(f"options must be an OptimizeOptions, got {type(options).__name__}")
    if helper_options is not None and not isinstance(helper_options, HelperArmOptions):
        raise OptionsError(f"helper_options must be a HelperArmOptions, got {type(helper_options).__name__}")
    check_bound("carrier.blends", blends, "blends")
    opts = options or OptimizeOptions()
    limit = opts.max_iterations if max_iterations is None else max_iterations
    check_bound("optimize.max_iterations", limit, "max_iterations")
    return opts, int(limit)


@one_blas_thread
def solve_on_carrier(
    am: AssemblerModel,
    carrier: Carrier,
    goal: pin.SE3 | npt.ArrayLike,
    q0: npt.ArrayLike | None = None,
    move_carrier: bool = True,
    blends: int = 5,
    polish: bool = True,
    w_carrier: float = W_CARRIER,
    max_iterations: int | None = None,
    options: OptimizeOptions | None = None,
    helper_options: HelperArmOptions | None = None,
    optimize: bool = True,
    progress: ProgressCallback | None = None,
) -> CarrierSolveResult:
    """Reach a world EE goal with the stack on its carrier.

    With ``move_carrier=False`` the carrier stays at ``q0`` and the stack is solved for the
    goal seen from its base (helper arm and optimizer, then optimized again under the
    world's gravity).

    With ``move_carrier=True`` the carrier's joints join the search: the goal seen from the
    base is blended from where ``q0`` puts it (t = 0) to the stack's home EE pose (t = 1) in
    ``blends`` steps; for each, the carrier's joint-limited IK places the base so, and the
    stack is solved there; the candidate within every limit with the lowest Ω_c wins. From
    it (``polish``), one SLSQP over the carrier's joints (within their limits) and the
    internal plates together minimizes Ω_c = w1·max|F| + w2·sqrt(Σλ²) +
    ``w_carrier``·max|τ|/τ_max (:func:`carrier_objective`), every leg limit and force limit
    holding and no joint over its effort limit, with forward-difference gradients. Its
    answer is kept only when SLSQP converged, a fresh :func:`carrier_statics` of it holds
    every limit and its Ω_c is lower; otherwise the placement is kept and the message says why.

    Args:
        q0: the carrier's configuration (default: the spec's upright one) [rad].
        blends: placements tried between the start and the home EE pose (2..100).
        polish: run the joint optimization after the placement search.
        w_carrier: weight of the carrier's torque term in Ω_c [N].
        max_iterations: iteration limit of the joint optimization (default
            ``options.max_iterations``).
        options: the stack optimizer's settings (method, w1, w2, EE tolerance, iteration
            limit, ftol); w1, w2 and ftol are the joint optimization's too (which is always
            SLSQP, with the EE at the goal). Default :class:`OptimizeOptions`.
        helper_options: the helper arm's settings (the initial condition at each placement).
        optimize: False: the helper arm's pose at each placement under the world's gravity,
            with neither force nor joint optimization.
        progress: called ``(done, total, note)`` after each placement and the joint optimization.
    """
    t0 = time.perf_counter()
    goal = to_se3(goal, "goal")
    opts, limit = _checked_settings(options, helper_options, blends, max_iterations)
    if isinstance(w_carrier, bool) or not isinstance(w_carrier, (int, float)) or not 0 <= w_carrier < math.inf:
        raise OptionsError(f"w_carrier must be a finite number >= 0 [N], got {w_carrier!r}")
    q0 = carrier.upright_q if q0 is None else carrier.check_q(q0, "q0")
    s = _Search(am, carrier, goal, opts, helper_options, bool(optimize), float(w_carrier))
    if not move_carrier:
        statics, why = _stack_on(s, q0)
        msg = why if statics is None else _verdict(statics)
        ok = statics is not None and statics.within_limits
        return CarrierSolveResult(
            ok, msg, goal, statics, False, [(0.0, q0, s.score(statics), msg)], time.perf_counter() - t0
        )
    best, candidates = _placements(s, q0, blends, progress)
    if best is None:
        message = f"unreachable: no carrier placement gave a valid stack pose ({len(candidates)} placements tried)"
        return CarrierSolveResult(False, message, goal, None, True, candidates, time.perf_counter() - t0)
    note = ""
    if polish and s.optimize and best.within_limits:
        best, note = _polish(s, best, limit, candidates)
    message = _verdict(best) + note
    if progress is not None:
        progress(len(candidates), len(candidates), "done")
    return CarrierSolveResult(best.within_limits, message, goal, best, True, candidates, time.perf_counter() - t0)


def _placements(
    s: _Search, q0: np.ndarray, blends: int, progress: ProgressCallback | None
) -> tuple[CarrierStatics | None, list[tuple[float, np.ndarray, float, str]]]:
    """The placement search of :func:`solve_on_carrier`: (best statics or None, candidates)."""
    start_rel = s.carrier.base_pose(q0).actInv(s.goal)
    home_ee = s.am.home[-1]
    candidates: list[tuple[float, np.ndarray, float, str]] = []
    best: CarrierStatics | None = None
    blend_values = np.linspace(0.0, 1.0, max(2, int(blends)))
    total = len(blend_values) + (1 if s.optimize else 0)
    for k, t in enumerate(blend_values):
        rel = pin.SE3.Interpolate(start_rel, home_ee, float(t))
        ik = s.carrier.ik(s.goal * rel.inverse(), q0)
        if not ik.success:
            candidates.append((float(t), ik.q, math.nan, f"carrier IK failed (error {ik.error:.2e})"))
        else:
            statics, why = _stack_on(s, ik.q)
            candidates.append((float(t), ik.q, s.score(statics), why if statics is None else _verdict(statics)))
            if statics is not None and (best is None or s.rank(statics) < s.rank(best)):
                best = statics
        if progress is not None:
            progress(k + 1, total, f"placement t = {t:.2f}")
    return best, candidates


def _polish(
    s: _Search, best: CarrierStatics, max_iterations: int, candidates: list[tuple[float, np.ndarray, float, str]]
) -> tuple[CarrierStatics, str]:
    """The joint optimization from the best placement: (the state kept, a note for the
    message, empty when the polished point is kept); its candidate row is appended."""
    from .carrier_polish import joint_polish

    polished, q, why = joint_polish(s.am, s.carrier, s.goal, best, s.w_carrier, s.options, max_iterations, s.tolerance)
    better = polished is not None and s.score(polished) < s.score(best)
    if polished is None:
        candidates.append((math.nan, q, math.nan, f"joint optimization: {why}; kept the best placement"))
        return best, f" (the joint optimization was not kept: {why})"
    note = f"joint optimization: {why}{'' if better else ' (no lower Ω_c: kept the placement)'}"
    candidates.append((math.nan, polished.q, s.score(polished), note))
    return (polished, "") if better else (best, "")


def carrier_objective(
    am: AssemblerModel, statics: CarrierStatics, w_carrier: float = W_CARRIER, options: OptimizeOptions | None = None
) -> float:
    """Ω_c = w1·max|F| + w2·sqrt(Σλ²) + w_carrier·max|τ|/τ_max of a mounted state (the paper's
    eq. 10 with the weights of ``options``, default :class:`OptimizeOptions`, plus the
    carrier's torque term) [w1 in 1/N, w2 in 1/rad, w_carrier in N]."""
    from .kinematics import plate_deviation

    o = options or OptimizeOptions()
    lam = plate_deviation(am, statics.state.plates).angles
    return float(
        o.w1 * statics.state.max_abs_force + o.w2 * np.sqrt(np.sum(lam**2)) + w_carrier * statics.carrier_ratio
    )


def _verdict(statics: CarrierStatics) -> str:
    if statics.within_limits:
        share = max(statics.stack_ratio, statics.carrier_ratio)
        return f"reached; {statics.binding} binds at {100 * share:.0f} % of its limit"
    if not statics.state.feasible:
        from .messages import binding, describe

        return f"the stack violates its limits: {describe(binding(statics.state.violations))}"
    k = int(np.argmax(statics.torque_ratio))
    return (
        f"torque limit: carrier joint {k} at {100 * statics.torque_ratio[k]:.0f} % of its effort limit "
        f"({statics.torques[k]:.1f} N·m)"
    )
