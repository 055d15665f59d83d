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

from .exceptions import AssemblerError, PoseError
from .kinematics import PlateArrays, plate_arrays, to_se3
from .model import AssemblerModel
from .state import StackState, evaluate_state

__all__ = [
    "CARRIERS",
    "Carrier",
    "CarrierSolveResult",
    "CarrierSpec",
    "CarrierStatics",
    "UnknownCarrierError",
    "carrier_statics",
    "robots_directory",
    "solve_on_carrier",
]

logger = logging.getLogger(__name__)


class UnknownCarrierError(AssemblerError, ValueError):
    """A carrier name that is not supported."""


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
    "ur3": CarrierSpec("ur_description/urdf/ur3_robot.urdf", "tool0", (), (-0.041, -0.693, 1.127, 1.138, -1.571, 1.612),
                       "Universal Robots UR3, 6 joints (rated payload 3 kg)"),
    "ur5": CarrierSpec("ur_description/urdf/ur5_robot.urdf", "tool0", (), (-0.02, -1.127, 1.535, 1.164, -1.571, 1.591),
                       "Universal Robots UR5, 6 joints (rated payload 5 kg)"),
    "ur10": CarrierSpec("ur_description/urdf/ur10_robot.urdf", "tool0", (),
                        (-0.023, -1.205, 1.738, 1.038, -1.571, 1.594),
                        "Universal Robots UR10, 6 joints (rated payload 10 kg)"),
    "panda": CarrierSpec("panda_description/urdf/panda.urdf", "panda_link8", ("panda_finger_joint1",
                         "panda_finger_joint2"), (-1.003, -0.35, 1.067, -2.689, -2.649, 0.688, 0.356),
                         "Franka Emika Panda, 7 joints, fingers locked (rated payload 3 kg)"),
}  # fmt: skip
"""The supported carriers by name (see :class:`CarrierSpec`)."""


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
        return (f"Carrier({self.name!r}, {self.model.nv} joints, tool frame {self.spec.tool_frame!r}, effort limits "
                f"{np.round(self.effort_limit, 1).tolist()} N·m)")  # fmt: skip

    @property
    def upright_q(self) -> np.ndarray:
        """The spec's upright configuration [rad]."""
        return np.array(self.spec.upright_q, dtype=float)

    def check_q(self, q: npt.ArrayLike, what: str = "carrier q") -> np.ndarray:
        """``q`` as an (nv,) array within the joint limits, or a :class:`PoseError`."""
        arr = np.asarray(q, dtype=float).ravel()
        if arr.shape != (self.model.nq,) or not np.all(np.isfinite(arr)):
            raise PoseError(f"{what} must be {self.model.nq} finite joint angles [rad] for {self.name}, got {arr}")
        outside = np.flatnonzero((arr < self.lower - 1e-9) | (arr > self.upper + 1e-9))
        if outside.size:
            k = int(outside[0])
            raise PoseError(f"{what}: joint {k} = {arr[k]:.4f} rad is outside [{self.lower[k]:.4f}, "
                            f"{self.upper[k]:.4f}]")  # fmt: skip
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
        return (f"CarrierStatics(max|F| {self.state.max_abs_force:.2f} N ({100 * self.stack_ratio:.0f} % of its "
                f"limit), carrier torque up to {100 * self.carrier_ratio:.0f} % of its effort limit, binding "
                f"{self.binding}, within limits: {self.within_limits})")  # fmt: skip


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
) -> CarrierStatics:
    """Leg forces and carrier torques holding the mounted stack still.

    Args:
        q: carrier joint angles [rad].
        plates: poses of plates 0..n relative to the base plate (plate 0 the identity, e.g.
            ``am.home`` or a plates file); they are placed in the world by the carrier.
        goal: optional EE goal in the world, checked like any state's.

    The torques are Pinocchio's ``computeStaticTorque``: the carrier's gravity torques minus
    the joint torques of the external force on the tool joint — the stack's reaction, the
    negative of the base wrench the mount applies to plate 0.
    """
    q = carrier.check_q(q)
    rel = plate_arrays(am, plates)
    if not (np.allclose(rel.R[0], np.eye(3), atol=1e-9) and np.allclose(rel.p[0], 0.0, atol=1e-12)):
        raise PoseError("plates are relative to the base plate: plate 0 must be the identity")
    base = carrier.base_pose(q)
    world = PlateArrays(np.einsum("ab,kbc->kac", base.rotation, rel.R), rel.p @ base.rotation.T + base.translation)
    state = evaluate_state(am, world, goal=goal) if goal is not None else evaluate_state(am, world)
    f, m = state.statics.base_wrench[:3], state.statics.base_wrench[3:]
    on_carrier_world = pin.SE3(np.eye(3), world.p[0]).act(pin.Force(-f, -m))  # about the world origin
    model, data = carrier.model, carrier.data
    pin.framesForwardKinematics(model, data, q)
    joint = model.frames[carrier.base_frame].parentJoint
    fext = pin.StdVec_Force()
    for k in range(model.njoints):
        fext.append(data.oMi[k].actInv(on_carrier_world) if k == joint else pin.Force.Zero())
    torques = np.array(pin.computeStaticTorque(model, data, q, fext), dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(carrier.effort_limit > 0, np.abs(torques) / carrier.effort_limit, 0.0)
    return CarrierStatics(state, q, torques, ratio, _stack_ratio(am, state))


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
        candidates: every carrier placement tried: ``(t, q, score or nan, note)`` with ``t``
            the blend from the goal seen from the start placement (0) to the home EE pose (1).
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
        out = {"success": self.success, "message": self.message, "moved_carrier": self.moved_carrier,
               "goal": self.goal.homogeneous.tolist(), "time_s": self.time_s,
               "candidates": [{"t": t, "q": q.tolist(), "score": None if math.isnan(s) else s, "note": note}
                              for t, q, s, note in self.candidates]}  # fmt: skip
        if self.statics is not None:
            out |= self.statics.to_dict()
            out["state"] = self.statics.state.to_dict()
        return out

    def __repr__(self) -> str:
        detail = repr(self.statics) if self.statics is not None else "no pose"
        return (f"CarrierSolveResult(success={self.success}, moved_carrier={self.moved_carrier}, {detail}, "
                f"{self.time_s:.2f} s, message={self.message!r})")  # fmt: skip


def _stack_on(am: AssemblerModel, carrier: Carrier, q: np.ndarray, goal: pin.SE3) -> tuple[CarrierStatics | None, str]:
    """The force-optimized stack for a world goal with the carrier held at ``q``."""
    from .optimize import optimize_internal_poses
    from .solve import solve

    base = carrier.base_pose(q)
    rel_goal = base.actInv(goal)
    first = solve(am, rel_goal)  # kinematics and a start, with gravity along the base's −z
    start = first.best
    if start is None:
        return None, f"the stack cannot reach the goal from this placement: {first.message}"
    world = [base * start.plates.se3(k) for k in range(am.n + 1)]
    result = optimize_internal_poses(am, world, goal)  # again, under the world's gravity
    if not result.success:
        return None, f"no valid stack pose under the mounted gravity: {result.message}"
    rel = [base.actInv(result.optimized.plates.se3(k)) for k in range(am.n + 1)]
    rel[0] = pin.SE3.Identity()
    return carrier_statics(am, carrier, q, rel, goal=goal), "converged"


def solve_on_carrier(
    am: AssemblerModel,
    carrier: Carrier,
    goal: pin.SE3 | npt.ArrayLike,
    q0: npt.ArrayLike | None = None,
    move_carrier: bool = True,
    blends: int = 5,
) -> CarrierSolveResult:
    """Reach a world EE goal with the stack on its carrier.

    With ``move_carrier=False`` the carrier stays at ``q0`` and the stack is solved for the
    goal seen from its base (helper arm and optimizer, then optimized again under the
    world's gravity).

    With ``move_carrier=True`` the carrier's joints join the search: the goal seen from the
    base is blended from where ``q0`` puts it (t = 0) to the stack's home EE pose (t = 1) in
    ``blends`` steps; for each, the carrier's joint-limited IK places the base so, and the
    stack is solved there. Each candidate is scored by the larger of the stack's max|F| over
    its force limit and the carrier's largest torque over its effort limit — the utilization
    of whichever binds — and the lowest score wins. This is a search over a one-parameter
    family of placements, not a joint optimization of all the carrier's joints.

    Args:
        q0: the carrier's configuration (default: the spec's upright one) [rad].
    """
    t0 = time.perf_counter()
    goal = to_se3(goal, "goal")
    q0 = carrier.upright_q if q0 is None else carrier.check_q(q0, "q0")
    if not move_carrier:
        statics, why = _stack_on(am, carrier, q0, goal)
        ok = statics is not None and statics.within_limits
        msg = why if statics is None else _verdict(statics)
        return CarrierSolveResult(ok, msg, goal, statics, False, [(0.0, q0, _score(statics), msg)],
                                  time.perf_counter() - t0)  # fmt: skip
    start_rel = carrier.base_pose(q0).actInv(goal)
    home_ee = am.home[-1]
    candidates: list[tuple[float, np.ndarray, float, str]] = []
    best: CarrierStatics | None = None
    for t in np.linspace(0.0, 1.0, max(2, blends)):
        rel = pin.SE3.Interpolate(start_rel, home_ee, float(t))
        ik = carrier.ik(goal * rel.inverse(), q0)
        if not ik.success:
            candidates.append((float(t), ik.q, math.nan, f"carrier IK failed (error {ik.error:.2e})"))
            continue
        statics, why = _stack_on(am, carrier, ik.q, goal)
        candidates.append((float(t), ik.q, _score(statics), why if statics is None else _verdict(statics)))
        if statics is not None and (best is None or _rank(statics) < _rank(best)):
            best = statics
    if best is None:
        return CarrierSolveResult(False, "no carrier placement gave a valid stack pose", goal, None, True, candidates,
                                  time.perf_counter() - t0)  # fmt: skip
    return CarrierSolveResult(best.within_limits, _verdict(best), goal, best, True, candidates,
                              time.perf_counter() - t0)  # fmt: skip


def _score(statics: CarrierStatics | None) -> float:
    return math.nan if statics is None else max(statics.stack_ratio, statics.carrier_ratio)


def _rank(statics: CarrierStatics) -> tuple[bool, float]:
    """Within limits first, then the lower utilization."""
    return (not statics.within_limits, _score(statics))


def _verdict(statics: CarrierStatics) -> str:
    if statics.within_limits:
        return f"reached; {statics.binding} binds at {100 * _score(statics):.0f} % of its limit"
    if not statics.state.feasible:
        return f"the stack violates its limits: {statics.state.violations[0]}"
    k = int(np.argmax(statics.torque_ratio))
    return (
        f"carrier joint {k} at {100 * statics.torque_ratio[k]:.0f} % of its effort limit ({statics.torques[k]:.1f} N·m)"
    )
