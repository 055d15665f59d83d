"""Map grids: EE positions × orientations (× configurations), each cell with a stable id.

A grid SPEC names each world axis as ``AXIS=VALUE`` or ``AXIS=START:STOP:COUNT`` (both ends
included), separated by commas, e.g. ``x=0.2:0.7:10,y=0,z=0.5:1.0:10`` [m]. Orientations
are rotation vectors ``RX RY RZ`` [deg], separated by ``;`` (default: level, ``0 0 0``).
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import GridError

__all__ = ["Cell", "Grid", "GridError", "parse_grid", "parse_orientations"]

_AXES = ("x", "y", "z")
MAX_CELLS = 10_000_000
"""Largest grid accepted (cells)."""


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
    """Axis values [m] and orientations [rad] of a map (see the module docstring)."""

    x: tuple[float, ...]
    y: tuple[float, ...]
    z: tuple[float, ...]
    orientations: tuple[tuple[float, float, float], ...] = ((0.0, 0.0, 0.0),)

    @property
    def shape(self) -> tuple[int, int, int, int]:
        return (len(self.x), len(self.y), len(self.z), len(self.orientations))

    def __len__(self) -> int:
        return int(np.prod(self.shape))

    def cells(self) -> list[Cell]:
        """Every cell, ids in C order of (x, y, z, orientation)."""
        out = []
        for k, (ix, iy, iz, io) in enumerate(itertools.product(*(range(s) for s in self.shape))):
            out.append(Cell(k, (ix, iy, iz, io), (self.x[ix], self.y[iy], self.z[iz]), self.orientations[io]))
        return out

    def varying_axes(self) -> list[str]:
        """The position axes with more than one value."""
        return [a for a in _AXES if len(getattr(self, a)) > 1]


def _axis_values(axis: str, text: str) -> tuple[float, ...]:
    parts = text.split(":")
    try:
        if len(parts) == 1:
            return (float(parts[0]),)
        if len(parts) == 3:
            start, stop, count = float(parts[0]), float(parts[1]), int(parts[2])
            if count < 1:
                raise ValueError
            return tuple(float(v) for v in np.linspace(start, stop, count))
    except ValueError:
        pass
    raise GridError(f"grid axis {axis}: '{text}' is not VALUE or START:STOP:COUNT (COUNT an integer >= 1)")


def parse_grid(spec: str, orientations: str | None = None) -> Grid:
    """A :class:`Grid` from a SPEC such as ``x=0.2:0.7:10,y=0,z=0.5:1.0:10`` (axes left out
    are 0) and optional orientations ``"0 0 0; 0 30 0"`` [deg].

    Raises:
        GridError: naming what is wrong and what is allowed.
    """
    values: dict[str, tuple[float, ...]] = {}
    for item in filter(None, (p.strip() for p in str(spec).split(","))):
        m = re.fullmatch(r"([a-zA-Z]+)\s*=\s*(\S+)", item)
        if m is None or m.group(1).lower() not in _AXES:
            raise GridError(f"grid item '{item}' is not AXIS=VALUE or AXIS=START:STOP:COUNT with AXIS in x, y, z")
        axis = m.group(1).lower()
        if axis in values:
            raise GridError(f"grid axis {axis} given twice")
        values[axis] = _axis_values(axis, m.group(2))
    if not values:
        raise GridError("empty grid: give e.g. x=0.2:0.7:10,y=0,z=0.5:1.0:10")
    vals = [v for vs in values.values() for v in vs]
    if not np.all(np.isfinite(vals)):
        raise GridError("grid values must be finite numbers [m]")
    grid = Grid(*(values.get(a, (0.0,)) for a in _AXES), parse_orientations(orientations))
    if len(grid) > MAX_CELLS:
        raise GridError(f"the grid has {len(grid)} cells; at most {MAX_CELLS} are allowed")
    return grid


def parse_orientations(text: str | None) -> tuple[tuple[float, float, float], ...]:
    """Rotation vectors [rad] from ``"RX RY RZ; RX RY RZ"`` in degrees (default level)."""
    if text is None or not str(text).strip():
        return ((0.0, 0.0, 0.0),)
    out = []
    for item in filter(None, (p.strip() for p in str(text).split(";"))):
        try:
            rv = [float(v) for v in item.replace(",", " ").split()]
        except ValueError:
            rv = []
        if len(rv) != 3 or not np.all(np.isfinite(rv)):
            raise GridError(f"orientation '{item}' is not three numbers RX RY RZ (rotation vector, degrees)")
        out.append(tuple(float(v) for v in np.deg2rad(rv)))
    return tuple(out)
