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

from .choices import CARRIER_NAMES, check_names
from .exceptions import AssemblerError, PoseError, UnknownCarrierError
from .kinematics import PlateArrays, plate_arrays, to_se3
from .model import AssemblerModel
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
            the joint optimization's answer last, with ``t`` nan.
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
    from .solver import solve

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
    max_iterations: int = 100,
) -> CarrierSolveResult:
    """Reach a world EE goal with the stack on its carrier.

    With ``move_carrier=False`` the carrier stays at ``q0`` and the stack is solved for the
    goal seen from its base (helper arm and optimizer, then optimized again under the
    world's gravity).

    With ``move_carrier=True`` the carrier's joints join the search: the goal seen from the
    base is blended from where ``q0`` puts it (t = 0) to the stack's home EE pose (t = 1) in
    ``blends`` steps; for each, the carrier's joint-limited IK places the base so, and the
    stack is solved there; the candidate within every limit with the lowest Ω_c wins. From
    it (``polish``), one SLSQP over the
    carrier's joints (within their limits) and the internal plates together minimizes
    Ω_c = w1·max|F| + w2·sqrt(Σλ²) + ``w_carrier``·max|τ|/τ_max (:func:`carrier_objective`),
    every leg limit and force limit holding and no joint over its effort limit, with
    forward-difference gradients; its answer is kept when its Ω_c is lower.

    Args:
        q0: the carrier's configuration (default: the spec's upright one) [rad].
        blends: placements tried between the start and the home EE pose.
        polish: run the joint optimization after the placement search.
        w_carrier: weight of the carrier's torque term in Ω_c [N].
        max_iterations: iteration limit of the joint optimization.
    """
    t0 = time.perf_counter()
    goal = to_se3(goal, "goal")
    q0 = carrier.upright_q if q0 is None else carrier.check_q(q0, "q0")
    if not move_carrier:
        statics, why = _stack_on(am, carrier, q0, goal)
        ok = statics is not None and statics.within_limits
        msg = why if statics is None else _verdict(statics)
        return CarrierSolveResult(ok, msg, goal, statics, False, [(0.0, q0, _score(am, statics, w_carrier), msg)],
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
        candidates.append(
            (float(t), ik.q, _score(am, statics, w_carrier), why if statics is None else _verdict(statics))
        )
        if statics is not None and (best is None or _rank(am, statics, w_carrier) < _rank(am, best, w_carrier)):
            best = statics
    if best is None:
        return CarrierSolveResult(False, "no carrier placement gave a valid stack pose", goal, None, True, candidates,
                                  time.perf_counter() - t0)  # fmt: skip
    if polish and best.within_limits:
        polished, why = _joint_polish(am, carrier, goal, best, w_carrier, max_iterations)
        better = polished is not None and carrier_objective(am, polished, w_carrier) < carrier_objective(
            am, best, w_carrier)  # fmt: skip
        note = f"joint optimization: {why}{'' if better else ' (kept the placement)'}"
        candidates.append(
            (math.nan, polished.q if polished is not None else best.q, _score(am, polished, w_carrier), note)
        )
        if better:
            best = polished
    return CarrierSolveResult(best.within_limits, _verdict(best), goal, best, True, candidates,
                              time.perf_counter() - t0)  # fmt: skip


def carrier_objective(am: AssemblerModel, statics: CarrierStatics, w_carrier: float = W_CARRIER) -> float:
    """Ω_c = w1·max|F| + w2·sqrt(Σλ²) + w_carrier·max|τ|/τ_max of a mounted state (the paper's
    eq. 10 with the optimizer's default weights, plus the carrier's torque term)."""
    from .kinematics import plate_deviation
    from .optimize import OptimizeOptions

    o = OptimizeOptions()
    lam = plate_deviation(am, statics.state.plates).angles
    return float(
        o.w1 * statics.state.max_abs_force + o.w2 * np.sqrt(np.sum(lam**2)) + w_carrier * statics.carrier_ratio
    )


class _JointProblem:
    """The carrier's joints and the internal plates together: x = [q, ξ_1..ξ_{n-1}, s, t],
    the plates as twists in the base plate's frame (``T_k = T_k⁰·exp6(ξ_k)``), plate n at the
    goal (``T_n = base(q)⁻¹·goal``), ``s >= |F_i|`` within the force limits and
    ``t >= |τ_k|/τ_max,k``, ``t <= 1``; every leg limit. Ω_c = w1·s + w2·sqrt(Σλ²) + w_c·t.
    Gradients by forward differences (one statics evaluation per variable)."""

    def __init__(self, am: AssemblerModel, carrier: Carrier, goal: pin.SE3, start: CarrierStatics, w_carrier: float):
        from .optimize import OptimizeOptions

        self.am, self.carrier, self.goal, self.w_carrier = am, carrier, goal, w_carrier
        self.opts = OptimizeOptions()
        base = carrier.base_pose(start.q)
        self.ref = [base.actInv(start.state.plates.se3(k)) for k in range(am.n + 1)]
        self.nq = carrier.model.nq
        self.nx = self.nq + 6 * (am.n - 1) + 2
        self._cache: dict[bytes, np.ndarray] = {}

    def world(self, x: np.ndarray) -> tuple[np.ndarray, PlateArrays]:
        q = x[: self.nq]
        base = self.carrier.base_pose(q)
        rel = [self.ref[0]] + [self.ref[k] * pin.exp6(x[self.nq + 6 * (k - 1) : self.nq + 6 * k])
                               for k in range(1, self.am.n)] + [base.actInv(self.goal)]  # fmt: skip
        return q, PlateArrays.from_se3([base * T for T in rel])

    def vector(self, x: np.ndarray) -> np.ndarray:
        """[Ω_c, constraint rows (>= 0)...] at x (cached)."""
        from .constraints import leg_limit_margins
        from .kinematics import leg_state, plate_deviation
        from .optimize import SINGULAR_FORCE
        from .statics import solve_statics

        key = x.tobytes()
        if key in self._cache:
            return self._cache[key]
        q, world = self.world(x)
        leg = self.am.config.leg
        legs = leg_state(self.am, world)
        statics = solve_statics(self.am, world, legs=legs)
        forces = np.where(np.isfinite(statics.forces), statics.forces, SINGULAR_FORCE).ravel()
        margins = leg_limit_margins(leg, legs.lengths, np.cos(legs.deflection), legs.rise, self.opts.limit_margin,
                                    rise_margin=self.opts.rise_margin).ravel()  # fmt: skip
        angles = plate_deviation(self.am, world).angles
        ratio = carrier_torques(self.carrier, q, world.p[0], statics.base_wrench) / self.carrier.effort_limit
        s, t = x[-2], x[-1]
        omega = self.opts.w1 * s + self.opts.w2 * np.sqrt(np.sum(angles**2)) + self.w_carrier * t
        rows = np.concatenate([[omega], s - forces, s + forces, leg.max_tension - 1e-6 - forces,
                               forces + leg.max_compression - 1e-6, t - ratio, t + ratio, margins])  # fmt: skip
        if len(self._cache) > 512:
            self._cache.clear()
        self._cache[key] = rows
        return rows

    def jacobian(self, x: np.ndarray, step: float = 1e-7) -> np.ndarray:
        f0 = self.vector(x)
        out = np.empty((f0.size, x.size))
        for i in range(x.size):
            xp = x.copy()
            xp[i] += step
            out[:, i] = (self.vector(xp) - f0) / step
        return out


def _joint_polish(
    am: AssemblerModel, carrier: Carrier, goal: pin.SE3, start: CarrierStatics, w_carrier: float, max_iterations: int
) -> tuple[CarrierStatics | None, str]:
    """SLSQP over the carrier's joints and the internal plates from a valid mounted state."""
    from scipy.optimize import minimize

    problem = _JointProblem(am, carrier, goal, start, w_carrier)
    nq, margin = problem.nq, 1e-3
    x0 = np.zeros(problem.nx)
    x0[:nq] = np.clip(start.q, carrier.lower + margin, carrier.upper - margin)
    x0[-2], x0[-1] = start.state.max_abs_force, min(start.carrier_ratio, 1.0 - 1e-6)
    bounds = [(lo + margin, hi - margin) for lo, hi in zip(carrier.lower, carrier.upper, strict=True)]
    bounds += [(None, None)] * (6 * (am.n - 1)) + [(0.0, None), (0.0, 1.0 - 1e-6)]
    jac_cache: dict[bytes, np.ndarray] = {}

    def jac(x: np.ndarray) -> np.ndarray:
        key = x.tobytes()
        if key not in jac_cache:
            jac_cache.clear()
            jac_cache[key] = problem.jacobian(x)
        return jac_cache[key]

    res = minimize(lambda x: problem.vector(x)[0], x0, jac=lambda x: jac(x)[0], method="SLSQP", bounds=bounds,
                   constraints=[{"type": "ineq", "fun": lambda x: problem.vector(x)[1:], "jac": lambda x: jac(x)[1:]}],
                   options={"maxiter": max_iterations, "ftol": 1e-6})  # fmt: skip
    q, world = problem.world(res.x)
    base = carrier.base_pose(q)
    rel = [pin.SE3.Identity()] + [base.actInv(world.se3(k)) for k in range(1, am.n + 1)]
    statics = carrier_statics(am, carrier, q, rel, goal=goal)
    return (statics if statics.within_limits else None), f"{res.message} ({res.nit} iterations)"


def _score(am: AssemblerModel, statics: CarrierStatics | None, w_carrier: float) -> float:
    return math.nan if statics is None else carrier_objective(am, statics, w_carrier)


def _rank(am: AssemblerModel, statics: CarrierStatics, w_carrier: float) -> tuple[bool, float]:
    """Within limits first, then the lower Ω_c."""
    return (not statics.within_limits, carrier_objective(am, statics, w_carrier))


def _verdict(statics: CarrierStatics) -> str:
    if statics.within_limits:
        share = max(statics.stack_ratio, statics.carrier_ratio)
        return f"reached; {statics.binding} binds at {100 * share:.0f} % of its limit"
    if not statics.state.feasible:
        return f"the stack violates its limits: {statics.state.violations[0]}"
    k = int(np.argmax(statics.torque_ratio))
    return (
        f"carrier joint {k} at {100 * statics.torque_ratio[k]:.0f} % of its effort limit ({statics.torques[k]:.1f} N·m)"
    )
