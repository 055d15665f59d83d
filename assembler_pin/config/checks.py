"""The range checks of a configuration: every value of an
:class:`~assembler_pin.config.AssemblerConfig`, with a one-line
:class:`~assembler_pin.exceptions.ConfigError` naming the key and what is allowed.

Units: lengths [m], masses [kg], forces [N], angles in degrees where the key says ``_deg``.
"""

from __future__ import annotations

import dataclasses
import difflib
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from ..exceptions import ConfigError, short_repr
from .bounds import check_bound
from .numbers import finite_float

if TYPE_CHECKING:
    from .schema import AssemblerConfig

__all__ = ["LIMITS", "MAX_MESSAGE", "MAX_PAYLOAD_RADIUS", "check", "shorten", "unknown_key", "validate"]

#: Longest message of a :class:`ConfigError` [characters].
MAX_MESSAGE = 200

#: Largest ``payload.radius`` [m]: a sphere of 2 m across is no tool of a stack of ~0.3 m legs.
MAX_PAYLOAD_RADIUS = 1.0

#: Physically meaningful ranges beyond the per-key rules: every value is at most this
#: large, so no product of them (forces ~ masses × gravity × lengths) overflows.
LIMITS = {
    "gravity": 1e3,  # [m/s^2], 100 g
    "mass": 1e5,  # [kg], any plate, motor, shaft or payload mass
    "length": 1e3,  # [m], radii, leg lengths, centres of mass, payload offset (absolute)
    "force": 1e9,  # [N], force limits
    "stiffness": 1e10,  # [N/m], leg stiffness
}
_UNIT_OF = {
    "gravity": "gravity",
    "mass": "mass",
    "motor_mass": "mass",
    "shaft_mass": "mass",
    "max_tension": "force",
    "max_compression": "force",
    "stiffness": "stiffness",
}


def shorten(message: str, limit: int = MAX_MESSAGE) -> str:
    """``message`` on one line of at most ``limit`` characters."""
    line = " ".join(message.split())
    return line if len(line) <= limit else line[: limit - 1] + "…"


def unknown_key(key: object, allowed: Sequence[str], what: str = "config key", prefix: str = "", doc: str = "") -> str:
    """The one-line message of an unknown key: the closest allowed key when one is close
    (``did you mean 'motor_radius'?``, by :func:`difflib.get_close_matches`), else the allowed
    keys when they fit in :data:`MAX_MESSAGE` characters, else their count and ``doc``, the
    page listing them. ``prefix`` is the section's dotted name (``"leg."``)."""
    text = key if isinstance(key, str) else short_repr(key, 30)  # str() of a huge int fails
    head = f"unknown {what} '{prefix}{shorten(text, 30)}'"
    close = difflib.get_close_matches(text[:100], list(allowed), n=1, cutoff=0.6)
    if close:
        return f"{head}: did you mean '{prefix}{close[0]}'?"
    listed = f"{head}; allowed: {', '.join(allowed)}"
    if len(listed) <= MAX_MESSAGE:
        return listed
    where = f", listed in {doc}" if doc else ""
    return shorten(f"{head}; {prefix.rstrip('.') or 'it'} takes {len(allowed)} keys{where}")


def check(condition: bool, key: str, value: Any, allowed: str) -> None:
    """Raise ConfigError ``config key 'key' = value is invalid: allowed`` unless ``condition``."""
    if not condition:
        raise ConfigError(shorten(f"config key '{key}' = {short_repr(value)} is invalid: {allowed}"))


def validate(cfg: AssemblerConfig) -> None:
    """Check every value; raise ConfigError naming the key and what is allowed."""
    check(
        isinstance(cfg.platforms, int) and not isinstance(cfg.platforms, bool) and 1 <= cfg.platforms <= 64,
        "platforms",
        cfg.platforms,
        "must be an integer from 1 to 64",
    )
    _check_magnitudes(cfg)
    _check_plate_and_payload(cfg)
    _check_leg(cfg)
    _check_home_pose(cfg)
    _check_collision_sizes(cfg)


def _check_magnitudes(cfg: AssemblerConfig) -> None:
    """Every number finite and, by its unit, within :data:`LIMITS` in magnitude."""
    p, leg, pl = cfg.plate, cfg.leg, cfg.payload
    numbers = {"gravity": cfg.gravity, "clearance": cfg.clearance}
    numbers |= {f"plate.{f.name}": getattr(p, f.name) for f in dataclasses.fields(p)}
    numbers |= {f"leg.{f.name}": getattr(leg, f.name) for f in dataclasses.fields(leg)}
    numbers |= {f"payload.{f.name}": getattr(pl, f.name) for f in dataclasses.fields(pl)}
    for key, value in numbers.items():
        x = finite_float(value)  # None for an integer too large for a float, as for NaN
        check(x is not None, key, value, "must be a finite number")
        name = key.rsplit(".", 1)[-1]
        kind = _UNIT_OF.get(name, None if name.endswith("_deg") else "length")
        if kind is not None and x is not None:
            check(abs(x) <= LIMITS[kind], key, value, f"must be at most {LIMITS[kind]:g} in magnitude")


