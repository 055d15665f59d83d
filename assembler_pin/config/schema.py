"""Configuration of an Assembler: geometry, masses, limits and payload.

The YAML format (every key optional; a missing key takes the default shown)::

    platforms: 4            # number of stacked Stewart platforms, integer >= 1
    gravity: 9.81           # [m/s^2], along -z of the world frame, >= 0
    plate:
      node_radius: 0.15     # [m] radius of the circle carrying the joint nodes, > 0
      node_spacing_deg: 8.0 # [deg] angle between the two leg ends of a node, in [0, 60)
      mass: 0.2             # [kg] plate mass, at the plate centre, >= 0
      radius: 0.17          # [m] radius of the plate's disc (collisions), > 0
      thickness: 0.01       # [m] thickness of the disc, centred on the joint plane, in [0, radius]
    leg:
      min_length: 0.20      # [m] shortest pin-to-pin length, > 0
      max_length: 0.35      # [m] longest pin-to-pin length, > min_length
      motor_mass: 0.10      # [kg] >= 0
      shaft_mass: 0.04      # [kg] >= 0
      motor_com: 0.06       # [m] motor centre of mass from the bottom joint, on the leg axis
      shaft_com: 0.06       # [m] shaft centre of mass from the top joint, on the leg axis
      max_deflection_deg: 45  # [deg] largest joint deflection from the home direction, (0, 90)
      max_tension: 200      # [N] > 0
      max_compression: 200  # [N] > 0
      max_speed: 0.05       # [m/s] > 0, largest leg-length rate along a planned motion
      max_acceleration: 0.2 # [m/s^2] > 0, largest leg-length acceleration along a motion
      stiffness: 1.0e6      # [N/m] axial stiffness of a leg, in [1e3, 1e10]: a ball-screw linear
                            # actuator is 1e6-1e7 N/m (screw, nut, bearings, housing in series);
                            # 1e6, the soft end, suits the small 200 N actuators of the prototype.
                            # It is the MJCF servos' gain too.
      motor_radius: 0.016   # [m] radius of the motor's capsule (collisions), > 0
      shaft_radius: 0.006   # [m] radius of the shaft's capsule, in (0, motor_radius]
      motor_length: 0.12    # [m] the motor's capsule from the bottom joint along the leg, in (0, min_length]
      node_zone: 0.05       # [m] length of a leg end, at a node it shares, not checked against
                            # the node's other legs (nor, on the base plate, the floor), in [0, min_length / 2]
    clearance: 0.005        # [m] smallest distance allowed between two bodies that must not touch, in [0, 1]
    payload:
      mass: 5.0             # [kg] >= 0
      offset: 0.2           # [m] along the end-effector plate's local +z
      radius: 0.0           # [m] a sphere at the payload's centre (collisions), in [0, 1]; 0: none
    hexapod:                # stacks under one body: :mod:`assembler_pin.config.hexapod`
      stacks: 6

Internally everything is SI and radians; only keys ending in ``_deg`` are in degrees.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import yaml

from ..exceptions import ConfigError, short_repr
from .bounds import BOUNDS
from .checks import MAX_MESSAGE, check, shorten, unknown_key, validate
from .hexapod import HexapodConfig, hexapod_from_mapping
from .inputs import read_input_text
from .numbers import finite_float, is_number

__all__ = [
    "AssemblerConfig",
    "LegConfig",
    "PayloadConfig",
    "PlateConfig",
    "load_config",
]


@dataclass(frozen=True)
class PlateConfig:
    """Plate geometry and mass.

    Attributes:
        node_radius: radius of the node circle [m].
        node_spacing_deg: angle between the two leg ends of one node [deg].
        mass: plate mass, concentrated at the plate centre [kg].
        radius, thickness: the plate as a flat cylinder about its frame's z axis, centred on
            the plane of its joint centres (:mod:`assembler_pin.collision`) [m].
    """

    node_radius: float = 0.15
    node_spacing_deg: float = 8.0
    mass: float = 0.2
    radius: float = 0.17
    thickness: float = 0.01


@dataclass(frozen=True)
class LegConfig:
    """Linear actuator (leg) stroke, masses and limits.

    Attributes:
        min_length, max_length: pin-to-pin length range [m].
        motor_mass, shaft_mass: [kg].
        motor_com: motor centre of mass from the bottom joint centre, on the leg axis [m].
        shaft_com: shaft centre of mass from the top joint centre, on the leg axis [m].
        max_deflection_deg: largest deflection of the leg from its home direction at
            either joint, measured in the frame of the plate the joint sits on [deg].
        max_tension, max_compression: force limits, both positive magnitudes [N].
        max_speed, max_acceleration: limits of a leg's length rate [m/s] and its
            acceleration [m/s²] along a planned motion (:mod:`assembler_pin.motion`).
        stiffness: axial stiffness of the leg [N/m] (:mod:`assembler_pin.compliance.ee_stiffness`).
        motor_radius, shaft_radius: radii of the leg's two capsules [m]: the motor from the
            bottom joint centre ``motor_length`` along the axis, the shaft from there to the
            top joint centre (:mod:`assembler_pin.collision`).
        motor_length: [m].
        node_zone: length of a leg's end, at a node it shares with other legs, that is not
            checked against them (nor, at the base plate, against the floor) [m].
    """

    min_length: float = 0.20
    max_length: float = 0.35
    motor_mass: float = 0.10
    shaft_mass: float = 0.04
    motor_com: float = 0.06
    shaft_com: float = 0.06
    max_deflection_deg: float = 45.0
    max_tension: float = 200.0
    max_compression: float = 200.0
    max_speed: float = 0.05
    max_acceleration: float = 0.2
    stiffness: float = 1.0e6
    motor_radius: float = 0.016
    shaft_radius: float = 0.006
    motor_length: float = 0.12
    node_zone: float = 0.05

    @property
    def mid_length(self) -> float:
        """Mid-stroke (home) length [m]."""
        return 0.5 * (self.min_length + self.max_length)

    @property
    def max_deflection(self) -> float:
        """Largest joint deflection [rad]."""
        return math.radians(self.max_deflection_deg)


@dataclass(frozen=True)
class PayloadConfig:
    """A point mass held rigidly by the end-effector plate.

    Attributes:
        mass: [kg].
        offset: distance along the end-effector plate's local +z [m].
        radius: the payload's body, a sphere at its centre, in [0, 1] [m] (0: none;
            :mod:`assembler_pin.collision`).
    """

    mass: float = 5.0
    offset: float = 0.2
    radius: float = 0.0


@dataclass(frozen=True)
class AssemblerConfig:
    """Everything that defines an Assembler. Build with :func:`load_config` or directly.

    Attributes:
        platforms: number of Stewart platforms in series (plates 0..platforms).
        gravity: magnitude of gravity along the world's -z [m/s^2].
        plate, leg, payload: see :class:`PlateConfig`, :class:`LegConfig`,
            :class:`PayloadConfig`.
        clearance: smallest distance allowed between two bodies that must not touch [m]
            (:mod:`assembler_pin.collision`).
        hexapod: stacks under one body (:class:`~assembler_pin.config.hexapod.HexapodConfig`).
    """

    platforms: int = 4
    gravity: float = 9.81
    plate: PlateConfig = field(default_factory=PlateConfig)
    leg: LegConfig = field(default_factory=LegConfig)
    payload: PayloadConfig = field(default_factory=PayloadConfig)
    clearance: float = 0.005
    hexapod: HexapodConfig = field(default_factory=HexapodConfig)

    def __post_init__(self) -> None:
        validate(self)

    # ------------------------------------------------------------------ derived
    @property
    def node_spacing(self) -> float:
        """Angle between the two leg ends of one node [rad]."""
        return math.radians(self.plate.node_spacing_deg)

    @property
    def leg_chord(self) -> float:
        """Horizontal distance between the two ends of a leg in the home pose [m]."""
        return 2.0 * self.plate.node_radius * math.sin(0.5 * (math.pi / 3.0 - self.node_spacing))

    @property
    def home_height(self) -> float:
        """Distance between consecutive plates in the home pose [m] (every leg mid-stroke)."""
        return math.sqrt(self.leg.mid_length**2 - self.leg_chord**2)

    def to_dict(self) -> dict[str, Any]:
        """The configuration as a plain dict, in the YAML file's layout."""
        out = dataclasses.asdict(self)
        out["hexapod"]["body_com"] = list(self.hexapod.body_com)  # YAML's safe dumper writes no tuple
        return out

    def replace(self, **changes: Any) -> AssemblerConfig:
        """A copy with top-level fields or whole sections replaced (validated again)."""
        return dataclasses.replace(self, **changes)


