"""The continuity term of a motion (:class:`MotionTerm`); the optimizer's options are
:class:`~assembler_pin.config.options.OptimizeOptions`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config.numbers import finite_float
from ..exceptions import OptionsError, short_repr

__all__ = ["MotionTerm"]


@dataclass(frozen=True)
class MotionTerm:
    """Continuity with the previous sample of a motion.

    Its cost ``w3·Σ (L_i - L_i^prev)²`` is :func:`assembler_pin.optimize.objective.motion_cost`.

    Attributes:
        previous_lengths: (n, 6) leg lengths of the previous sample [m].
        max_step: largest change of any leg length from it [m] (> 0).
        w3: weight of Σ ΔL² in the objective [1/m²] (>= 0).
    """

    previous_lengths: np.ndarray
    max_step: float
    w3: float = 0.0

    def __post_init__(self) -> None:
        if not ((finite_float(self.max_step) or 0.0) > 0):
            raise OptionsError(f"max_step must be a finite number > 0 [m], got {short_repr(self.max_step, 40)}")
        if not (finite_float(self.w3) is not None and self.w3 >= 0):
            raise OptionsError(f"w3 must be a finite number >= 0 [1/m^2], got {short_repr(self.w3, 40)}")
        prev = np.asarray(self.previous_lengths, dtype=float)
        if prev.ndim != 2 or prev.shape[1] != 6 or not np.all(np.isfinite(prev)):
            raise OptionsError(f"previous_lengths must be a finite (n, 6) array [m], got shape {prev.shape}")
        object.__setattr__(self, "previous_lengths", prev)

    def margins(self, lengths: np.ndarray) -> np.ndarray:
        """Rows >= 0 when every leg moved at most ``max_step``: (2·6n,)."""
        step = (lengths - self.previous_lengths).ravel()
        return np.concatenate([self.max_step - step, self.max_step + step])
