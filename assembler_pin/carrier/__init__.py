"""The stack on a carrier arm: a serial robot from example-robot-data holds the base plate.

The carrier is loaded from the URDFs that the ``example-robot-data`` wheel ships (under
``<site-packages>/cmeel.prefix/share/example-robot-data/robots/``), and the stack's base plate
is fixed to its tool frame through a mount transform (tool → base plate). The stack keeps
its own closed-loop model: its plates are given relative to the base plate and placed in
the world through the carrier's forward kinematics, so gravity acts along world −z whatever
way the carrier turns the stack (sideways, upside down).

* :class:`Carrier` (:mod:`.robot`) — the carrier's Pinocchio model (its own ``Data``, of which
  it is the only writer), the visual model with its meshes, the mount, forward kinematics and
  a joint-limited inverse kinematics of the base plate.
* :func:`carrier_statics` (:mod:`.statics`) — leg forces of the mounted stack and the
  carrier's joint torques holding the whole still: Pinocchio's ``computeStaticTorque`` with
  the stack's wrench on the tool joint as an external force.
* :func:`solve_on_carrier` (:mod:`.solve`) — a world goal: the carrier's joints join the
  search (see its docstring; the joint optimization is :mod:`.polish`), and the result says
  whether the stack or the carrier binds.
"""

from __future__ import annotations

from ..exceptions import UnknownCarrierError
from .robot import CARRIERS, Carrier, CarrierSpec, IKResult, robots_directory
from .solve import W_CARRIER, CarrierSolveResult, carrier_objective, solve_on_carrier
from .statics import CarrierStatics, carrier_statics, carrier_torques

__all__ = [
    "CARRIERS",
    "W_CARRIER",
    "Carrier",
    "CarrierSolveResult",
    "CarrierSpec",
    "CarrierStatics",
    "IKResult",
    "UnknownCarrierError",
    "carrier_objective",
    "carrier_statics",
    "carrier_torques",
    "robots_directory",
    "solve_on_carrier",
]
