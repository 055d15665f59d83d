"""The compliant truss: the legs as springs, the stack's stiffness and its loaded pose.

- :mod:`.elastic`: the elastic potential, its gradient and Hessian, Newton's method.
- :mod:`.tangent`: the tangent solves behind it (block sweep, held stacks).
- :mod:`.ee_stiffness`: the end effector's stiffness (:func:`stiffness`).
- :mod:`.loaded`: the loaded pose, the compensated lengths and the sag's gradient.
- :mod:`.scaling`: how the stiffness scales with the stack's size and geometry.
"""

from __future__ import annotations

from .ee_stiffness import StiffnessResult, stiffness
from .loaded import (
    MAX_WRENCH,
    CompensatedLengths,
    LoadedPose,
    SagGradient,
    compensated_lengths,
    loaded_pose,
    sag_and_gradient,
)

__all__ = [
    "MAX_WRENCH",
    "CompensatedLengths",
    "LoadedPose",
    "SagGradient",
    "StiffnessResult",
    "compensated_lengths",
    "loaded_pose",
    "sag_and_gradient",
    "stiffness",
]
