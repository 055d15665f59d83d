"""Scenes: the obstacles around the stack and the floor, read strictly from YAML.

The format (every key but ``obstacles`` or ``floor`` optional; world frame, z up, metres,
rotation vectors in radians)::

    floor: {z: 0.0}                 # a horizontal plane; bodies must stay above it
    obstacles:
      - box: {size: [0.1, 0.1, 0.5], pose: [0.6, 0.0, 0.25, 0.0, 0.0, 0.0]}
        name: column                # optional, at most 40 characters
      - cylinder: {radius: 0.02, length: 1.0, pose: [0.5, -0.3, 0.5, 1.5708, 0.0, 0.0]}
      - sphere: {radius: 0.05, center: [0.4, 0.3, 0.9]}
      - box: {size: [0.6, 0.6, 0.1], pose: [0.0, 0.0, -0.056, 0.0, 0.0, 0.0]}
        support: true               # optional: the stack is mounted on it (boxes, cylinders)

``size`` is the box's full edge lengths along its own axes; ``pose`` is the box's or the
cylinder's centre ``(x, y, z)`` and the rotation vector ``(rx, ry, rz)`` of its frame (a
cylinder's axis is its frame's z). An obstacle without ``name`` is called ``"box 0"``,
``"cylinder 1"``... by its kind and its index in the list. A box or a cylinder with
``support: true`` is what the stack stands on (a table, a mount): it gets the floor's rule,
not checked against the standing plates nor against the first ``leg.node_zone`` of a leg
from its joint on one. Counts and sizes are bounded
(:data:`MAX_OBSTACLES`, :data:`MAX_SIZE`); every refusal is one
:class:`~assembler_pin.exceptions.SceneError` line naming the entry and what is allowed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from ..config.bounds import BOUNDS
from ..config.checks import shorten, unknown_key
from ..config.numbers import finite_float
from ..config.schema import load_yaml, read_text_file
from ..exceptions import ConfigError, SceneError, short_repr

__all__ = ["MAX_OBSTACLES", "MAX_SCENE_BYTES", "MAX_SIZE", "Obstacle", "Scene", "read_scene", "scene_from_dict"]

#: Most obstacles a scene may hold (the ``scene.obstacles`` row of the limits table).
MAX_OBSTACLES = int(BOUNDS["scene.obstacles"].high)
#: Largest size, radius, length or coordinate magnitude accepted [m].
MAX_SIZE = 1e3
#: Largest scene file read [bytes] (the ``scene.bytes`` row of the limits table): 1 KiB an
#: obstacle (an entry is under 300 bytes), so that the largest file is read in well under 1 s.
MAX_SCENE_BYTES = int(BOUNDS["scene.bytes"].high)
#: Longest obstacle name [characters].
MAX_NAME = 40

_KINDS = ("box", "cylinder", "sphere")


@dataclass(frozen=True)
class Obstacle:
    """One fixed obstacle.

    Attributes:
        kind: ``box``, ``cylinder`` or ``sphere``.
        name: how messages name it.
        pose: its frame in the world (identity rotation for a sphere) [m].
        size: box: full edge lengths (3,); cylinder: (radius, length); sphere: (radius,) [m].
        support: the stack stands on it (a box or a cylinder): the floor's rule (not checked
            against the standing plates nor the first ``leg.node_zone`` of a leg from its
            joint on one).
    """

    kind: str
    name: str
    pose: pin.SE3
    size: tuple[float, ...]
    support: bool = False

    def bounding_capsule(self) -> tuple[np.ndarray, np.ndarray, float]:
        """A capsule holding the obstacle: start (3,), start→end vector (3,) world [m] and
        radius [m] (a box: along its longest edge, the half-diagonal of the other two)."""
        R, p = self.pose.rotation, self.pose.translation
        if self.kind == "sphere":
            return p.copy(), np.zeros(3), self.size[0]
        if self.kind == "cylinder":
            axis, half, radius = R[:, 2], 0.5 * self.size[1], self.size[0]
        else:
            i = int(np.argmax(self.size))
            axis, half = R[:, i], 0.5 * self.size[i]
            radius = 0.5 * math.hypot(*(s for k, s in enumerate(self.size) if k != i))
        return p - half * axis, 2.0 * half * axis, radius


@dataclass(frozen=True)
class Scene:
    """Obstacles and an optional horizontal floor, world frame.

    Attributes:
        obstacles: the fixed bodies.
        floor_z: height of the floor [m], or None for no floor.
        standing: the plates that stand on the floor by design (plate indices of the stack
            checked): they are not checked against the floor, nor is the first
            ``leg.node_zone`` of a leg from its joint on one of them. ``(0,)``, the base plate,
            unless a walk's foot lands or lifts off (:func:`~assembler_pin.walk.plan_walk`).
            Not a key of the file.
    """

    obstacles: tuple[Obstacle, ...] = field(default_factory=tuple)
    floor_z: float | None = None
    standing: tuple[int, ...] = (0,)

    def __post_init__(self) -> None:
        if not isinstance(self.standing, tuple) or not all(
            isinstance(k, int) and not isinstance(k, bool) and 0 <= k <= 1024 for k in self.standing
        ):
            raise SceneError(f"scene standing must be a tuple of plate indices, got {short_repr(self.standing)}")


def _number(value: Any, where: str, low: float = -MAX_SIZE, high: float = MAX_SIZE, positive: bool = False) -> float:
    x = finite_float(value)  # None for an integer too large for a float, as for NaN
    if x is None:
        raise SceneError(shorten(f"scene {where} = {short_repr(value)} is invalid: must be a finite number"))
    if not low <= x <= high or (positive and x <= 0):
        bound = f"in (0, {high:g}]" if positive else f"in [{low:g}, {high:g}]"
        raise SceneError(shorten(f"scene {where} = {short_repr(value)} is invalid: must be {bound} [m]"))
    return x


def _vector(value: Any, where: str, count: int, positive: bool = False) -> list[float]:
    if not isinstance(value, (list, tuple)) or len(value) != count:
        raise SceneError(shorten(f"scene {where} = {short_repr(value)} is invalid: must be a list of {count} numbers"))
    return [_number(v, f"{where}[{i}]", positive=positive) for i, v in enumerate(value)]


def _keys(data: Any, where: str, required: tuple[str, ...], optional: tuple[str, ...] = ()) -> Mapping:
    if not isinstance(data, Mapping):
        raise SceneError(shorten(f"scene {where} must be a mapping, got {short_repr(data)}"))
    allowed = required + optional
    for key in data:
        if key not in allowed:
            raise SceneError(unknown_key(key, allowed, "scene key", f"{where}.", "docs/guides/collisions.md"))
    for key in required:
        if key not in data:
            raise SceneError(f"scene {where} needs '{key}'")
    return data


def _pose(value: Any, where: str) -> pin.SE3:
    v = _vector(value, where, 6)
    rotvec = np.array(v[3:])
    if np.linalg.norm(rotvec) > 100.0:
        raise SceneError(
            shorten(f"scene {where} rotation vector {short_repr(v[3:])} is invalid: must be at most 100 rad")
        )
    return pin.SE3(pin.exp3(rotvec), np.array(v[:3]))


def _obstacle(entry: Any, index: int) -> Obstacle:
    where = f"obstacles[{index}]"
    if not isinstance(entry, Mapping):
        raise SceneError(shorten(f"scene {where} must be a mapping with one of {', '.join(_KINDS)}"))
    kinds = [k for k in entry if k in _KINDS]
    if len(kinds) != 1:
        raise SceneError(
            shorten(f"scene {where} must have exactly one of {', '.join(_KINDS)}, got {short_repr(list(entry))}")
        )
    kind = kinds[0]
    _keys(entry, where, (kind,), ("name", "support"))
    support = entry.get("support", False)
    if not isinstance(support, bool) or (support and kind == "sphere"):
        allowed = "true or false" if kind != "sphere" else "not allowed on a sphere (a box or a cylinder)"
        raise SceneError(shorten(f"scene {where}.support = {short_repr(support)} is invalid: {allowed}"))
    name = entry.get("name", f"{kind} {index}")
    if not isinstance(name, str) or not name.strip() or len(name) > MAX_NAME or not name.isprintable():
        raise SceneError(
            shorten(f"scene {where}.name = {short_repr(name)} is invalid: 1 to {MAX_NAME} printable characters")
        )
    body = entry[kind]
    at = f"{where}.{kind}"
    if kind == "box":
        _keys(body, at, ("size", "pose"))
        size3 = tuple(_vector(body["size"], f"{at}.size", 3, True))
        return Obstacle(kind, name, _pose(body["pose"], f"{at}.pose"), size3, support)
    if kind == "cylinder":
        _keys(body, at, ("radius", "length", "pose"))
        size = (
            _number(body["radius"], f"{at}.radius", positive=True),
            _number(body["length"], f"{at}.length", positive=True),
        )
        return Obstacle(kind, name, _pose(body["pose"], f"{at}.pose"), size, support)
    _keys(body, at, ("radius", "center"))
    centre = np.array(_vector(body["center"], f"{at}.center", 3))
    return Obstacle(kind, name, pin.SE3(np.eye(3), centre), (_number(body["radius"], f"{at}.radius", positive=True),))


def scene_from_dict(data: Any) -> Scene:
    """A :class:`Scene` from a mapping in the file's layout.

    Raises:
        SceneError: unknown keys, wrong types, values out of range or too many obstacles.
    """
    if data is None:
        return Scene()
    doc = _keys(data, "file", (), ("obstacles", "floor"))
    floor_z = None
    if "floor" in doc:
        floor_z = _number(_keys(doc["floor"], "floor", ("z",))["z"], "floor.z")
    entries = doc.get("obstacles", [])
    if entries is None:
        entries = []
    if not isinstance(entries, list):
        raise SceneError(shorten(f"scene obstacles must be a list, got {short_repr(entries)}"))
    if len(entries) > MAX_OBSTACLES:
        raise SceneError(f"scene has {len(entries)} obstacles; at most {MAX_OBSTACLES} are allowed")
    obstacles = tuple(_obstacle(e, i) for i, e in enumerate(entries))
    names = [o.name for o in obstacles]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise SceneError(shorten(f"scene obstacle name {short_repr(dup)} is given twice"))
    return Scene(obstacles, floor_z)


def read_scene(path: str | Path | Mapping[str, Any] | Scene | None) -> Scene | None:
    """Read a scene file (or take a mapping, a :class:`Scene` or None as is).

    Raises:
        SceneError: one line naming the file and the entry: unreadable, not YAML, or invalid.
    """
    if path is None or isinstance(path, Scene):
        return path
    if isinstance(path, Mapping):
        return scene_from_dict(path)
    if not isinstance(path, (str, Path)):
        raise SceneError(f"a scene must be a YAML path, a mapping, a Scene or None, got {short_repr(path)}")
    if not str(path):
        raise SceneError("a scene file path must not be empty")
    shown = shorten(Path(path).name, 40)
    text = read_text_file(Path(path), shown, "scene file", MAX_SCENE_BYTES, SceneError, "scene.bytes")
    try:  # a list longer than the obstacle bound stops the read at its next item
        data = load_yaml(
            text, f"scene file '{shown}'", MAX_OBSTACLES, f" (a scene holds at most {MAX_OBSTACLES} obstacles)"
        )
    except ConfigError as exc:
        raise SceneError(str(exc)) from None
    try:
        return scene_from_dict(data)
    except SceneError as exc:
        message = f"{shown}: {exc}"
        raise SceneError(message if len(message) <= 200 else shorten(str(exc))) from None
