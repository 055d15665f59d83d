"""Benchmark of the two-point support: median times of its calls at the home pose."""

from __future__ import annotations

from ..kinematics import plate_arrays
from ..model.assembler import AssemblerModel
from ..supports.choice import chosen_distribution
from ..supports.two_point import two_point_statics
from .timing import median_time_us

__all__ = ["benchmark_supports"]


def benchmark_supports(am: AssemblerModel, repeat: int = 50) -> dict[str, float]:
    """Median wall time [s] per call at the home pose of
    :func:`~assembler_pin.supports.two_point_statics` and of
    :func:`~assembler_pin.supports.chosen_distribution` (with and without its check)."""
    pa = plate_arrays(am, am.home)
    calls = {
        "two_point_statics": lambda: two_point_statics(am, pa),
        "chosen_distribution": lambda: chosen_distribution(am, pa),
        "chosen_distribution_unchecked": lambda: chosen_distribution(am, pa, verify=False),
    }
    return {name: 1e-6 * median_time_us(call, repeat) for name, call in calls.items()}
