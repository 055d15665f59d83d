"""URDF and closure-sidecar generation for an Assembler of any number of platforms.

The URDF is a tree (see DESIGN conventions):

* ``plate_0`` is the root link. Plate k+1 hangs from plate k by the ``floating`` joint
  ``sp{k}_plate`` whose origin is the home pose, so a free-flyer coordinate of zero is
  the home pose of that platform.
* Leg i of platform j is the chain ``plate_j`` → revolute ``sp{j}_leg{i}_ux`` (axis x of a
  frame at the bottom joint centre whose z is the leg's home direction) → ``_cross``
  (massless) → revolute ``sp{j}_leg{i}_uy`` → ``_motor`` → prismatic
  ``sp{j}_leg{i}_actuator`` (axis z, position = pin-to-pin length [m]) → ``_shaft``, whose
  frame origin is the top joint centre.
* The link ``sp{j}_leg{i}_top`` is fixed to plate j+1 at the top joint centre. The ball
  joint closing the loop is the 3D point constraint joining ``sp{j}_leg{i}_shaft`` and
  ``sp{j}_leg{i}_top``: the sidecar lists these pairs.
* ``payload`` is fixed to the end-effector plate at the payload offset and carries the
  payload mass.

Children are written (and named) so that each platform's legs come before the next
plate's free-flyer in Pinocchio's depth-first joint order.

The sidecar (``assembler.yaml``) follows the convention of Gepetto's
example-parallel-robots: ``closed_loop`` (frame-name pairs), ``type`` (``3d`` for each
pair), ``name_mot`` (actuated joints). It adds one key, ``assembler_config``: the
configuration the files were generated from, so that they can be loaded back with all
the limits that are not part of URDF.
"""

from __future__ import annotations

import functools
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import yaml

from .config import AssemblerConfig
from .geometry import DIMENSIONS, LEGS_PER_PLATFORM, LegGeometry, leg_geometry
from .naming import names

__all__ = [
    "SIDECAR_FILENAME",
    "URDF_FILENAME",
    "assembler_urdf",
    "closure_sidecar",
    "cylinder_inertia",
    "names",
    "node_points",
    "xml_number",
    "xml_vector",
]

URDF_FILENAME = "assembler.urdf"
SIDECAR_FILENAME = "assembler.yaml"


def xml_number(x: float) -> str:
    """A number as URDF text: 15 significant decimals, ``0`` for zero (shared by every URDF writer)."""
    x = float(x)
    if x == 0.0:
        return "0"
    return repr(round(x, 15))


def xml_vector(v: np.ndarray) -> str:
    """A vector as space-separated numbers (:func:`xml_number`)."""
    return " ".join(xml_number(x) for x in v)


def _origin(parent: ET.Element, xyz: np.ndarray, rotation: np.ndarray | None = None) -> None:
    rpy = np.zeros(3) if rotation is None else pin.rpy.matrixToRpy(rotation)
    ET.SubElement(parent, "origin", xyz=xml_vector(xyz), rpy=xml_vector(rpy))


def _inertial(link: ET.Element, mass: float, com: np.ndarray, diag: np.ndarray) -> None:
    inertial = ET.SubElement(link, "inertial")
    _origin(inertial, com)
    ET.SubElement(inertial, "mass", value=xml_number(mass))
    ET.SubElement(
        inertial,
        "inertia",
        ixx=xml_number(diag[0]),
        ixy="0",
        ixz="0",
        iyy=xml_number(diag[1]),
        iyz="0",
        izz=xml_number(diag[2]),
    )


def cylinder_inertia(mass: float, radius: float, length: float) -> np.ndarray:
    """Diagonal inertia of a solid cylinder about its centre, axis z [kg m^2] (every model writer's)."""
    ixx = mass * (3.0 * radius**2 + length**2) / 12.0
    return np.array([ixx, ixx, 0.5 * mass * radius**2])


def _shape(
    link: ET.Element,
    xyz: np.ndarray,
    geometry: tuple[str, dict[str, str]],
    material: str | None = None,
    collision: bool = True,
) -> None:
    tags = ("visual", "collision") if collision else ("visual",)
    for tag in tags:
        el = ET.SubElement(link, tag)
        _origin(el, xyz)
        geom = ET.SubElement(el, "geometry")
        ET.SubElement(geom, geometry[0], geometry[1])
        if tag == "visual" and material is not None:
            ET.SubElement(el, "material", name=material)


