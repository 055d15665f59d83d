"""The one naming scheme of the stack: every link, joint, actuator and column name, built
and parsed here.

Indices are 0-based: plate ``k`` in 0..n (plate 0 the base, plate n the EE plate),
platform ``j`` in 0..n-1 (between plates j and j+1), leg ``i`` in 0..5 of its platform.
The URDF, the MJCF, the meshcat scene, the trajectory CSV columns and the helper arm all use
these names, so a name written by one surface is read back by another. How a person reads
a platform or a leg (``SP1 leg 2``, the same 0-based numbers) is :mod:`~assembler_pin.common.labels`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["LEG_PARTS", "ParsedName", "names", "parse_name"]

LEG_PARTS = ("ux", "cross", "uy", "motor", "actuator", "shaft", "top", "ball")
"""The parts of a leg chain that carry names: universal-joint hinges ``ux``/``uy`` and the
cross between them, the ``motor`` (cylinder) body, the prismatic ``actuator``, the ``shaft``
(rod) body, the ``top`` frame on the upper plate and (MJCF) the ``ball`` closure."""


class names:  # noqa: N801 - a namespace of name builders
    """Builders of every name the package writes."""

    payload = "payload"
    payload_joint = "payload_mount"

    @staticmethod
    def plate(k: int) -> str:
        """Link (URDF) / body (MJCF) / frame of plate k."""
        return f"plate_{k}"

    @staticmethod
    def plate_joint(j: int) -> str:
        """Floating joint of plate j+1 relative to plate j (URDF), ball joint (MJCF)."""
        return f"sp{j}_plate"

    @staticmethod
    def plate_slide(j: int, axis: str) -> str:
        """MJCF slide of plate j+1 along plate j's ``axis`` in {x, y, z}."""
        return f"sp{j}_plate_{axis}"

    @staticmethod
    def leg(j: int, i: int, part: str | None = None) -> str:
        """Leg i of platform j (the MJCF actuator name), or one of its :data:`LEG_PARTS`."""
        return f"sp{j}_leg{i}" if part is None else f"sp{j}_leg{i}_{part}"

    @staticmethod
    def length_column(j: int, i: int) -> str:
        """Trajectory CSV column of the pin-to-pin length of leg i of platform j [m]."""
        return f"L_sp{j}_leg{i}"

    @staticmethod
    def force_column(j: int, i: int) -> str:
        """Trajectory CSV column of the axial force of leg i of platform j with the motion's
        own part (static + inertial) [N], tension positive."""
        return f"F_sp{j}_leg{i}"

    @staticmethod
    def helper_joint(j: int, axis: str) -> str:
        """Helper-arm cluster j's revolute joint about ``axis`` in {x, y, z}."""
        return f"sp{j}_r{axis}"

    @staticmethod
    def helper_link(j: int, axis: str) -> str:
        """Helper-arm link after cluster j's joint about ``axis`` (z ends the cluster)."""
        return f"sp{j}_cluster" if axis == "z" else f"sp{j}_r{axis}_link"

    @staticmethod
    def plate_mount(k: int) -> str:
        """Helper-arm fixed joint that carries plate k."""
        return f"plate_{k}_mount"


@dataclass(frozen=True)
class ParsedName:
    """A parsed name: ``kind`` is ``plate``, ``payload``, ``leg`` or a leg part, and
    ``indices`` (0-based) are ``(k,)`` for plate k, ``(j, i)`` for leg i of platform j and
    ``()`` for the payload."""

    kind: str
    indices: tuple[int, ...] = ()


_PLATE = re.compile(r"plate_(\d+)", re.ASCII)
_LEG = re.compile(r"sp(\d+)_leg(\d+)(?:_([a-z]+))?", re.ASCII)


def parse_name(name: str) -> ParsedName:
    """The body a name built by :class:`names` refers to (the inverse of the builders).

    Raises:
        ValueError: ``name`` is not a plate, payload or leg name.
    """
    if name == names.payload:
        return ParsedName("payload")
    if m := _PLATE.fullmatch(name):
        return ParsedName("plate", (int(m[1]),))
    if (m := _LEG.fullmatch(name)) and (m[3] is None or m[3] in LEG_PARTS):
        return ParsedName(m[3] or "leg", (int(m[1]), int(m[2])))
    raise ValueError(f"{name!r} is not a plate, payload or leg name of the stack")
