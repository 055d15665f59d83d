"""A compiled pass of the optimizer's per-point values and derivatives.

The optimizer reads, at every point it evaluates, the actuator forces, leg lengths,
deflection cosines, rise and plate angles of the stack and, where it asks for them, their
derivatives with respect to the world twists of plates 1..n. :mod:`assembler_pin.statics.derivatives`
computes them with numpy (~60 small array calls per point); the loops of
:mod:`~assembler_pin.statics.pose_loops` compute the same numbers in one call, compiled here by numba
(``cache=True``: compiled once per install and Python version, then loaded from numba's
cache on the first call in a process).

The compiled pass is the optimizer's engine (numba is a dependency, so every install runs
the same arithmetic). The numpy path (:func:`~assembler_pin.statics.derivatives.pose_values`,
:func:`~assembler_pin.statics.derivatives.pose_derivatives`) is the tests' reference, and the
pass of the problems that read its intermediates (the sag objective and rows, IPOPT's moment
variables). The tests hold the two to 1e-10 N on stacks of 1..16 platforms and the compiled
derivatives to finite differences.

Frames: world poses of plates 0..n; forces [N], tension positive; lengths [m]; angles [rad].
"""

from __future__ import annotations

import logging
import math
import types
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..kinematics import PlateArrays
from ..model.assembler import AssemblerModel
from . import pose_loops as loops
from .derivatives import PoseDerivatives
from .loops import constants

__all__ = ["CompiledPass", "PoseMeasures", "pose_kernel_available"]

logger = logging.getLogger(__name__)

_kernel: Any = None  # the compiled pass, once built (None: not yet)

#: Placeholders for the derivative arrays of a values-only call (the kernel does not read them).
_NO_D3, _NO_D4, _NO_D2 = np.zeros((1, 1, 1)), np.zeros((1, 1, 1, 1)), np.zeros((1, 1))


@dataclass(frozen=True)
class PoseMeasures:
    """What the optimizer reads at one stack pose (the values of :func:`compiled_pose_values`).

    Attributes:
        plates: the world poses of plates 0..n.
        forces: (n, 6) actuator forces [N, tension positive]; NaN on a singular platform.
        lengths: (n, 6) leg lengths [m].
        cos_deflection: (n, 6, 2) cosines of the bottom / top joint deflections.
        rise: (n, 6) height of each top joint above its bottom joint, bottom plate's frame [m].
        plate_angles: (n,) λ_k [rad] (paper eq. 9).
    """

    plates: PlateArrays
    forces: np.ndarray
    lengths: np.ndarray
    cos_deflection: np.ndarray
    rise: np.ndarray
    plate_angles: np.ndarray


def _build_kernel() -> Any:
    """Compile (or load from numba's cache) the pass.

    Each loop of :data:`~assembler_pin.statics.pose_loops.PARTS` is compiled as a copy whose globals
    name the compiled callees, so the interpreted originals keep calling each other."""
    import numba  # delayed: numba's import and the cached pass's load only when an optimizer runs

    jit = numba.njit(cache=True, nogil=True, error_model="numpy")
    scope: dict[str, Any] = {"math": math, "np": np, "__name__": __name__}
    for name, func in loops.PARTS:  # callees first: the callers see them compiled
        scope[name] = jit(types.FunctionType(func.__code__, scope, func.__name__))
    return scope["_pose"]


def pose_kernel_available() -> bool:
    """Load the compiled pass in this process (from numba's cache, or compiled on the first use
    after an install); True once loaded."""
    global _kernel
    if _kernel is None:
        logger.info("loading the optimizer's compiled pass (compiled on the first use after an install)")
        _kernel = _build_kernel()
    return True


class CompiledPass:
    """The compiled pass for one stack model: its anchors, home and rest directions and
    constants arranged once, then :meth:`values` and :meth:`derivatives` per pose."""

    def __init__(self, am: AssemblerModel) -> None:
        pose_kernel_available()
        geo = am.geometry
        rest = am.plate_placement_p
        self.n = am.n
        self._model = (
            np.ascontiguousarray(geo.bottom_in_plate, dtype=float),
            np.ascontiguousarray(geo.top_in_plate, dtype=float),
            np.ascontiguousarray(geo.home_direction, dtype=float),
            np.ascontiguousarray(rest / np.linalg.norm(rest, axis=1, keepdims=True)),
            np.array(constants(am.config)),
        )

    def _outputs(self) -> tuple[np.ndarray, ...]:
        n = self.n
        return np.empty((n, 6)), np.empty((n, 6)), np.empty((n, 6, 2)), np.empty((n, 6)), np.empty(n)

    def values(self, pa: PlateArrays) -> PoseMeasures:
        """Forces, lengths, deflection cosines, rise and plate angles of a stack pose (those of
        :func:`~assembler_pin.statics.derivatives.pose_values`); a singular platform gives NaN forces.

        Args:
            pa: world poses of plates 0..n (validated, e.g. by
                :func:`~assembler_pin.kinematics.plate_arrays`).
        """
        out = self._outputs()
        R, p = np.ascontiguousarray(pa.R, dtype=float), np.ascontiguousarray(pa.p, dtype=float)
        _kernel(R, p, *self._model, False, *out, _NO_D3, _NO_D3, _NO_D4, _NO_D3, _NO_D2)
        return PoseMeasures(pa, *out)

    def derivatives(self, pa: PlateArrays) -> PoseDerivatives:
        """The :class:`~assembler_pin.statics.derivatives.PoseDerivatives` of a stack pose (those of
        :func:`~assembler_pin.statics.derivatives.pose_derivatives`): derivatives with respect to the
        world twists of plates 1..n, last axis 6n.

        Raises:
            numpy.linalg.LinAlgError: a platform's 6×6 system is singular.
        """
        n, C = self.n, 6 * self.n
        forces, lengths, cos, rise, lam = self._outputs()
        dF, dL, drise = np.zeros((n, 6, C)), np.zeros((n, 6, C)), np.zeros((n, 6, C))
        dcos, dlam2 = np.zeros((n, 6, 2, C)), np.zeros((n, C))
        R, p = np.ascontiguousarray(pa.R, dtype=float), np.ascontiguousarray(pa.p, dtype=float)
        if not _kernel(R, p, *self._model, True, forces, lengths, cos, rise, lam, dF, dL, dcos, drise, dlam2):
            raise np.linalg.LinAlgError("a platform's 6x6 statics system is singular")
        return PoseDerivatives(
            forces=forces,
            d_forces=dF,
            lengths=lengths,
            d_lengths=dL,
            cos_deflection=cos,
            d_cos_deflection=dcos,
            rise=rise,
            d_rise=drise,
            plate_angles=lam,
            d_plate_angles_sq=dlam2,
        )
