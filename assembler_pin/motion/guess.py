"""Valid starting poses for stack FK: plate rotations projected onto SO(3).

Stack FK started from the previous sample's plates repeats a product of rotations; rounding
leaves each product a little off SO(3), and Newton's method on the leg lengths does not
restore orthonormality (it acts by left-multiplying with exact rotations, which keeps
``RᵀR``). Over thousands of chained samples the error compounds into a pose that matches
the lengths with a skewed rotation (micrometres to millimetres off the true pose). Every FK
guess in :mod:`assembler_pin.motion` goes through :func:`on_se3` first.
"""

from __future__ import annotations

import numpy as np

from ..kinematics import PlateArrays, nearest_rotations

__all__ = ["on_se3"]


def on_se3(plates: PlateArrays) -> PlateArrays:
    """The same plate poses with every rotation projected onto SO(3) (a new object)."""
    return PlateArrays(nearest_rotations(np.asarray(plates.R, dtype=float)), np.array(plates.p, dtype=float))