_SECTIONS: dict[str, type] = {"plate": PlateConfig, "leg": LegConfig, "payload": PayloadConfig}
_TOP_SCALARS = ("platforms", "gravity", "clearance")


def _section_from_mapping(name: str, cls: type, data: Any) -> Any:
    if not isinstance(data, Mapping):
        raise ConfigError(f"config key '{name}' must be a mapping of keys to values, got {short_repr(data)}")
    allowed = [f.name for f in dataclasses.fields(cls)]
    for key in data:
        if key not in allowed:
            raise ConfigError(unknown_key(key, allowed, prefix=f"{name}.", doc="docs/configuration.md"))
    return cls(**{k: _number(f"{name}.{k}", v) for k, v in data.items()})


def _number(key: str, value: Any) -> float:
    """The value of config key ``key`` as a finite float (:func:`~.numbers.finite_float`)."""
    x = finite_float(value)
    if x is None:
        reason = "must be a finite number" if is_number(value) else "must be a number"
        raise ConfigError(shorten(f"config key '{key}' = {short_repr(value)} is invalid: {reason}"))
    return x


#: Longest configuration file read [bytes] (the ``config.bytes`` row of the limits table).
MAX_CONFIG_BYTES = int(BOUNDS["config.bytes"].high)
#: Most items of one YAML list read (a closure sidecar of 64 platforms lists 384 motors; a
#: reader may ask for fewer, as a scene for its obstacles).
MAX_LIST_ITEMS = 10_000

