"""The plate-deviation angle λ_k of paper eq. 9 (world frame, radians)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..common.linalg import cross
from ..model.assembler import AssemblerModel
from .poses import PlateArrays, plate_arrays

__all__ = ["PlateDeviation", "plate_deviation"]


@dataclass(frozen=True)
class PlateDeviation:
    """The plate-deviation angle λ_k of paper eq. 9 and the vectors it is made of.

    Attributes:
        angles: (n,) λ_k, k = 1..n: angle between ``p_k - p_{k-1}`` and plate k's rest
            direction on plate k-1 [rad].
        step_dir: (n, 3) unit ``p_k - p_{k-1}``, world; step_length: (n,) its length [m].
        rest_dir: (n, 3) unit rest direction of plate k on plate k-1, world.
        sin, cos: (n,) sine and cosine of λ_k.
    """

    angles: np.ndarray
    step_dir: np.ndarray
    step_length: np.ndarray
    rest_dir: np.ndarray
    sin: np.ndarray
    cos: np.ndarray


def plate_deviation(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> PlateDeviation:
    """λ_k of every plate (paper eq. 9), the one definition used by the objective and its gradient."""
    pa = plate_arrays(am, plates)
    rest = am.plate_placement_p
    rest_dir = np.matmul(pa.R[:-1], (rest / np.linalg.norm(rest, axis=1, keepdims=True))[..., None])[..., 0]
    step = pa.p[1:] - pa.p[:-1]
    step_length = np.linalg.norm(step, axis=1)
    step_dir = step / step_length[:, None]
    sin = np.linalg.norm(cross(step_dir, rest_dir), axis=1)
    cos = np.einsum("jk,jk->j", step_dir, rest_dir)
    return PlateDeviation(np.arctan2(sin, cos), step_dir, step_length, rest_dir, sin, cos)
