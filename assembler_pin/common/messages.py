"""The words of a failure: one short line that names the binding cause and how far off it is.

A result with ``success`` false says why in its ``message`` (``reason`` for motions): one
line of at most :data:`MAX_LENGTH` characters that starts with (or, after a short prefix,
names) one cause of :data:`CAUSES`, followed by the numbers that say how far off, each with
its unit; never "nan" or "inf". The details (every attempt, the solver's own words) stay in
the result's other fields and in the ``--json`` answer.

==================  ================================================================
cause               meaning
==================  ================================================================
unreachable         the goal is farther than the stack or its helper arm can reach
leg stroke          a leg shorter or longer than its stroke, or its top joint not
                    above its bottom joint (continuous translation)
joint deflection    a ball joint deflected past its limit
force limit         a leg's force beyond its tension or compression limit
torque limit        a carrier arm's joint torque beyond its effort limit
singular            a platform whose statics is singular (condition number too large)
goal missed         the end effector away from the goal beyond the tolerance
motion step         a leg would move more in one motion step than allowed
sag limit           the end effector's sag under its own load beyond ``max_sag``
did not converge    an iterative solve (forward kinematics, optimizer, equilibrium)
                    stopped before its tolerance
assembly mode       forward kinematics converged to another solution of the lengths
collision           two bodies (legs, plates, obstacles, the floor) closer than the
                    clearance allowed, in metres
==================  ================================================================

The words *valid* (every kinematic limit met), *feasible* (valid, and every force within
its limits) and *success* (the answer asked for was found) keep those meanings everywhere.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from typing import Protocol, TypeVar

from .labels import leg_label, platform_label

__all__ = ["CAUSES", "MAX_LENGTH", "Violating", "binding", "describe", "finite_text", "number", "one_line"]


class Violating(Protocol):
    """What a message reads of a violated limit (:class:`assembler_pin.constraints.Violation`
    has it): its kind, where (platform and leg, ``None`` for the EE or the whole platform),
    the offending value, the limit and how far past it, in the limit's SI unit, and for a
    collision the two bodies (``between``)."""

    @property
    def kind(self) -> str: ...
    @property
    def platform(self) -> int | None: ...
    @property
    def leg(self) -> int | None: ...
    @property
    def value(self) -> float: ...
    @property
    def limit(self) -> float: ...
    @property
    def amount(self) -> float: ...
    @property
    def between(self) -> tuple[str, str] | None: ...


_V = TypeVar("_V", bound=Violating)

#: The longest failure message [characters].
MAX_LENGTH = 200

#: The causes a failure message names (see the module docstring).
CAUSES = (
    "unreachable",
    "leg stroke",
    "joint deflection",
    "force limit",
    "torque limit",
    "singular",
    "goal missed",
    "motion step",
    "sag limit",
    "did not converge",
    "assembly mode",
    "collision",
)

#: Violation kind → (cause, what is measured, unit, scale from SI to the unit).
_KINDS = {
    "min_length": ("leg stroke", "length", "mm", 1e3),
    "max_length": ("leg stroke", "length", "mm", 1e3),
    "continuous_translation": ("leg stroke", "top joint rise", "mm", 1e3),
    "deflection_bottom": ("joint deflection", "bottom joint", "°", 180.0 / math.pi),
    "deflection_top": ("joint deflection", "top joint", "°", 180.0 / math.pi),
    "tension": ("force limit", "tension", "N", 1.0),
    "compression": ("force limit", "force", "N", 1.0),
    "non_finite_force": ("force limit", "force", "N", 1.0),
    "singular": ("singular", "condition number", "", 1.0),
    "ee_position": ("goal missed", "end effector", "mm", 1e3),
    "ee_rotation": ("goal missed", "end effector", "°", 180.0 / math.pi),
    "collision": ("collision", "distance", "m", 1.0),
}

#: Order in which causes bind when a state breaks several limits (kinematic first).
_PRIORITY = ("ee_position", "ee_rotation", "max_length", "min_length", "continuous_translation")


def number(value: float, unit: str = "", digits: int = 4) -> str:
    """``value`` with ``digits`` significant digits and its unit; "not finite" for NaN or ±inf."""
    if not math.isfinite(value):
        return "not finite"
    text = f"{value:.{digits}g}"
    return f"{text} {unit}".rstrip() if unit not in ("°",) else f"{text}°"


def describe(v: Violating | None) -> str:
    """One violation in the failure vocabulary, with its value, its limit and how far past,
    e.g. ``leg stroke: SP3 leg 0 length 1824 mm, limit 350 mm (1474 mm over)``; ``None``
    (what :func:`binding` gives for no violation) reads ``no limit violated``."""
    if v is None:
        return "no limit violated"
    cause, what, unit, scale = _KINDS.get(v.kind, (v.kind.replace("_", " "), "value", "", 1.0))
    if v.platform is None:
        where = "EE"
    elif v.leg is None:
        where = platform_label(v.platform)
    else:
        where = leg_label(v.platform, v.leg)
    if v.kind == "collision" and v.between is not None:
        value, limit = number(v.value, "m"), number(v.limit, "m")
        under = number(v.amount, "m", 3)
        return f"{cause}: {v.between[0]} and {v.between[1]} {value} apart, clearance {limit} ({under} under)"
    if v.kind == "non_finite_force":
        return f"{cause}: {where} force not finite (the statics overflowed)"
    if v.kind in ("ee_position", "ee_rotation"):
        away = number(scale * v.value, unit)
        return f"{cause}: {where} {away} from the goal (tolerance {number(scale * v.limit, unit, 2)})"
    value, limit = number(scale * v.value, unit), number(scale * v.limit, unit)
    over = number(scale * v.amount, unit, 3)
    side = "under" if v.kind in ("min_length", "continuous_translation") else "over"
    return f"{cause}: {where} {what} {value}, limit {limit} ({over} {side})"


def binding(violations: Iterable[_V]) -> _V | None:
    """The violation a message names: goal errors and leg stroke first, then the largest
    relative amount (how far past the limit, over the limit)."""
    vs = list(violations)
    if not vs:
        return None

    def key(v: _V) -> tuple[int, float]:
        rank = _PRIORITY.index(v.kind) if v.kind in _PRIORITY else len(_PRIORITY)
        rel = v.amount / abs(v.limit) if v.limit and math.isfinite(v.limit) else math.inf
        return rank, -rel if math.isfinite(rel) else -math.inf

    return min(vs, key=key)


_NON_FINITE = re.compile(r"(?<![A-Za-z])[-+]?(nan|inf|infinity)(?![A-Za-z])", re.IGNORECASE)


def finite_text(text: str) -> str:
    """``text`` with every "nan"/"inf" word written "not finite" (layout kept)."""
    return _NON_FINITE.sub("not finite", text)


def one_line(text: str, limit: int = MAX_LENGTH) -> str:
    """``text`` as one line of at most ``limit`` characters: whitespace runs become one
    space, a "nan"/"inf" word becomes "not finite", and a longer text is cut at a word with "…"."""
    line = _NON_FINITE.sub("not finite", " ".join(str(text).split()))
    if len(line) <= limit:
        return line
    cut = line[: limit - 1]
    space = cut.rfind(" ")
    return (cut[:space] if space > limit // 2 else cut).rstrip(" ;,:(") + "…"
