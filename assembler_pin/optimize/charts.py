"""The two charts of the decision variables: the pose part of x → world plate poses.

Both hold plate 0 and (unless the EE may move) plate n fixed; the *movable* plates are
1..n-1, and n when the user allows an end-effector tolerance.

* :class:`LocalChart` (the smooth method): ``T_k = T_k⁰ · exp6(x_k)``, a twist in plate k's
  own frame around its starting pose.
* :class:`TaaChart` (the paper's formulation): ``x_k = (p_k, rotation vector of R_k)`` in
  the world frame.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..kinematics import PlateArrays

__all__ = ["LocalChart", "TaaChart"]


class _Chart:
    """What both charts share: the reference poses of plates 0..n (also as arrays,
    ``ref_arrays``) and the movable plates."""

    def __init__(self, ref: Sequence[pin.SE3], movable: Sequence[int]) -> None:
        self.ref = list(ref)
        self.ref_arrays = PlateArrays.from_se3(self.ref)
        self.movable = list(movable)
        self.n = len(self.ref) - 1
        self.size = 6 * len(self.movable)

    def slot(self, x: np.ndarray, slot: int) -> np.ndarray:
        """The 6 coordinates of the ``slot``-th movable plate."""
        return x[6 * slot : 6 * slot + 6]


class LocalChart(_Chart):
    """``T_k = T_k⁰ · exp6(x_k)``: a local twist [m, rad] per movable plate."""

    def start(self) -> np.ndarray:
        """The chart point of the reference poses: zero."""
        return np.zeros(self.size)

    def plates(self, x: np.ndarray) -> PlateArrays:
        """World poses of plates 0..n at the chart point ``x``."""
        R, p = self.ref_arrays.R.copy(), self.ref_arrays.p.copy()
        for slot, k in enumerate(self.movable):
            moved = self.ref[k] * pin.exp6(self.slot(x, slot))
            R[k], p[k] = moved.rotation, moved.translation
        return PlateArrays(R, p)

    def twist_blocks(self, x: np.ndarray, plates: PlateArrays) -> np.ndarray:
        """(movable, 6, 6): the world twist of each movable plate per its chart coordinates,
        ``Ad(T_k) · Jexp6(x_k)``."""
        return np.array(
            [
                pin.SE3(plates.R[k], plates.p[k]).action @ pin.Jexp6(self.slot(x, slot))
                for slot, k in enumerate(self.movable)
            ]
        ).reshape(-1, 6, 6)

    def twist_jacobian(self, x: np.ndarray, plates: PlateArrays) -> np.ndarray:
        """B (6n, size): the world twists of plates 1..n per chart coordinate, the
        :meth:`twist_blocks` on the movable plates' blocks, zero elsewhere."""
        B = np.zeros((6 * self.n, self.size))
        for slot, (k, block) in enumerate(zip(self.movable, self.twist_blocks(x, plates), strict=True)):
            B[6 * (k - 1) : 6 * k, 6 * slot : 6 * slot + 6] = block
        return B

    def ee_rotation(self, x: np.ndarray, plates: PlateArrays, goal: pin.SE3) -> np.ndarray:
        """Rotation vector of the EE from the goal [rad]: its chart coordinates (the EE is
        the last movable plate, referenced at the goal)."""
        return x[self.size - 3 : self.size]


class TaaChart(_Chart):
    """``x_k = (p_k, log3(R_k))``: world position [m] and rotation vector [rad] per movable plate."""

    def start(self) -> np.ndarray:
        """The chart point of the reference poses."""
        return np.concatenate(
            [np.concatenate([self.ref[k].translation, pin.log3(self.ref[k].rotation)]) for k in self.movable]
        )

    def plates(self, x: np.ndarray) -> PlateArrays:
        """World poses of plates 0..n at the chart point ``x``."""
        R = np.array([m.rotation for m in self.ref])
        p = np.array([m.translation for m in self.ref])
        for slot, k in enumerate(self.movable):
            p[k] = x[6 * slot : 6 * slot + 3]
            R[k] = pin.exp3(x[6 * slot + 3 : 6 * slot + 6])
        return PlateArrays(R, p)

    def ee_rotation(self, x: np.ndarray, plates: PlateArrays, goal: pin.SE3) -> np.ndarray:
        """Rotation vector of the EE from the goal [rad]."""
        return pin.log3(goal.rotation.T @ plates.R[self.n])