def _joint(
    robot: ET.Element,
    name: str,
    kind: str,
    parent: str,
    child: str,
    xyz: np.ndarray,
    rotation: np.ndarray | None = None,
    axis: str | None = None,
    limit: tuple[float, float, float] | None = None,
) -> None:
    joint = ET.SubElement(robot, "joint", name=name, type=kind)
    _origin(joint, xyz, rotation)
    ET.SubElement(joint, "parent", link=parent)
    ET.SubElement(joint, "child", link=child)
    if axis is not None:
        ET.SubElement(joint, "axis", xyz=axis)
    if limit is not None:
        lower, upper, effort = limit
        ET.SubElement(
            joint, "limit", lower=xml_number(lower), upper=xml_number(upper), effort=xml_number(effort), velocity="0"
        )


def node_points(cfg: AssemblerConfig, k: int) -> np.ndarray:
    """(3, 3) centres of plate k's three joint nodes in its frame [m] (drawn as spheres)."""
    a = np.radians(90.0 + 60.0 * k + 120.0 * np.arange(3))
    r = cfg.plate.node_radius
    return np.stack([r * np.cos(a), r * np.sin(a), np.zeros(3)], axis=1)


#: Colours of the URDF's materials (RGBA).
_MATERIALS = {
    "plate": "0.55 0.6 0.7 1",
    "motor": "0.2 0.25 0.3 1",
    "shaft": "0.8 0.8 0.8 1",
    "node": "0.15 0.35 0.8 1",
    "payload": "0.85 0.55 0.1 1",
}
_ZERO = np.zeros(3)
_Z_AXIS = np.array([0.0, 0.0, 1.0])


def _add_plate(robot: ET.Element, cfg: AssemblerConfig, k: int) -> None:
    """The link of plate k: a cylinder of the plate's mass with its three joint nodes."""
    dim, r = DIMENSIONS, cfg.plate.node_radius
    link = ET.SubElement(robot, "link", name=names.plate(k))
    _inertial(link, cfg.plate.mass, _ZERO, cylinder_inertia(cfg.plate.mass, r, dim.plate_thickness))
    _shape(link, _ZERO, ("cylinder", {"radius": xml_number(r), "length": xml_number(dim.plate_thickness)}), "plate")
    for p in node_points(cfg, k):
        _shape(link, p, ("sphere", {"radius": xml_number(dim.node_sphere_radius)}), "node", collision=False)


def _add_leg_body(
    robot: ET.Element, name: str, mass: float, com: float, length: float, radius: float, material: str
) -> None:
    """A leg's motor or shaft link: a cylinder of ``mass`` [kg], ``length`` and ``radius``
    [m] centred ``com`` [m] along the leg axis (no shape unless its length is positive)."""
    link = ET.SubElement(robot, "link", name=name)
    _inertial(link, mass, com * _Z_AXIS, cylinder_inertia(mass, radius, length))
    if length > 0:
        _shape(
            link,
            com * _Z_AXIS,
            ("cylinder", {"radius": xml_number(radius), "length": xml_number(length)}),
            material,
        )


def _add_leg(robot: ET.Element, cfg: AssemblerConfig, geo: LegGeometry, j: int, i: int) -> None:
    """Leg i of platform j: ``_ux`` → ``_cross`` → ``_uy`` → ``_motor`` → ``_actuator`` → ``_shaft``."""
    leg, dim = cfg.leg, DIMENSIONS
    defl = leg.max_deflection
    n_ = functools.partial(names.leg, j, i)
    _inertial(ET.SubElement(robot, "link", name=n_("cross")), 0.0, _ZERO, _ZERO)
    _joint(
        robot,
        n_("ux"),
        "revolute",
        names.plate(j),
        n_("cross"),
        geo.bottom_in_plate[j, i],
        geo.leg_base_rotation[j, i],
        "1 0 0",
        (-defl, defl, 0.0),
    )
    _add_leg_body(robot, n_("motor"), leg.motor_mass, leg.motor_com, 2.0 * leg.motor_com, dim.motor_radius, "motor")
    _joint(robot, n_("uy"), "revolute", n_("cross"), n_("motor"), _ZERO, None, "0 1 0", (-defl, defl, 0.0))
    shaft_len = 2.0 * leg.shaft_com
    _add_leg_body(robot, n_("shaft"), leg.shaft_mass, -leg.shaft_com, shaft_len, dim.shaft_radius, "shaft")
    force_limit = max(leg.max_tension, leg.max_compression)
    limit = (leg.min_length, leg.max_length, force_limit)
    _joint(robot, n_("actuator"), "prismatic", n_("motor"), n_("shaft"), _ZERO, None, "0 0 1", limit)


