"""The helper arm as an ordinary URDF (a kinematic model: visuals, no inertia)."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

from ..common.naming import names
from ..config.schema import AssemblerConfig
from ..exceptions import OptionsError
from ..model.urdf import xml_number
from .limits import cluster_limits

__all__ = ["HELPER_ARM_URDF_FILENAME", "helper_arm_urdf"]

HELPER_ARM_URDF_FILENAME = "helper_arm.urdf"


def _link(
    robot: ET.Element, name: str, d: float, half_link_below: bool, half_link_above: bool, sphere: bool = False
) -> None:
    """A link of the arm: a grey cylinder half a link (d/2 [m]) long below and/or above its
    origin, and a blue sphere at a cluster."""
    el = ET.SubElement(robot, "link", name=name)
    for below, present in ((True, half_link_below), (False, half_link_above)):
        if not present:
            continue
        vis = ET.SubElement(el, "visual")
        ET.SubElement(vis, "origin", xyz=f"0 0 {xml_number(-d / 4 if below else d / 4)}", rpy="0 0 0")
        ET.SubElement(ET.SubElement(vis, "geometry"), "cylinder", radius="0.01", length=xml_number(d / 2))
        ET.SubElement(vis, "material", name="helper_grey")
    if sphere:
        vis = ET.SubElement(el, "visual")
        ET.SubElement(vis, "origin", xyz="0 0 0", rpy="0 0 0")
        ET.SubElement(ET.SubElement(vis, "geometry"), "sphere", radius="0.02")
        ET.SubElement(vis, "material", name="helper_blue")


def _joint(
    robot: ET.Element, name: str, kind: str, parent: str, child: str, z: float, axis: str | None, limit: float
) -> None:
    """A joint ``z`` [m] above its parent's origin; revolute ones get ``[-limit, limit]`` [rad]."""
    el = ET.SubElement(robot, "joint", name=name, type=kind)
    ET.SubElement(el, "parent", link=parent)
    ET.SubElement(el, "child", link=child)
    ET.SubElement(el, "origin", xyz=f"0 0 {xml_number(z)}", rpy="0 0 0")
    if axis is not None:
        ET.SubElement(el, "axis", xyz=axis)
        ET.SubElement(el, "limit", lower=xml_number(-limit), upper=xml_number(limit), effort="0", velocity="0")


def _add_cluster(robot: ET.Element, j: int, n: int, d: float, tilt: float, twist: float) -> None:
    """Cluster j: joints x (d/2 above plate j), y, z co-located, then plate j+1 d/2 above."""
    parent = names.plate(j)
    for axis_name, axis, lim in (("x", "1 0 0", tilt), ("y", "0 1 0", tilt), ("z", "0 0 1", twist)):
        child = names.helper_link(j, axis_name)
        if axis_name == "z":
            _link(robot, child, d, True, True, sphere=True)
        else:
            _link(robot, child, d, False, False)
        z = d / 2 if axis_name == "x" else 0.0
        _joint(robot, names.helper_joint(j, axis_name), "revolute", parent, child, z, axis, lim)
        parent = child
    _link(robot, names.plate(j + 1), d, True, j + 1 < n)
    _joint(robot, names.plate_mount(j + 1), "fixed", parent, names.plate(j + 1), d / 2, None, 0.0)


def helper_arm_urdf(cfg: AssemblerConfig, link_length: float | None = None) -> str:
    """URDF text of the helper arm of a configuration (see the module docstring).

    Links ``plate_0`` (root, the base plate's frame) … ``plate_n`` (tip = end effector);
    joints ``sp{j}_rx``, ``sp{j}_ry``, ``sp{j}_rz`` (revolute about x, y, z, co-located
    at the mid-height point of SP j), limits from :func:`cluster_limits`; the clusters'
    last link is ``sp{j}_cluster``. A kinematic model: links carry visual shapes (a
    cylinder along each link, a sphere at each cluster) but no inertia.

    Args:
        link_length: distance d between clusters [m]; default the home SP height.
    """
    d = cfg.home_height if link_length is None else float(link_length)
    if not (math.isfinite(d) and d > 0.0):
        raise OptionsError(f"helper arm link length must be a positive number of metres, got {link_length!r}")
    tilt, twist = cluster_limits(cfg, d)
    n = cfg.platforms
    robot = ET.Element("robot", name="helper_arm")
    robot.append(
        ET.Comment(
            f" Helper arm of a {n}-platform Assembler (paper III): 3 revolute joints (x, y, z) per "
            f"cluster, clusters {xml_number(d)} m apart; "
            f"limits: tilt {xml_number(tilt)} rad, twist {xml_number(twist)} rad. "
        )
    )
    ET.SubElement(ET.SubElement(robot, "material", name="helper_grey"), "color", rgba="0.6 0.6 0.6 1")
    ET.SubElement(ET.SubElement(robot, "material", name="helper_blue"), "color", rgba="0.2 0.3 0.9 1")
    _link(robot, names.plate(0), d, False, True)
    for j in range(n):
        _add_cluster(robot, j, n, d, tilt, twist)
    ET.indent(robot, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"
