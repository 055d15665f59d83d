"""The answer of the statics: :class:`StaticsResult`, one equilibrium of a pose."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["StaticsResult"]


@dataclass(frozen=True)
class StaticsResult:
    """Static equilibrium of a pose.

    Attributes:
        forces: (n, 6) axial actuator forces [N], tension positive (the paper's sign).
        ball_forces: (n, 6, 3) force the top plate exerts on each shaft tip at the ball
            joint, world axes [N].
        base_wrench: (6,) wrench ``[f, m]`` the base mount applies to plate 0, world
            axes, moment about plate 0's origin [N, N·m].
        condition: (n,) 1-norm condition number of each platform's statics block.
        singular: True when a block's condition number exceeds
            :data:`~assembler_pin.statics.closed_form.CONDITION_LIMIT`
            (the forces are then not trustworthy).
    """

    forces: np.ndarray
    ball_forces: np.ndarray
    base_wrench: np.ndarray
    condition: np.ndarray
    singular: bool

    @property
    def max_abs_force(self) -> float:
        return float(np.abs(self.forces).max())

    @property
    def mean_abs_force(self) -> float:
        return float(np.abs(self.forces).mean())

    def __repr__(self) -> str:
        n = self.forces.shape[0]
        return (
            f"StaticsResult({n} platforms, max|F| {self.max_abs_force:.3f} N, mean|F| {self.mean_abs_force:.3f} N, "
            f"base force {np.round(self.base_wrench[:3], 3).tolist()} N, worst condition "
            f"{float(np.max(self.condition)):.3g}{', SINGULAR' if self.singular else ''})"
        )
