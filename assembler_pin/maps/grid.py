"""Map grids: EE positions × orientations (× configurations), each cell with a stable id.

A grid SPEC names each world axis as ``AXIS=VALUE`` or ``AXIS=START:STOP:COUNT`` (both ends
included), separated by commas, e.g. ``x=0.2:0.7:10,y=0,z=0.5:1.0:10`` [m]. Orientations
are rotation vectors ``RX RY RZ`` [deg], separated by ``;`` (default: level, ``0 0 0``).

The readers are strict: numbers are plain ASCII decimals (``0.25``, ``-1e-3``; no ``nan``,
``inf``, ``1_000`` or non-ASCII digits), a COUNT is a plain integer, every item is given once
and no item is empty. Counts are checked against :data:`~assembler_pin.config.bounds.BOUNDS`
(``map.axis_count``, ``map.orientations``, ``map.cells``) from the SPEC's numbers, before
any axis array is built.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..config.bounds import BOUNDS, check_bound
from ..config.numbers import finite_float
from ..exceptions import GridError, short_repr

__all__ = ["Cell", "Grid", "parse_grid", "parse_orientations"]

_AXES = ("x", "y", "z")
MAX_CELLS = int(BOUNDS["map.cells"].high)
"""Largest map accepted (cells, over every orientation and configuration)."""
MAX_POSITION = 1000.0
"""Largest |coordinate| of a grid point [m]: far beyond any stack, small enough for exact solves."""
MAX_ROTATION_DEG = 360.0
"""Largest rotation-vector norm of an orientation [deg]."""
_SPEC_CHARS = 100_000
"""Longest SPEC text read (characters); longer ones cannot be within the bounds."""
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
_COUNT = re.compile(r"\+?\d{1,30}", re.ASCII)
_ITEM = re.compile(r"\s*([A-Za-z]+)\s*=\s*([^\s=]+)\s*", re.ASCII)


@dataclass(frozen=True)
class Cell:
    """One EE goal of a map: its id, indices, position [m] and rotation vector [rad]."""

    id: int
    index: tuple[int, int, int, int]
    position: tuple[float, float, float]
    rotation: tuple[float, float, float]

    def goal(self) -> pin.SE3:
        return pin.SE3(pin.exp3(np.array(self.rotation)), np.array(self.position))


@dataclass(frozen=True)
class Grid:
    """Axis values [m] and orientations [rad] of a map (see the module docstring).

    Raises:
        GridError: an axis or the orientations are empty, too long, not finite numbers, or
            the grid has more than :data:`MAX_CELLS` cells.
    """

    x: tuple[float, ...]
    y: tuple[float, ...]
    z: tuple[float, ...]
    orientations: tuple[tuple[float, float, float], ...] = ((0.0, 0.0, 0.0),)

    def __post_init__(self) -> None:
        for axis in _AXES:
            values = _float_tuple(getattr(self, axis), f"grid axis {axis}")
            check_bound("map.axis_count", len(values), f"grid axis {axis}: the number of values", GridError)
            if max(abs(v) for v in values) > MAX_POSITION:
                raise GridError(f"grid axis {axis}: values must be within ±{MAX_POSITION:g} m")
            object.__setattr__(self, axis, values)
        if not isinstance(self.orientations, (tuple, list)):
            raise GridError("grid orientations must be a sequence of rotation vectors (rx, ry, rz) [rad]")
        check_bound("map.orientations", len(self.orientations), "the number of orientations", GridError)
        rots = tuple(_float_tuple(r, "grid orientation", 3) for r in self.orientations)
        if any(math.degrees(math.hypot(*r)) > MAX_ROTATION_DEG + 1e-9 for r in rots):
            raise GridError(f"grid orientations must be rotation vectors of at most {MAX_ROTATION_DEG:g}°")
        object.__setattr__(self, "orientations", rots)
        check_bound("map.cells", math.prod(self.shape), "the grid's number of cells", GridError)

    @property
    def shape(self) -> tuple[int, int, int, int]:
        return (len(self.x), len(self.y), len(self.z), len(self.orientations))

    def __len__(self) -> int:
        return math.prod(self.shape)

    def cell(self, k: int) -> Cell:
        """The cell of id ``k`` (C order of (x, y, z, orientation))."""
        if not 0 <= k < len(self):
            raise GridError(f"cell id {k} is outside the grid's {len(self)} cells")
        ix, iy, iz, io = (int(i) for i in np.unravel_index(k, self.shape))
        return Cell(k, (ix, iy, iz, io), (self.x[ix], self.y[iy], self.z[iz]), self.orientations[io])

    def iter_cells(self) -> Iterator[Cell]:
        """Every cell, ids in C order of (x, y, z, orientation), one at a time."""
        for k, (ix, iy, iz, io) in enumerate(itertools.product(*(range(s) for s in self.shape))):
            yield Cell(k, (ix, iy, iz, io), (self.x[ix], self.y[iy], self.z[iz]), self.orientations[io])

    def cells(self) -> list[Cell]:
        """Every cell, ids in C order of (x, y, z, orientation)."""
        return list(self.iter_cells())

    def varying_axes(self) -> list[str]:
        """The position axes with more than one value."""
        return [a for a in _AXES if len(getattr(self, a)) > 1]


def _float_tuple(values: object, what: str, size: int | None = None) -> tuple[float, ...]:
    """``values`` as a tuple of finite floats (not bools), else a GridError naming ``what``."""
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or not hasattr(values, "__iter__"):
        raise GridError(f"{what} must be a sequence of numbers, got {type(values).__name__}")
    if size is not None and len(values) != size:
        raise GridError(f"{what} must have {size} numbers, got {len(values)}")
    out = []
    for v in values:
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
            raise GridError(f"{what} must hold numbers, got {type(v).__name__}")
        x = finite_float(v)  # None for an integer too large for a float, as for NaN
        if x is None:
            raise GridError(f"{what} must hold finite numbers, got {short_repr(v, 40)}")
        out.append(x)
    if not out:
        raise GridError(f"{what} is empty")
    return tuple(out)


def _number(text: str, what: str) -> float:
    """A finite ASCII decimal number, else a GridError naming ``what``."""
    if _NUMBER.fullmatch(text) is None:
        raise GridError(f"{what}: {_shown(text)} is not a number (plain decimal such as 0.25 or -1e-3)")
    value = float(text)
    if not math.isfinite(value):
        raise GridError(f"{what}: {_shown(text)} is not a finite number")
    return value


def _shown(text: str) -> str:
    """``text`` quoted for a message, escapes included, in at most 32 characters."""
    shown = repr(text)
    return shown if len(shown) <= 32 else shown[:28] + "..." + shown[0]


def _axis_spec(axis: str, text: str) -> tuple[float, float, int]:
    """(start, stop, count) of one axis item, the count checked against ``map.axis_count``."""
    parts = text.split(":")
    if len(parts) == 1:
        value = _number(parts[0], f"grid axis {axis}")
        return value, value, 1
    if len(parts) != 3:
        raise GridError(f"grid axis {axis}: {_shown(text)} is not VALUE or START:STOP:COUNT")
    start, stop = _number(parts[0], f"grid axis {axis} START"), _number(parts[1], f"grid axis {axis} STOP")
    if _COUNT.fullmatch(parts[2]) is None:
        raise GridError(f"grid axis {axis}: COUNT {_shown(parts[2])} is not an integer >= 1 (START:STOP:COUNT)")
    count = int(parts[2])
    check_bound("map.axis_count", count, f"grid axis {axis} COUNT", GridError)
    if count > 1 and start == stop:
        raise GridError(f"grid axis {axis}: START equals STOP, so COUNT must be 1 (got {count})")
    for value in (start, stop):
        if abs(value) > MAX_POSITION:
            raise GridError(f"grid axis {axis}: values must be within ±{MAX_POSITION:g} m, got {value:g}")
    return start, stop, count


def _split(text: str, sep: str, what: str, example: str) -> list[str]:
    """The items of a SPEC, refusing empty ones (``a,,b``, a trailing separator)."""
    items = [p.strip() for p in text.split(sep)]
    if any(not p for p in items):
        raise GridError(f"{what}: an empty item (separate items with one '{sep}', e.g. {example})")
    return items


def parse_grid(spec: str, orientations: str | None = None, configs: int = 1) -> Grid:
    """A :class:`Grid` from a SPEC such as ``x=0.2:0.7:10,y=0,z=0.5:1.0:10`` (axes left out
    are 0) and optional orientations ``"0 0 0; 0 30 0"`` [deg].

    Args:
        configs: how many configurations the map covers (the ``map.cells`` bound counts them).

    Raises:
        GridError: naming what is wrong and what is allowed.
    """
    example = "x=0.2:0.7:10,y=0,z=0.5:1.0:10"
    if not isinstance(spec, str):
        raise GridError(f"the grid SPEC must be text such as {example}, got {type(spec).__name__}")
    if not spec.strip():
        raise GridError(f"empty grid: give e.g. {example}")
    if len(spec) > _SPEC_CHARS:
        raise GridError(f"the grid SPEC must be a short text such as {example}")
    specs: dict[str, tuple[float, float, int]] = {}
    for item in _split(spec, ",", "grid", example):
        m = _ITEM.fullmatch(item)
        if m is None or m.group(1).lower() not in _AXES:
            raise GridError(f"grid item {_shown(item)} is not AXIS=VALUE or AXIS=START:STOP:COUNT with AXIS in x, y, z")
        axis = m.group(1).lower()
        if axis in specs:
            raise GridError(f"grid axis {axis} given twice")
        specs[axis] = _axis_spec(axis, m.group(2))
    n_rot = _orientation_count(orientations)
    cells = math.prod(specs[a][2] if a in specs else 1 for a in _AXES) * n_rot * max(int(configs), 1)
    check_bound("map.cells", cells, "the map's number of cells (grid points x orientations x configs)", GridError)
    values = {a: tuple(float(v) for v in np.linspace(*specs[a])) if a in specs else (0.0,) for a in _AXES}
    return Grid(values["x"], values["y"], values["z"], parse_orientations(orientations))


def _orientation_count(text: str | None) -> int:
    """How many orientations a SPEC names, checked against ``map.orientations`` before parsing."""
    if text is None:
        return 1
    if not isinstance(text, str):
        raise GridError(f"the orientations must be text such as '0 0 0; 0 30 0', got {type(text).__name__}")
    if len(text) > _SPEC_CHARS:
        raise GridError("the orientations SPEC is too long to be within map.orientations")
    count = text.count(";") + 1 if text.strip() else 1
    check_bound("map.orientations", count, "the number of orientations", GridError)
    return count


def parse_orientations(text: str | None) -> tuple[tuple[float, float, float], ...]:
    """Rotation vectors [rad] from ``"RX RY RZ; RX RY RZ"`` in degrees (default level).

    Raises:
        GridError: an item that is not three finite numbers, a rotation of more than
            :data:`MAX_ROTATION_DEG`, an orientation given twice, or an empty item.
    """
    _orientation_count(text)
    if text is None or not text.strip():
        return ((0.0, 0.0, 0.0),)
    out: list[tuple[float, float, float]] = []
    for item in _split(text, ";", "orientations", "'0 0 0; 0 30 0'"):
        fields = item.replace(",", " ").split()
        if len(fields) != 3:
            raise GridError(f"orientation {_shown(item)} is not three numbers RX RY RZ (rotation vector, degrees)")
        rv = [_number(f, f"orientation {_shown(item)}") for f in fields]
        if math.hypot(*rv) > MAX_ROTATION_DEG:
            raise GridError(f"orientation {_shown(item)}: a rotation of at most {MAX_ROTATION_DEG:g}° is allowed")
        rot = (math.radians(rv[0]), math.radians(rv[1]), math.radians(rv[2]))
        if rot in out:
            raise GridError(f"orientation {_shown(item)} given twice")
        out.append(rot)
    return tuple(out)
