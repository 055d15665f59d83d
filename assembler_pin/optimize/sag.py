"""The EE's linear sag at an optimizer point, from the closed-form pass alone.

The same measure as :func:`~assembler_pin.compliance.loaded.sag_and_gradient` (every leg stretched
by ``F / k``, the plates moved by ``y`` with ``A y = F / k``, ``A`` the legs' length
Jacobian, the EE origin by ``δp = v_n + ω_n × p_n``), without the derivatives: ``A`` is block
bidiagonal (platform j's legs move with plates j and j+1), so ``y`` follows platform by
platform, ``K_jᵀ y_{j+1} = F_j / k + Kb_jᵀ y_j`` with ``K_j`` the lines ``[u; t × u]`` of
platform j's legs at their top joints and ``Kb_j`` the lines ``[u; b × u]`` at their bottom
joints (``y_0 = 0``: plate 0 stays). Every line search point of the sag objective is
evaluated this way; the gradient (at the accepted points) is the adjoint of
:func:`~assembler_pin.compliance.loaded.sag_and_gradient`.
"""

from __future__ import annotations

import numpy as np

from ..common.linalg import cross
from ..statics.closed_form import Equilibrium
from ..statics.derivatives import PoseValues

__all__ = ["equilibrium_sag", "linear_sag"]


def linear_sag(values: PoseValues, stiffness: float) -> tuple[float, np.ndarray]:
    """(``|δp|`` [m], ``δp`` (3,) [m, world axes]) of the EE origin at a pose.

    Args:
        values: the pose's closed-form pass (:func:`~assembler_pin.statics.derivatives.pose_values`).
        stiffness: the legs' axial stiffness k [N/m].

    Returns NaN when a platform's lines are singular (no sag is defined there).
    """
    return equilibrium_sag(values.eq, values.plates.p[-1], stiffness)


def equilibrium_sag(eq: Equilibrium, ee_position: np.ndarray, stiffness: float) -> tuple[float, np.ndarray]:
    """:func:`linear_sag` from the closed-form equilibrium alone.

    Args:
        eq: the pose's :class:`~assembler_pin.statics.closed_form.Equilibrium` (world frame).
        ee_position: the EE plate's origin, world [m].
        stiffness: the legs' axial stiffness k [N/m].
    """
    top = eq.K  # (n, 6 rows, 6 legs): the lines [u; t × u], one column per leg
    bottom = np.concatenate([eq.u, cross(eq.b, eq.u)], axis=-1)  # (n, 6 legs, 6)
    stretch = eq.forces / stiffness
    y = np.zeros(6)
    try:
        for j in range(top.shape[0]):
            y = np.linalg.solve(top[j].T, stretch[j] + bottom[j] @ y)
    except np.linalg.LinAlgError:
        return float("nan"), np.full(3, np.nan)
    p = ee_position
    dp = y[:3] + np.array([y[4] * p[2] - y[5] * p[1], y[5] * p[0] - y[3] * p[2], y[3] * p[1] - y[4] * p[0]])
    return float(np.linalg.norm(dp)), dp
