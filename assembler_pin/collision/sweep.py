"""The clearance between two poses of a motion: a conservative bound from the two ends.

Every body of the stack is a segment with a radius (a leg's motor and shaft) or a flat
cylinder (a plate). From one pose to another a leg's axis segment moves, in the Hausdorff
distance, by at most the largest move of its ends (the joint centres and the motor's end:
a segment is the convex hull of its ends), and a plate by at most ``|Δp| + ρ θ`` (``θ`` the
angle of its rotation, ``ρ`` its rim's distance from its centre). A distance between two
bodies changes by at most the sum of their moves (obstacles do not move), so along a motion
from pose A to pose B whose bodies move by at most ``δ`` in all, the clearance stays at least
``(d_A + d_B) / 2 - δ`` (:func:`swept_bound`). This holds where the motion between A and B
does not go further than its chord (the move from A to an intermediate pose and from there
to B add up to the move from A to B); the planner makes it so by bisecting until the bound
holds, so the residual is of second order in the step.

Frames: world; lengths [m]; angles [rad].
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..kinematics import PlateArrays, plate_arrays
from ..kinematics.legs import leg_points
from ..model.assembler import AssemblerModel

__all__ = ["body_move", "swept_bound"]


def _ends(am: AssemblerModel, pa: PlateArrays) -> np.ndarray:
    """(3, 6n, 3): every leg's bottom joint centre, motor end and top joint centre."""
    bottom, top = leg_points(am.geometry, pa.R, pa.p)
    bottom, top = bottom.reshape(-1, 3), top.reshape(-1, 3)
    u = top - bottom
    u /= np.maximum(np.linalg.norm(u, axis=1), 1e-300)[:, None]
    return np.stack([bottom, bottom + am.config.leg.motor_length * u, top])


def body_move(
    am: AssemblerModel, a: PlateArrays | Sequence | np.ndarray, b: PlateArrays | Sequence | np.ndarray
) -> float:
    """The largest move [m] of any body of the stack (legs, plates) from pose ``a`` to pose
    ``b``, in the Hausdorff distance of its axis segments or of its cylinder."""
    pa, pb = plate_arrays(am, a), plate_arrays(am, b)
    legs = float(np.linalg.norm(_ends(am, pa) - _ends(am, pb), axis=2).max()) if am.n else 0.0
    plate = am.config.plate
    rho = math.hypot(plate.radius, 0.5 * plate.thickness)
    turn = np.einsum("kji,kjl->kil", pa.R, pb.R)  # R_a^T R_b
    cos = np.clip((np.trace(turn, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    plates = float((np.linalg.norm(pb.p - pa.p, axis=1) + rho * np.arccos(cos)).max())
    return max(legs, plates)


def swept_bound(d_a: float, d_b: float, move: float) -> float:
    """A lower bound [m] of the clearance along a motion from a pose of clearance ``d_a`` to one
    of clearance ``d_b`` whose bodies move by at most ``move`` (:func:`body_move`)."""
    return 0.5 * (d_a + d_b) - move
