"""The statics engine: the compiled closed form for one stack and for batches.

:func:`solve_statics` is the package's statics of one pose, on the compiled kernel of
:mod:`~assembler_pin.statics.kernel` (numba, compiled once per install and loaded from numba's
cache); :func:`solve_statics_batch` is the same kernel over B stacks. Pinocchio's statics
(:func:`~assembler_pin.statics.pinocchio_statics.solve_statics_pinocchio`) and the numpy closed
form (:func:`~assembler_pin.statics.kernel.reference_forces`) are the independent references the
tests hold them to (1e-10 N); a caller who passes a whole-stack Pinocchio ``Data`` gets the
Pinocchio computation on it, with the same forces.

Frames: world poses of plates 0..n; forces [N], tension positive.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..common.validation import as_float_array
from ..exceptions import PoseError
from ..kinematics import LegState, PlateArrays, checked_rotations
from ..model.assembler import AssemblerModel
from .closed_form import CONDITION_LIMIT
from .kernel import closed_form_forces, kernel_result
from .pinocchio_statics import check_statics_arguments, solve_statics_pinocchio
from .result import StaticsResult

__all__ = ["solve_statics", "solve_statics_batch"]


def solve_statics(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    raise_on_singular: bool = False,
    legs: LegState | None = None,
    data: pin.Data | None = None,
) -> StaticsResult:
    """Actuator and ball-joint forces holding the stack still at the given plate poses.

    Each platform's six legs balance their own weight at their joints, and its top plate the
    weight above it and the six ball forces: a 6×6 system per platform, solved in the top
    plate's frame, whose 1-norm condition number flags a singular platform
    (:data:`~assembler_pin.statics.closed_form.CONDITION_LIMIT`).

    Args:
        plates: world poses of plates 0..n, or a state carrying them
            (see :func:`~assembler_pin.kinematics.plate_arrays`).
        raise_on_singular: raise :class:`~assembler_pin.exceptions.SingularConfigurationError`
            instead of returning a result flagged ``singular``.
        legs: the leg state of these plates, for the Pinocchio computation (with ``data``);
            the compiled engine computes the legs itself.
        data: a Pinocchio ``Data`` of the whole-stack model that the caller owns
            (``am.create_data()``): the forces are then computed by Pinocchio on it
            (:func:`~assembler_pin.statics.pinocchio_statics.solve_statics_pinocchio`), the same
            to 1e-10 N. Default: the compiled engine.

    Raises:
        ArgumentError: ``raise_on_singular`` not a bool, ``legs`` not the plates' leg state.
        PoseError: the poses are not n+1 plate poses.
        SingularConfigurationError: with ``raise_on_singular``, a singular platform.
    """
    if data is not None:
        return solve_statics_pinocchio(am, plates, raise_on_singular, legs, data)
    check_statics_arguments(am, raise_on_singular, legs)
    return kernel_result(am, plates, raise_on_singular)


def solve_statics_batch(am: AssemblerModel, plates: npt.ArrayLike) -> np.ndarray:
    """Actuator forces of B stacks at once, for maps and sweeps.

    The compiled closed form of :func:`solve_statics` over the stacks, which the tests hold
    to Pinocchio's statics to 1e-9 N, singular stacks included.

    Args:
        plates: (B, n+1, 4, 4) world poses of the plates of each stack (validated all at once).

    Returns:
        (B, n, 6) forces [N], tension positive; NaN rows for a stack whose statics are
        singular (see :func:`solve_statics`).

    Raises:
        PoseError: the array is not B stacks of n+1 poses.
    """
    matrices = as_float_array(plates, "plate poses of B stacks (B, n+1, 4, 4)")
    if matrices.ndim != 4 or matrices.shape[1:] != (am.n + 1, 4, 4):
        raise PoseError(f"plate poses of B stacks must have shape (B, {am.n + 1}, 4, 4), got {matrices.shape}")
    B = matrices.shape[0]
    R, p = checked_rotations(matrices.reshape(-1, 4, 4), "pose")
    R, p = R.reshape(B, am.n + 1, 3, 3), p.reshape(B, am.n + 1, 3)
    forces, condition = closed_form_forces(am, R, p)
    singular = ~(condition.max(axis=1) <= CONDITION_LIMIT)  # NaN counts as singular
    return np.where(singular[:, None, None], np.nan, forces)
