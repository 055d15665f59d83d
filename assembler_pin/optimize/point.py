"""One point of the optimizer: the closed-form values at a chart point, and their
derivatives in chart coordinates (from the same pass, only where the solver asks)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..kinematics import PlateArrays
from ..statics.derivatives import PoseDerivatives, PoseValues
from ..statics.pose_kernel import PoseMeasures

__all__ = ["SINGULAR_FORCE", "ChartDerivatives", "Point", "block_chart"]

#: Forces [N] standing in for the statics at a singular trial point: finite (SLSQP cannot
#: handle NaN) and far outside every force limit, so such a step is infeasible.
SINGULAR_FORCE = 1e6


@dataclass(frozen=True)
class Point:
    """The values at the pose part ``x`` of a decision vector.

    Attributes:
        x: the chart coordinates of the movable plates.
        values: the closed-form pass (:func:`~assembler_pin.statics.derivatives.pose_values`, or its
            compiled twin :meth:`~assembler_pin.statics.pose_kernel.CompiledPass.values`).
        forces: (n, 6) actuator forces [N, tension positive], :data:`SINGULAR_FORCE` where
            the statics are not defined.
    """

    x: np.ndarray
    values: PoseValues | PoseMeasures

    @cached_property
    def forces(self) -> np.ndarray:
        f = self.values.forces
        return np.where(np.isfinite(f), f, SINGULAR_FORCE)

    @property
    def singular(self) -> bool:
        """Some platform's statics are not defined here."""
        return not bool(np.all(np.isfinite(self.values.forces)))

    @property
    def plates(self) -> PlateArrays:
        return self.values.plates

    @property
    def lengths(self) -> np.ndarray:
        """(n, 6) leg lengths [m]."""
        return self.values.lengths

    @property
    def plate_angles(self) -> np.ndarray:
        """(n,) λ_k [rad]."""
        return self.values.plate_angles

    @property
    def max_abs_force(self) -> float:
        return float(np.abs(self.forces).max())


def block_chart(rows: np.ndarray, blocks: np.ndarray, plates: np.ndarray) -> np.ndarray:
    """Rows (r, 6n) per world twist of plates 1..n → (r, 6·len(plates)) per chart coordinate
    of a block-diagonal chart: the columns of each movable plate (``plates``: its index,
    0 for plate 1) times its 6×6 block (``blocks`` (len(plates), 6, 6))."""
    per_plate = rows.reshape(rows.shape[0], -1, 6)[:, plates, :].transpose(1, 0, 2)  # (movable, rows, 6)
    return np.matmul(per_plate, blocks).transpose(1, 0, 2).reshape(rows.shape[0], -1)


@dataclass(frozen=True)
class ChartDerivatives:
    """Derivatives at a :class:`Point`, in chart coordinates.

    Attributes:
        pose: the derivatives w.r.t. the world twists of plates 1..n
            (:func:`~assembler_pin.statics.derivatives.pose_derivatives`, last axis 6n).
        B: (6n, m) the world twists of plates 1..n per chart coordinate.
        blocks: where ``B`` is block diagonal (the local chart), the index (0 for plate 1)
            of each movable plate: then :meth:`chart` multiplies the 6×6 blocks alone
            (O(6n·m·6) instead of O(6n·m·6n) per row); None: the dense product.
    """

    pose: PoseDerivatives
    B: np.ndarray
    blocks: np.ndarray | None = None

    def chart(self, d: np.ndarray) -> np.ndarray:
        """``d`` (..., 6n) as rows (prod(...), m) per chart coordinate."""
        rows = d.reshape(-1, self.B.shape[0])
        if self.blocks is None:
            return rows @ self.B
        k = self.blocks
        return block_chart(rows, self.B.reshape(-1, 6, len(k), 6)[k, :, np.arange(len(k)), :], k)

    @cached_property
    def forces(self) -> np.ndarray:
        """(6n, m) d(forces) [N per chart unit], rows in the order of ``forces.ravel()``."""
        return self.chart(self.pose.d_forces)

    @cached_property
    def lengths(self) -> np.ndarray:
        """(6n, m) d(leg lengths)."""
        return self.chart(self.pose.d_lengths)

    @cached_property
    def plate_angles_sq(self) -> np.ndarray:
        """(n, m) d(λ_k²)."""
        return self.chart(self.pose.d_plate_angles_sq)
