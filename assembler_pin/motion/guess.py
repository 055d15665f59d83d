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
import pinocchio as pin

from ..kinematics import PlateArrays, nearest_rotations

__all__ = ["nearest_rotations", "on_se3", "spread_start"]


def on_se3(plates: PlateArrays) -> PlateArrays:
    """The same plate poses with every rotation projected onto SO(3) (a new object)."""
    return PlateArrays(nearest_rotations(np.asarray(plates.R, dtype=float)), np.array(plates.p, dtype=float))


def spread_start(plates: PlateArrays, goal: pin.SE3) -> PlateArrays:
    """A start for the next sample of a motion: the previous sample's plates with the EE's
    move to ``goal`` shared evenly by the platforms.

    With ``ξ = log6(goal · T_n⁻¹)`` the EE's move in the world frame (``T_n`` the previous
    EE pose), plate k goes to ``exp6(k/n · ξ) · T_k``: every platform moves by the same
    relative transform, plate 0 stays, plate n lands on ``goal``. Rotations on SO(3).
    """
    n = len(plates.R) - 1
    xi = pin.log6(goal * plates.se3(n).inverse())
    R, p = nearest_rotations(np.asarray(plates.R, dtype=float)), np.array(plates.p, dtype=float)
    for k in range(1, n + 1):
        moved = pin.exp6(xi * (k / n)) * pin.SE3(R[k], p[k])
        R[k], p[k] = moved.rotation, moved.translation
    R[n], p[n] = goal.rotation, goal.translation
    return PlateArrays(R, p)
