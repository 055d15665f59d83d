"""The clearance between two poses of a motion: a conservative bound from the two ends.

Every body of the stack is a segment with a radius (a leg's motor and shaft) or a flat
cylinder (a plate). From one pose to another a leg's axis moves, in the Hausdorff distance,
by at most the largest move of its joint centres and its motor's end (each of its two
segments is the convex hull of its ends), and a plate by at most ``|Δp| + ρ θ`` (``θ`` the
angle of its rotation, ``ρ`` its rim's distance from its centre): :func:`body_moves`.
Obstacles and the floor do not move.

The distance of two bodies ``a`` and ``b`` changes by at most the sum of their moves. Along a
motion from pose A to pose B in which each body moves by at most its move from A to B (the
move from A to an intermediate pose and from there to B add up to no more than the chord),
the pair's distance at any intermediate pose is at least ``d_A − x`` and at least
``d_B − (m_a + m_b − x)`` for some ``x``, so at least their mean::

    d(t) >= (d_A + d_B − m_a − m_b) / 2

and the clearance is at least the smallest of these over the pairs (:func:`swept_bound`). The
planner bisects (stack FK of the midpoint lengths) where the bound is below the clearance,
so what the chord assumption leaves out is of second order in the step.

Frames: world; lengths [m]; angles [rad].
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..kinematics import PlateArrays
from ..kinematics.legs import leg_points
from ..model.assembler import AssemblerModel
from .check import Clearance, physical_bodies

__all__ = ["body_moves", "swept_bound"]


def _ends(am: AssemblerModel, pa: PlateArrays) -> np.ndarray:
    """(3, 6n, 3): every leg's bottom joint centre, motor end and top joint centre."""
    bottom, top = leg_points(am.geometry, pa.R, pa.p)
    bottom, top = bottom.reshape(-1, 3), top.reshape(-1, 3)
    u = top - bottom
    u /= np.maximum(np.linalg.norm(u, axis=1), 1e-300)[:, None]
    return np.stack([bottom, bottom + am.config.leg.motor_length * u, top])


def body_moves(
    am: AssemblerModel, a: PlateArrays | Sequence | np.ndarray, b: PlateArrays | Sequence | np.ndarray
) -> np.ndarray:
    """The move [m] of every body of the stack from pose ``a`` to pose ``b``: (7n+1,) in the
    order of :func:`~assembler_pin.collision.bodies.stack_body_names` (legs ``6 j + i``, then
    plates 0..n), each the Hausdorff distance of its axis segments or of its cylinder."""
    model, pa = physical_bodies(am, a)
    _, pb = physical_bodies(am, b)
    legs = np.linalg.norm(_ends(model, pa) - _ends(model, pb), axis=2).max(axis=0)
    plate = model.config.plate
    rho = math.hypot(plate.radius, 0.5 * plate.thickness)
    turn = np.einsum("kji,kjl->kil", pa.R, pb.R)  # R_a^T R_b
    cos = np.clip((np.trace(turn, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    plates = np.linalg.norm(pb.p - pa.p, axis=1) + rho * np.arccos(cos)
    return np.concatenate([legs, plates])


def swept_bound(a: Clearance, b: Clearance, moves: np.ndarray) -> float:
    """A lower bound [m] of the clearance along a motion from a pose of clearance ``a`` to one of
    clearance ``b`` (the same pairs, the same scene), the stack's bodies moving by ``moves``
    (:func:`body_moves`): the smallest ``(d_A + d_B − m_a − m_b) / 2`` over the pairs
    (module doc); ``inf`` when no pair is checked.

    Raises:
        ValueError: the two clearances do not hold the same pairs.
    """
    if a.pairs.shape != b.pairs.shape or not np.array_equal(a.pairs, b.pairs):
        raise ValueError("the two clearances must hold the same pairs (one scene, one stack)")
    if not len(a.distances):
        return math.inf
    m = np.zeros(len(a.names))
    m[: len(moves)] = moves
    bound = 0.5 * (a.distances + b.distances - m[a.pairs[:, 0]] - m[a.pairs[:, 1]])
    return float(bound.min())
