"""Hold a loaded URDF to the configuration its closure sidecar carries.

The exported ``assembler.urdf`` and ``assembler.yaml`` say the same things twice: every mass,
inertia, centre of mass, joint origin (the geometry), joint limit and the platform count of
the URDF follows from the sidecar's ``assembler_config``. :func:`urdf_disagreements` reads both
URDFs — the one given and the one :func:`~assembler_pin.model.urdf.assembler_urdf` writes for the
sidecar's configuration — element by element (links and joints by name; numbers to a relative
tolerance of 1e-9) and lists every difference with the configuration keys it depends on.
The sidecar's keys that are not in a URDF (gravity, speed limits) are taken from it as they are.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from ..exceptions import ModelFileError, short_repr

__all__ = ["NUMBER_TOL", "parse_urdf", "urdf_disagreements", "urdf_facts"]

#: Relative (and absolute, for values near 0) tolerance of a URDF number against the
#: sidecar's: the URDF is written with 15 significant digits.
NUMBER_TOL = 1e-9

#: Most differences quoted in one message.
_QUOTED = 2

#: The configuration keys each URDF quantity follows from (first matching pattern).
_HINTS: tuple[tuple[str, str], ...] = (
    (r"^link plate_\d+ inertial", "plate.mass, plate.node_radius"),
    (r"^link payload inertial", "payload.mass"),
    (r"^link sp\d+_leg\d+_motor inertial origin", "leg.motor_com"),
    (r"^link sp\d+_leg\d+_motor inertial", "leg.motor_mass, leg.motor_com"),
    (r"^link sp\d+_leg\d+_shaft inertial origin", "leg.shaft_com"),
    (r"^link sp\d+_leg\d+_shaft inertial", "leg.shaft_mass, leg.shaft_com"),
    (r"^joint sp\d+_leg\d+_u[xy] limit", "leg.max_deflection_deg"),
    (r"^joint sp\d+_leg\d+_actuator limit effort", "leg.max_tension, leg.max_compression"),
    (r"^joint sp\d+_leg\d+_actuator limit", "leg.min_length, leg.max_length"),
    (r"^joint sp\d+_leg\d+_ux origin", "plate.node_radius, plate.node_spacing_deg, leg stroke"),
    (r"^joint sp\d+_plate origin", "home height: leg stroke, plate.node_radius"),
    (r"^joint sp\d+_leg\d+_top_mount origin", "plate.node_radius, plate.node_spacing_deg"),
    (r"^joint payload_mount origin", "payload.offset"),
    (r"^link plate_\d+ (visual|collision)", "plate.node_radius"),
    (r"^link sp\d+_leg\d+_(motor|shaft) (visual|collision)", "leg.motor_com, leg.shaft_com"),
)

_Fact = tuple[float, ...] | str


def parse_urdf(text: str, what: str) -> ET.Element:
    """The ``<robot>`` element of a URDF text (no DTD or entities: a URDF needs none).

    Raises:
        ModelFileError: not XML, a DOCTYPE/ENTITY declaration, or no ``<robot>`` root.
    """
    if re.search(r"<!(DOCTYPE|ENTITY)", text, re.IGNORECASE):
        raise ModelFileError(f"{what}: a DOCTYPE or ENTITY declaration is not accepted in a URDF")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ModelFileError(f"{what} is not XML: {exc}") from None
    if root.tag != "robot":
        raise ModelFileError(f"{what}: the root element must be <robot>, got <{short_repr(root.tag, 30)[1:-1]}>")
    return root


def _numbers(text: str | None, count: int, what: str, default: str | None = None) -> tuple[float, ...]:
    raw = default if text is None else text
    parts = (raw or "").split()
    try:
        values = tuple(float(x) for x in parts)
    except ValueError:
        values = ()
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise ModelFileError(f"URDF {what}: expected {count} finite numbers, got {short_repr(raw, 40)}")
    return values


def _origin(facts: dict[str, _Fact], key: str, element: ET.Element) -> None:
    origin = element.find("origin")
    xyz = _numbers(None if origin is None else origin.get("xyz"), 3, f"{key} origin xyz", "0 0 0")
    rpy = _numbers(None if origin is None else origin.get("rpy"), 3, f"{key} origin rpy", "0 0 0")
    facts[f"{key} origin xyz"] = xyz
    facts[f"{key} origin rotation"] = tuple(pin.rpy.rpyToMatrix(np.array(rpy)).ravel())


def _link_facts(facts: dict[str, _Fact], link: ET.Element, key: str) -> None:
    inertial = link.find("inertial")
    if inertial is None:
        facts[f"{key} inertial"] = "none"
    else:
        _origin(facts, f"{key} inertial", inertial)
        mass = inertial.find("mass")
        facts[f"{key} inertial mass"] = _numbers(None if mass is None else mass.get("value"), 1, f"{key} mass")
        inertia = inertial.find("inertia")
        names = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        values = " ".join("nan" if inertia is None else (inertia.get(n) or "nan") for n in names)
        facts[f"{key} inertial inertia"] = _numbers(values, 6, f"{key} inertia")
    for tag in ("visual", "collision"):
        for k, shape in enumerate(link.findall(tag)):
            where = f"{key} {tag} {k}"
            _origin(facts, where, shape)
            geometry = shape.find("geometry")
            kinds = [] if geometry is None else list(geometry)
            if len(kinds) != 1:
                facts[f"{where} geometry"] = "missing"
                continue
            g = kinds[0]
            facts[f"{where} geometry"] = g.tag
            for attr in ("radius", "length"):
                if g.get(attr) is not None:
                    facts[f"{where} {g.tag} {attr}"] = _numbers(g.get(attr), 1, f"{where} {attr}")
            if g.get("size") is not None:
                facts[f"{where} {g.tag} size"] = _numbers(g.get("size"), 3, f"{where} size")


def _joint_facts(facts: dict[str, _Fact], joint: ET.Element, key: str) -> None:
    facts[f"{key} type"] = joint.get("type") or "missing"
    for tag in ("parent", "child"):
        el = joint.find(tag)
        facts[f"{key} {tag}"] = "missing" if el is None else (el.get("link") or "missing")
    _origin(facts, key, joint)
    axis = joint.find("axis")
    facts[f"{key} axis"] = _numbers(None if axis is None else axis.get("xyz"), 3, f"{key} axis", "1 0 0")
    limit = joint.find("limit")
    if limit is not None:
        for attr in ("lower", "upper", "effort"):
            facts[f"{key} limit {attr}"] = _numbers(limit.get(attr), 1, f"{key} limit {attr}", "0")


def urdf_facts(root: ET.Element) -> dict[str, _Fact]:
    """Every quantity of a URDF that the configuration determines, keyed ``"link NAME ..."``
    or ``"joint NAME ..."`` in document order (materials and colours are left out).

    Raises:
        ModelFileError: a link or joint without a name or given twice, or a malformed number.
    """
    facts: dict[str, _Fact] = {}
    seen: set[str] = set()
    for element in root:
        if element.tag not in ("link", "joint"):
            continue
        name = element.get("name")
        if not name or " " in name:
            raise ModelFileError(f"URDF: a <{element.tag}> has no name, or a name with spaces")
        key = f"{element.tag} {name}"
        if key in seen:
            raise ModelFileError(f"URDF: {element.tag} {short_repr(name, 40)} is given twice")
        seen.add(key)
        facts[key] = element.tag
        (_link_facts if element.tag == "link" else _joint_facts)(facts, element, key)
    return facts


def _plate_count(facts: dict[str, _Fact]) -> int:
    return sum(1 for k in facts if re.fullmatch(r"link plate_\d+", k))


def _differs(a: _Fact, b: _Fact) -> int | None:
    """Index of the first differing component (0 for strings), None when equal to tolerance."""
    if isinstance(a, str) or isinstance(b, str):
        return None if a == b else 0
    if len(a) != len(b):
        return 0
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        if not abs(x - y) <= NUMBER_TOL * max(1.0, abs(x), abs(y)):
            return i
    return None


def _hint(key: str) -> str:
    for pattern, keys in _HINTS:
        if re.match(pattern, key):
            return keys
    return "platforms" if key.startswith(("link plate_", "joint sp")) else "the generated layout"


def _number(values: tuple[float, ...], i: int, digits: int = 6) -> str:
    return f"{values[i]:.{digits}g}" if i < len(values) else "-"


def _describe(key: str, given: _Fact | None, expected: _Fact | None) -> str:
    kind, name, *rest = key.split(" ")
    what = f"{kind} '{short_repr(name, 40)[1:-1]}' {' '.join(rest)}".strip()
    if given is None:
        return f"{what}: missing from the URDF"
    if expected is None:
        return f"{what}: in the URDF only"
    i = _differs(given, expected) or 0
    if isinstance(given, str) or isinstance(expected, str):
        a, b = short_repr(given, 30), short_repr(expected, 30)
    else:
        index = f"[{i}]" if len(expected) > 1 else ""
        what += index
        a, b = (_number(v, i) for v in (given, expected))
        if a == b:
            a, b = (_number(v, i, 17) for v in (given, expected))
    return f"{what}: URDF {a}, sidecar {b} [{_hint(key)}]"


def urdf_disagreements(given: ET.Element, expected: ET.Element) -> str | None:
    """One line naming where the given URDF differs from the expected one, None when every
    quantity agrees (:data:`NUMBER_TOL`).

    The platform count is compared first (the number of ``plate_k`` links), then every link
    and joint quantity by name; at most three differences are quoted, with the count of the rest.
    """
    a, b = urdf_facts(given), urdf_facts(expected)
    plates_a, plates_b = _plate_count(a), _plate_count(b)
    if plates_a == 0:
        robot = short_repr(given.get("name", ""), 30)
        return f"the URDF (robot {robot}) has no plate links plate_0, plate_1, ...: it does not describe an Assembler"
    if plates_a != plates_b:
        return (
            f"platform count: the URDF has {plates_a} plates ({plates_a - 1} platforms), "
            f"the sidecar's assembler_config platforms = {plates_b - 1}"
        )
    keys = list(b) + [k for k in a if k not in b]
    diffs = [k for k in keys if k not in a or k not in b or _differs(a[k], b[k]) is not None]
    if not diffs:
        return None
    groups: dict[str, list[str]] = {}  # the same quantity of every leg or plate: one group
    for k in diffs:
        groups.setdefault(_hint(k), []).append(k)
    # the quantities that follow from the fewest configuration keys first: they name the cause
    ordered = sorted(groups.values(), key=lambda members: _hint(members[0]).count(","))
    parts = []
    for members in ordered[:_QUOTED]:
        alike = f" (+{len(members) - 1} alike)" if len(members) > 1 else ""
        parts.append(_describe(members[0], a.get(members[0]), b.get(members[0])) + alike)
    more = f"; {len(groups) - _QUOTED} more kinds differ" if len(groups) > _QUOTED else ""
    return "; ".join(parts) + more
