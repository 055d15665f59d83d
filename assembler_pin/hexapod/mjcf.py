"""MJCF export of the hexapod: every stack the stack's own MJCF
(:func:`~assembler_pin.model.mjcf.assembler_mjcf`, its names prefixed ``s{i}_``) placed at its
foot, one free body welded to the EE plates, one position servo per leg.

* Each stack's reference configuration is the model's home pose, its plate 0 at the stack's
  foot: the export is of stacks at their home poses (:func:`~.machine.ring_stacks`).
* The body ``hexapod_body`` is a free body of the body's mass at its centre of mass (a solid
  disc of ``hexapod.body_radius`` and ``hexapod.body_thickness``, resting on the EE plates);
  each EE plate is welded to it (``<weld name="s{i}_ee_weld">``, its relative pose that of the
  reference configuration).
* ``feet="welded"``: plate 0 of each stack is fixed to the world. ``feet="resting"``: plate 0
  is a free body whose disc collides with the floor plane under it (Coulomb friction
  ``hexapod.friction``); nothing else collides.
* Actuators ``s{i}_sp{j}_leg{k}``, stack by stack, platform-major: ``ctrl`` is the commanded
  length [m]; MuJoCo's actuator force is the leg's compression (the package's force, tension
  positive, is its negative).
"""

from __future__ import annotations

import copy
import xml.etree.ElementTree as ET
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..common.naming import names
from ..exceptions import HexapodError
from ..kinematics import PlateArrays
from ..model.assembler import AssemblerModel
from ..model.mjcf import assembler_mjcf
from ..model.urdf import cylinder_inertia, xml_document, xml_number, xml_vector
from .machine import checked_body, checked_stacks

__all__ = ["BODY", "hexapod_mjcf"]

#: The body's name in the MJCF.
BODY = "hexapod_body"

_REFERENCES = ("name", "body1", "body2", "joint")


def _prefixed(element: ET.Element, prefix: str) -> ET.Element:
    """A deep copy of ``element`` with every name and reference prefixed."""
    out = copy.deepcopy(element)
    for node in out.iter():
        for key in _REFERENCES:
            if key in node.attrib:
                node.set(key, prefix + node.get(key, ""))
    return out


def _quat_wxyz(R: np.ndarray) -> str:
    x, y, z, w = pin.Quaternion(R).coeffs()
    return xml_vector(np.array([w, x, y, z]))


def _check_home(am: AssemblerModel, pas: list[PlateArrays]) -> None:
    home = PlateArrays.from_se3(am.home)
    for i, pa in enumerate(pas):
        foot = pa.se3(0) * home.se3(0).inverse()
        for k in range(am.n + 1):
            if not (foot * home.se3(k)).isApprox(pa.se3(k), 1e-9):
                raise HexapodError(f"stack {i} is not at the model's home pose: the MJCF's reference is the home pose")


def _body(world: ET.Element, am: AssemblerModel, pas: list[PlateArrays], mass: float, com: np.ndarray) -> None:
    hc, plate = am.config.hexapod, am.config.plate
    body = ET.SubElement(world, "body", name=BODY, pos=xml_vector(com))
    ET.SubElement(body, "freejoint", name=f"{BODY}_free")
    inertia = cylinder_inertia(mass, hc.body_radius, hc.body_thickness)
    ET.SubElement(body, "inertial", pos="0 0 0", mass=xml_number(mass), diaginertia=xml_vector(inertia))
    lift = np.array([0.0, 0.0, 0.5 * (plate.thickness + hc.body_thickness)])
    centre = np.mean([pa.p[-1] for pa in pas], axis=0) + lift
    size = xml_vector(np.array([hc.body_radius, 0.5 * hc.body_thickness]))
    ET.SubElement(body, "geom", type="cylinder", size=size, pos=xml_vector(centre - com), material="plate")


def hexapod_mjcf(am: AssemblerModel, stacks: Sequence, body_mass: float, body_com, feet: str = "welded") -> str:
    """The MJCF text (module doc) of the stacks ``stacks`` (at the model's home poses, each
    placed at its foot) under a body of ``body_mass`` [kg] (> 0: a free body) centred at
    ``body_com`` (world [m]), the feet ``"welded"`` or ``"resting"``.

    Raises:
        HexapodError: malformed or non-home stacks, a massless body, unknown ``feet``.
    """
    pas = checked_stacks(am, stacks)
    mass, com = checked_body(body_mass, body_com)
    if not mass > 0:
        raise HexapodError("the MJCF's body is a free body: body_mass must be > 0 kg")
    if feet not in ("welded", "resting"):
        raise HexapodError(f"feet must be welded or resting, got {feet!r:.40}")
    _check_home(am, pas)
    single = ET.fromstring(assembler_mjcf(am.config))
    world, equality, actuator = (single.find(tag) for tag in ("worldbody", "equality", "actuator"))
    assert world is not None and equality is not None and actuator is not None
    stack = world.find(f"body[@name='{names.plate(0)}']")
    assert stack is not None
    world.remove(stack)
    connects, servos = list(equality), list(actuator)
    for node in connects:
        equality.remove(node)
    for node in servos:
        actuator.remove(node)
    friction = xml_vector(np.array([am.config.hexapod.friction, 0.005, 0.0001]))
    for i, pa in enumerate(pas):
        prefix = f"s{i}_"
        body = _prefixed(stack, prefix)
        body.set("pos", xml_vector(pa.p[0]))
        body.set("quat", _quat_wxyz(pa.R[0]))
        if feet == "resting":
            body.insert(0, ET.Element("freejoint", name=f"{prefix}foot"))
            disc = body.find("geom[@type='cylinder']")
            assert disc is not None
            disc.attrib.update(contype="1", conaffinity="1", friction=friction, condim="3")
        world.append(body)
        equality.extend(_prefixed(node, prefix) for node in connects)
        ET.SubElement(equality, "weld", name=f"{prefix}ee_weld", body1=prefix + names.plate(am.n), body2=BODY)
        actuator.extend(_prefixed(node, prefix) for node in servos)
    _body(world, am, pas, mass, com)
    if feet == "resting":
        disc = stack.find("geom[@type='cylinder']")
        assert disc is not None
        floor = min(pa.p[0, 2] for pa in pas) - float(disc.get("size", "0 0").split()[1])
        ET.SubElement(world, "geom", name="floor", type="plane", size="0 0 1", pos=xml_vector(np.array([0, 0, floor])))
        world[-1].attrib.update(contype="1", conaffinity="1", friction=friction)
    single.set("model", "hexapod")
    note = f"\n     A hexapod of {len(pas)} such stacks under one body, feet {feet}."
    return xml_document(single, am.config, note)