_YAML12_INT = re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$")
_YAML12_FLOAT = re.compile(
    r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"
)


class StrictLoader(yaml.SafeLoader):
    """YAML for the package's own files, read by the YAML 1.2 core schema.

    * Numbers are YAML 1.2's: ``9_81``, ``1:30``, ``0b1`` or ``017``-as-octal are not numbers
      (YAML 1.1 reads ``9_81`` as 981 and ``1:30`` as 90) but strings, refused where a number
      belongs; ``2e-1`` and ``1e5`` are numbers. ``true``/``false`` are the only booleans
      (``yes``, ``on`` are strings), ``null``/``~`` the only nulls; no merge keys (``<<``).
    * Aliases and anchors (``*name``, ``&name``) are refused: a configuration never needs
      them, and nested aliases expand exponentially (an "alias bomb").
    * A key given twice is an error (not the last one silently winning).

    Every error is a :class:`~assembler_pin.exceptions.ConfigError` or a ``yaml.YAMLError``.
    """

    yaml_implicit_resolvers: ClassVar[dict] = {}
    #: Most items of one list: reading stops at the next one (:func:`load_yaml`).
    max_items: int = MAX_LIST_ITEMS
    #: What the message adds to the list bound (:func:`load_yaml`).
    items_note: str = ""

    def compose_node(self, parent: yaml.Node | None, index: object) -> yaml.Node:
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None) is not None:
            raise ConfigError(
                f"line {event.start_mark.line + 1}: YAML anchors and aliases (&name, *name) are not accepted"
            )
        if isinstance(parent, yaml.SequenceNode) and isinstance(index, int) and index >= self.max_items:
            raise ConfigError(
                f"line {event.start_mark.line + 1}: a list holds more than {self.max_items} items{self.items_note}"
            )
        return super().compose_node(parent, index)

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise ConfigError(f"key {short_repr(key)} is given twice (line {key_node.start_mark.line + 1})")
            seen.add(key)
        return super().construct_mapping(node, deep=deep)

    def construct_yaml12_int(self, node: yaml.ScalarNode) -> int:
        text = self.construct_scalar(node)
        if not _YAML12_INT.match(text):  # an explicit !!int tag on text that is no YAML 1.2 integer
            raise ConfigError(f"line {node.start_mark.line + 1}: {short_repr(text, 30)} is not an integer")
        base = {"0o": 8, "0x": 16}.get(text[:2], 10)
        return int(text[2:] if base != 10 else text, base)

    def construct_yaml12_float(self, node: yaml.ScalarNode) -> float:
        text = self.construct_scalar(node)
        if not (_YAML12_FLOAT.match(text) or _YAML12_INT.match(text)):
            raise ConfigError(f"line {node.start_mark.line + 1}: {short_repr(text, 30)} is not a number")
        if _YAML12_INT.match(text) and text[:2] in ("0o", "0x"):
            return float(self.construct_yaml12_int(node))
        text = text.lower()
        return float(text.replace(".inf", "inf").replace(".nan", "nan"))


for _tag, _regex, _first in (
    ("bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")),
    ("null", re.compile(r"^(?:~|null|Null|NULL|)$"), ["~", "n", "N", ""]),
    ("int", _YAML12_INT, list("-+0123456789")),
    ("float", _YAML12_FLOAT, list("-+.0123456789")),
):
    StrictLoader.add_implicit_resolver(f"tag:yaml.org,2002:{_tag}", _regex, _first)
StrictLoader.add_constructor("tag:yaml.org,2002:int", StrictLoader.construct_yaml12_int)
StrictLoader.add_constructor("tag:yaml.org,2002:float", StrictLoader.construct_yaml12_float)


