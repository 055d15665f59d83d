"""The leg state of one stack pose in one compiled call.

:func:`compiled_leg_arrays` gives the arrays of the :class:`~assembler_pin.kinematics.legs.LegState` that the
numpy functions of :mod:`~assembler_pin.kinematics.legs` compose (joint centres, lengths,
directions in the world and in both plates, deflections, rise), from one loop over the 6n legs
compiled by numba (``cache=True``: compiled once per install, then loaded from numba's cache).
The tests hold it to the numpy composition to 1e-12.

Frames: world poses of plates 0..n; lengths [m]; angles [rad].
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..exceptions import PoseError
from ..model.assembler import AssemblerModel
from .poses import PlateArrays

__all__ = ["MIN_LEG_LENGTH", "compiled_leg_arrays"]

_kernel: Any = None  # the compiled loop, once built

#: Shortest pin-to-pin length [m] the leg state accepts (two joint centres apart).
MIN_LEG_LENGTH = 1e-9


def _legs_py(
    R, p, bottom_in, top_in, home, bottom, top, lengths, directions, in_bottom, in_top, deflection, rise
):  # pragma: no cover - compiled
    """Fills the outputs (n, 6, ...) from R (n+1, 3, 3), p (n+1, 3) and the anchors (n, 6, 3);
    returns the shortest length [m]."""
    n = R.shape[0] - 1
    shortest = math.inf
    for j in range(n):
        for i in range(6):
            length_sq = 0.0
            for a in range(3):
                b = p[j, a]
                t = p[j + 1, a]
                for c in range(3):
                    b += R[j, a, c] * bottom_in[j, i, c]
                    t += R[j + 1, a, c] * top_in[j, i, c]
                bottom[j, i, a] = b
                top[j, i, a] = t
                length_sq += (t - b) * (t - b)
            length = math.sqrt(length_sq)
            lengths[j, i] = length
            shortest = min(shortest, length)
            for a in range(3):
                directions[j, i, a] = (top[j, i, a] - bottom[j, i, a]) / length
            cos_b = 0.0
            cos_t = 0.0
            for a in range(3):
                ub = 0.0
                ut = 0.0
                for c in range(3):
                    ub += R[j, c, a] * directions[j, i, c]
                    ut += R[j + 1, c, a] * directions[j, i, c]
                in_bottom[j, i, a] = ub
                in_top[j, i, a] = ut
                cos_b += ub * home[j, i, a]
                cos_t += ut * home[j, i, a]
            deflection[j, i, 0] = math.acos(min(1.0, max(-1.0, cos_b)))
            deflection[j, i, 1] = math.acos(min(1.0, max(-1.0, cos_t)))
            rise[j, i] = in_bottom[j, i, 2] * length
    return shortest


def _compiled() -> Any:
    """The compiled loop (built, or loaded from numba's cache, on first use)."""
    global _kernel
    if _kernel is None:
        import numba  # delayed: numba's import only when a leg state is computed

        _kernel = numba.njit(cache=True, nogil=True)(_legs_py)
    return _kernel


def compiled_leg_arrays(am: AssemblerModel, pa: PlateArrays) -> tuple[np.ndarray, ...]:
    """The fields of the :class:`~assembler_pin.kinematics.legs.LegState` of checked plate
    arrays, in its order: bottom and top joint centres, lengths, directions (world, bottom
    plate, top plate), deflections and rise.

    Raises:
        PoseError: two joint centres of a leg coincide.
    """
    n, geo = am.n, am.geometry
    bottom, top, directions = np.empty((n, 6, 3)), np.empty((n, 6, 3)), np.empty((n, 6, 3))
    in_bottom, in_top = np.empty((n, 6, 3)), np.empty((n, 6, 3))
    lengths, deflection, rise = np.empty((n, 6)), np.empty((n, 6, 2)), np.empty((n, 6))
    R = np.ascontiguousarray(pa.R, dtype=np.float64)
    p = np.ascontiguousarray(pa.p, dtype=np.float64)
    shortest = _compiled()(
        R, p, geo.bottom_in_plate, geo.top_in_plate, geo.home_direction,
        bottom, top, lengths, directions, in_bottom, in_top, deflection, rise,
    )  # fmt: skip
    if not shortest >= MIN_LEG_LENGTH:
        raise PoseError("plate poses put a leg's two joint centres on top of each other")
    return bottom, top, lengths, directions, in_bottom, in_top, deflection, rise