def _add_platform(robot: ET.Element, cfg: AssemblerConfig, geo: LegGeometry, j: int) -> None:
    """Platform j: its six legs, plate j+1 on its floating joint, and the legs' top mounts."""
    for i in range(LEGS_PER_PLATFORM):
        _add_leg(robot, cfg, geo, j, i)
    _add_plate(robot, cfg, j + 1)
    home = np.array([0.0, 0.0, cfg.home_height])
    _joint(robot, names.plate_joint(j), "floating", names.plate(j), names.plate(j + 1), home)
    for i in range(LEGS_PER_PLATFORM):
        top = ET.SubElement(robot, "link", name=names.leg(j, i, "top"))
        _inertial(top, 0.0, _ZERO, _ZERO)
        mount = names.leg(j, i, "top_mount")
        _joint(robot, mount, "fixed", names.plate(j + 1), names.leg(j, i, "top"), geo.top_in_plate[j, i])


def _add_payload(robot: ET.Element, cfg: AssemblerConfig) -> None:
    """The payload: a box of the payload's mass fixed above the EE plate at its offset."""
    size = DIMENSIONS.payload_size
    payload = ET.SubElement(robot, "link", name=names.payload)
    m = cfg.payload.mass
    _inertial(payload, m, _ZERO, np.full(3, m * size**2 / 6.0))
    _shape(payload, _ZERO, ("box", {"size": xml_vector(np.full(3, size))}), "payload")
    offset = np.array([0.0, 0.0, cfg.payload.offset])
    _joint(robot, names.payload_joint, "fixed", names.plate(cfg.platforms), names.payload, offset)


def assembler_urdf(cfg: AssemblerConfig) -> str:
    """The URDF text of the stack described by ``cfg`` (see module docstring), written in
    document order: materials, plate 0, then per platform its legs and its top plate, the payload."""
    robot = ET.Element("robot", name="assembler")
    for name, rgba in _MATERIALS.items():
        ET.SubElement(ET.SubElement(robot, "material", name=name), "color", rgba=rgba)
    _add_plate(robot, cfg, 0)
    geo = leg_geometry(cfg)
    for j in range(cfg.platforms):
        _add_platform(robot, cfg, geo, j)
    _add_payload(robot, cfg)
    ET.indent(robot, space="  ")
    header = (
        '<?xml version="1.0"?>\n'
        f"<!-- Assembler: {cfg.platforms} stacked Stewart platforms, generated by assembler_pin. Loop\n"
        "     closures (ball joints) are listed in the sidecar assembler.yaml. -->\n"
    )
    return header + ET.tostring(robot, encoding="unicode") + "\n"


def closure_sidecar(cfg: AssemblerConfig) -> str:
    """The closure sidecar YAML text (Gepetto example-parallel-robots convention)."""
    pairs = [
        [names.leg(j, i, "shaft"), names.leg(j, i, "top")]
        for j in range(cfg.platforms)
        for i in range(LEGS_PER_PLATFORM)
    ]
    data = {
        "closed_loop": pairs,
        "type": ["3d"] * len(pairs),
        "name_mot": [names.leg(j, i, "actuator") for j in range(cfg.platforms) for i in range(LEGS_PER_PLATFORM)],
        "assembler_config": cfg.to_dict(),
    }
    header = (
        "# Loop closures of assembler.urdf (convention of Gepetto's example-parallel-robots).\n"
        "# closed_loop: frame pairs joined by a ball joint; type: 3d = point constraint;\n"
        "# name_mot: actuated (prismatic) joints; assembler_config: the generating config.\n"
    )
    return header + yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100)
