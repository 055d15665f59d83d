"""Statics of the stack on its carrier: the leg forces under world gravity and the carrier's
joint torques holding the whole still (Pinocchio's ``computeStaticTorque`` with the stack's
wrench on the tool joint as an external force)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..config.options import DEFAULT_GOAL_TOLERANCE, GoalTolerance
from ..exceptions import OptionsError, PoseError
from ..kinematics import PlateArrays, plate_arrays
from ..model.assembler import AssemblerModel
from ..state import StackState, evaluate_state
from .robot import Carrier

__all__ = ["CarrierStatics", "carrier_statics", "carrier_torques"]


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
