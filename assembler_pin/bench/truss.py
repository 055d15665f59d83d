"""Benchmark of the compliant truss (``assembler-pin bench --truss``): median times of its
calls at the home pose."""

from __future__ import annotations

from ..common.threads import single_blas_thread
from ..compliance.ee_stiffness import stiffness
from ..compliance.loaded import compensated_lengths, loaded_pose, sag_and_gradient
from ..kinematics import plate_arrays
from ..model.assembler import AssemblerModel
from ..statics.derivatives import pose_derivatives
from ..statics.engine import solve_statics
from .timing import median_time_us

__all__ = ["benchmark_stiffness"]


def benchmark_stiffness(am: AssemblerModel, repeat: int = 200) -> dict[str, float]:
    """Median wall time [s] per call of :func:`~assembler_pin.compliance.stiffness`,
    :func:`~assembler_pin.compliance.loaded_pose`, :func:`~assembler_pin.compliance.compensated_lengths`
    and :func:`~assembler_pin.compliance.sag_and_gradient` at the home pose (and, for scale,
    :func:`~assembler_pin.statics.solve_statics` and the force objective's derivatives
    :func:`~assembler_pin.statics.derivatives.pose_derivatives`), BLAS on one thread as in the
    optimizer."""
    pa = plate_arrays(am, am.home)
    lengths = compensated_lengths(am, pa).lengths
    calls = {
        "stiffness": lambda: stiffness(am, pa),
        "loaded_pose": lambda: loaded_pose(am, lengths),
        "compensated_lengths": lambda: compensated_lengths(am, pa),
        "sag_and_gradient": lambda: sag_and_gradient(am, pa),
        "solve_statics": lambda: solve_statics(am, pa),
        "pose_derivatives": lambda: pose_derivatives(am, pa),
    }
    with single_blas_thread():
        return {name: 1e-6 * median_time_us(call, repeat) for name, call in calls.items()}