def _check_plate_and_payload(cfg: AssemblerConfig) -> None:
    """Gravity ≥ 0, the plate's node radius > 0 and node spacing in [0, 60)°, masses ≥ 0."""
    p, pl = cfg.plate, cfg.payload
    check(cfg.gravity >= 0, "gravity", cfg.gravity, "must be >= 0 [m/s^2]")
    check(p.node_radius > 0, "plate.node_radius", p.node_radius, "must be > 0 [m]")
    check(0 <= p.node_spacing_deg < 60, "plate.node_spacing_deg", p.node_spacing_deg, "must be in [0, 60) degrees")
    check(p.mass >= 0, "plate.mass", p.mass, "must be >= 0 [kg]")
    check(pl.mass >= 0, "payload.mass", pl.mass, "must be >= 0 [kg]")
    check(0 <= pl.radius <= MAX_PAYLOAD_RADIUS, "payload.radius", pl.radius, "must be in [0, 1] [m]")


def _check_leg(cfg: AssemblerConfig) -> None:
    """The leg's masses, stroke, centres of mass, deflection, force, speed and stiffness limits."""
    leg = cfg.leg
    for key in ("motor_mass", "shaft_mass"):
        check(getattr(leg, key) >= 0, f"leg.{key}", getattr(leg, key), "must be >= 0 [kg]")
    check(leg.min_length > 0, "leg.min_length", leg.min_length, "must be > 0 [m]")
    check(
        leg.max_length > leg.min_length,
        "leg.max_length",
        leg.max_length,
        f"must be > leg.min_length ({leg.min_length}) [m]",
    )
    for key in ("motor_com", "shaft_com"):
        value = getattr(leg, key)
        allowed = f"must be in [0, leg.min_length = {leg.min_length}] [m]"
        check(0 <= value <= leg.min_length, f"leg.{key}", value, allowed)
    deflection = leg.max_deflection_deg
    check(0 < deflection < 90, "leg.max_deflection_deg", deflection, "must be in (0, 90) degrees")
    for key in ("max_tension", "max_compression"):
        check(getattr(leg, key) > 0, f"leg.{key}", getattr(leg, key), "must be > 0 [N]")
    for key in ("max_speed", "max_acceleration"):  # a near-zero limit would plan a near-endless motion
        check_bound(f"leg.{key}", getattr(leg, key), f"config key 'leg.{key}'", ConfigError)
    check(leg.stiffness >= 1e3, "leg.stiffness", leg.stiffness, "must be in [1e3, 1e10] [N/m]")


def _check_home_pose(cfg: AssemblerConfig) -> None:
    """A home pose exists: the mid-stroke leg is longer than the horizontal span of its nodes."""
    leg, chord = cfg.leg, cfg.leg_chord
    if leg.mid_length <= chord * (1.0 + 1e-9):
        raise ConfigError(
            f"no home pose exists: mid-stroke leg length {leg.mid_length:.4g} m must exceed "
            f"the horizontal span between its nodes {chord:.4g} m "
            "(lengthen the legs or reduce plate.node_radius)"
        )


def _check_collision_sizes(cfg: AssemblerConfig) -> None:
    """The bodies' sizes of :mod:`assembler_pin.collision`: plate disc, leg capsules, clearance."""
    p, leg = cfg.plate, cfg.leg
    check(p.radius > 0, "plate.radius", p.radius, "must be > 0 [m]")
    check(
        0 <= p.thickness <= p.radius, "plate.thickness", p.thickness, f"must be in [0, plate.radius = {p.radius}] [m]"
    )
    check(leg.motor_radius > 0, "leg.motor_radius", leg.motor_radius, "must be > 0 [m]")
    check(
        0 < leg.shaft_radius <= leg.motor_radius,
        "leg.shaft_radius",
        leg.shaft_radius,
        f"must be in (0, leg.motor_radius = {leg.motor_radius}] [m]",
    )
    check(
        0 < leg.motor_length <= leg.min_length,
        "leg.motor_length",
        leg.motor_length,
        f"must be in (0, leg.min_length = {leg.min_length}] [m]",
    )
    check(
        0 <= leg.node_zone <= 0.5 * leg.min_length,
        "leg.node_zone",
        leg.node_zone,
        f"must be in [0, leg.min_length / 2 = {0.5 * leg.min_length:g}] [m]",
    )
    check(0 <= cfg.clearance <= 1.0, "clearance", cfg.clearance, "must be in [0, 1] [m]")