def load_yaml(text: str, what: str, max_items: int = MAX_LIST_ITEMS, items_note: str = "") -> Any:
    """Parse YAML text with :class:`StrictLoader`.

    Args:
        what: the source, for the message (e.g. "config file 'c.yaml'").
        max_items: the most items of one list; the read stops at the next one, before the
            rest of the text is parsed; ``items_note`` is added to that message.

    Raises:
        ConfigError: one line of at most :data:`MAX_MESSAGE` characters naming ``what``.
    """
    loader = None
    try:
        loader = StrictLoader(text)  # reads the text's first characters: may raise already
        loader.max_items, loader.items_note = max_items, items_note
        return loader.get_single_data()
    except ConfigError as exc:
        raise ConfigError(shorten(f"{what}: {exc}")) from None
    except yaml.YAMLError as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        raise ConfigError(shorten(f"{what} is not valid YAML{where}: {first}")) from None
    except (RecursionError, ValueError, OverflowError):
        raise ConfigError(f"{what} is not a readable configuration (nested too deeply or a malformed number)") from None
    finally:
        if loader is not None:
            loader.dispose()


def config_from_dict(data: Mapping[str, Any] | None) -> AssemblerConfig:
    """Build a validated configuration from a (possibly partial) mapping.

    Raises:
        ConfigError: unknown keys, wrong types or out-of-range values.
    """
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        raise ConfigError(f"a configuration must be a mapping of keys to values, got {short_repr(data)}")
    allowed = [*_TOP_SCALARS, *_SECTIONS, "hexapod"]
    for key in data:
        if key not in allowed:
            raise ConfigError(unknown_key(key, allowed))
    kwargs: dict[str, Any] = {}
    if "platforms" in data:
        value = data["platforms"]
        whole = finite_float(value)
        if whole is not None and whole.is_integer() and abs(whole) < 2**31:
            value = int(value)  # 3.0 and numpy integers are the integer 3
        check(
            isinstance(value, int) and not isinstance(value, bool),
            "platforms",
            value,
            "must be an integer from 1 to 64",
        )
        kwargs["platforms"] = value
    for key in ("gravity", "clearance"):
        if key in data:
            kwargs[key] = _number(key, data[key])
    for name, cls in _SECTIONS.items():
        if name in data:
            kwargs[name] = _section_from_mapping(name, cls, data[name])
    if "hexapod" in data:
        kwargs["hexapod"] = hexapod_from_mapping(data["hexapod"])
    return AssemblerConfig(**kwargs)


def read_text_file(path: Path, shown: str, what: str, max_bytes: int, error: type[Exception], bound: str = "") -> str:
    """The UTF-8 text of the file at ``path``, at most ``max_bytes`` bytes (a configuration, a
    scene or a model file), read through the one checked door of input files
    (:func:`~assembler_pin.config.inputs.read_input_text`: a FIFO, a directory or a device is
    refused before it is opened).

    Args:
        bound: the row of the limits table that sets ``max_bytes``, named in its message.

    Raises:
        error: one line naming ``what`` and ``shown`` (the path as the user gave it): the file
            cannot be read, is not a regular file, is larger than ``max_bytes`` or is not UTF-8.
    """
    try:
        return read_input_text(path, what, error, max_bytes, shown=shown, bound=bound)
    except error as exc:
        raise error(shorten(str(exc))) from None


def load_config(source: str | Path | Mapping[str, Any] | AssemblerConfig | None = None) -> AssemblerConfig:
    """Load a configuration from a YAML file path, a mapping, or return the default.

    Args:
        source: path of a YAML file, a mapping in the YAML layout, an existing
            :class:`AssemblerConfig` (returned as is), or ``None`` for the defaults.

    Raises:
        ConfigError: unreadable file, invalid YAML, unknown keys, wrong types or values.
    """
    if source is None:
        return AssemblerConfig()
    if isinstance(source, AssemblerConfig):
        return source
    if isinstance(source, Mapping):
        return config_from_dict(source)
    if not isinstance(source, (str, Path)):
        raise ConfigError(
            f"a configuration must be a YAML path, a mapping, an AssemblerConfig or None, got {short_repr(source)}"
        )
    if not str(source):
        raise ConfigError("a config file path must not be empty")
    path = Path(source)
    short_path = shorten(path.name, 40)
    text = read_text_file(path, short_path, "config file", MAX_CONFIG_BYTES, ConfigError, "config.bytes")
    data = load_yaml(text, f"config file '{short_path}'")
    try:
        return config_from_dict(data)
    except ConfigError as exc:
        message = f"{short_path}: {exc}"  # the file's name when the line has room for it
        raise ConfigError(message if len(message) <= MAX_MESSAGE else shorten(str(exc))) from None
