"""The ``hexapod`` section of a configuration: k stacks under one rigid body
(:mod:`assembler_pin.hexapod`).

The YAML section (every key optional; a missing key takes the default shown)::

    hexapod:
      stacks: 6             # stacks under the body, integer in [1, 16]
      radius: 0.6           # [m] radius of the circle of the feet (the stacks' base plates), in (0, 100]
      body_mass: 20.0       # [kg] the body's mass, in [0, 1e5]
      body_com: [0.0, 0.0, 0.1]  # [m] the body's centre of mass from the centre of the EE plates' circle
      body_radius: 0.8      # [m] the body as a disc about that circle's axis (collisions), > 0
      body_thickness: 0.05  # [m] the disc's thickness, above the EE plates, in [0, body_radius]
      friction: 0.5         # Coulomb friction coefficient of a resting foot on the floor, in [0, 10]
      min_margin: 0.0       # [m] smallest stability margin of a resting stand and walk, in [-100, 100]
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..exceptions import ConfigError, short_repr
from .bounds import check_bound
from .checks import LIMITS, check, shorten
from .numbers import is_number

__all__ = ["HexapodConfig", "hexapod_from_mapping"]


@dataclass(frozen=True)
class HexapodConfig:
    """The hexapod: its stacks on a ring under one body (module doc for the ranges).

    Attributes:
        stacks: how many stacks; radius: the feet's circle [m] (about the world z axis, on
            the floor z = 0).
        body_mass: [kg]; body_com: (3,) its centre of mass [m] from the centre of the EE
            plates' circle (world axes).
        body_radius, body_thickness: the body as a disc [m] (collisions).
        friction: Coulomb coefficient of a resting foot; min_margin: smallest stability
            margin [m] of a resting stand and of every sample of a walk.
    """

    stacks: int = 6
    radius: float = 0.6
    body_mass: float = 20.0
    body_com: tuple[float, float, float] = (0.0, 0.0, 0.1)
    body_radius: float = 0.8
    body_thickness: float = 0.05
    friction: float = 0.5
    min_margin: float = 0.0

    def __post_init__(self) -> None:
        value = self.stacks
        check(isinstance(value, int) and not isinstance(value, bool), "hexapod.stacks", value, "must be an integer")
        for key in ("stacks", "radius", "body_mass", "friction", "min_margin"):
            check_bound(f"hexapod.{key}", getattr(self, key), f"config key 'hexapod.{key}'", ConfigError)
        check(self.radius > 0, "hexapod.radius", self.radius, "must be in (0, 100] [m]")
        com = self.body_com
        check(
            isinstance(com, tuple)
            and len(com) == 3
            and all(is_number(c) and math.isfinite(c) and abs(c) <= LIMITS["length"] for c in com),
            "hexapod.body_com",
            com,
            f"must be three finite numbers x, y, z [m] within ±{LIMITS['length']:g}",
        )
        r, t = self.body_radius, self.body_thickness
        check(is_number(r) and 0 < r <= LIMITS["length"], "hexapod.body_radius", r, "must be in (0, 1000] [m]")
        check(is_number(t) and 0 <= t <= r, "hexapod.body_thickness", t, f"must be in [0, body_radius = {r}] [m]")


def hexapod_from_mapping(data: Any) -> HexapodConfig:
    """The ``hexapod`` section from its YAML mapping (module doc).

    Raises:
        ConfigError: not a mapping, an unknown key, a value of the wrong type or out of range.
    """
    if not isinstance(data, Mapping):
        raise ConfigError(f"config key 'hexapod' must be a mapping of keys to values, got {short_repr(data)}")
    allowed = [f.name for f in dataclasses.fields(HexapodConfig)]
    values: dict[str, Any] = {}
    for key, value in data.items():
        if key not in allowed:
            name = shorten(str(key), 12)
            raise ConfigError(shorten(f"unknown config key 'hexapod.{name}'; allowed: {','.join(allowed)}"))
        if key == "body_com":
            ok = isinstance(value, (list, tuple)) and len(value) == 3 and all(is_number(c) for c in value)
            check(ok, "hexapod.body_com", value, "must be a list of three numbers x, y, z [m]")
            values[key] = tuple(float(c) for c in value)
        elif key == "stacks":
            ok = is_number(value) and math.isfinite(value) and float(value).is_integer() and abs(value) < 2**31
            check(ok, "hexapod.stacks", value, "must be an integer from 1 to 16")
            values[key] = int(value)
        else:
            check(is_number(value), f"hexapod.{key}", value, "must be a number")
            values[key] = float(value)
    return HexapodConfig(**values)
