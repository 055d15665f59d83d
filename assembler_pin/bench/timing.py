"""What the benchmarks share: the median timer, random reachable poses and the goal grid."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable

import numpy as np

from ..kinematics import PlateArrays, stack_forward_kinematics
from ..model.assembler import AssemblerModel

__all__ = ["LEVEL_GRID", "median_time_us", "random_reachable_plates"]


def median_time_us(fn: Callable[[], object], repeat: int) -> float:
    """Median wall time of ``fn()`` over ``repeat`` calls, after one warm-up call [µs]."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times) * 1e6


def random_reachable_plates(
    am: AssemblerModel, rng: np.random.Generator, spread: float = 0.35
) -> tuple[np.ndarray, PlateArrays]:
    """Random in-stroke leg lengths and the plate poses they give (by stack FK).

    Args:
        spread: fraction of the stroke around mid-stroke that lengths are drawn from.

    Returns:
        (lengths (n, 6) [m], plate poses).
    """
    leg = am.config.leg
    half = 0.5 * spread * (leg.max_length - leg.min_length)
    while True:
        lengths = rng.uniform(leg.mid_length - half, leg.mid_length + half, (am.n, 6))
        fk = stack_forward_kinematics(am, lengths)
        if fk.success:
            return lengths, fk.plates


#: The level-EE goal grid of :func:`benchmark_solve_grid`: x = -0.4…0.5, y = 0, 0.2,
#: z = 0.5…1.0 m, steps of 0.1 m, EE parallel to the base.
LEVEL_GRID = tuple(
    (round(x, 3), round(y, 3), round(z, 3))
    for x in np.arange(-0.4, 0.55, 0.1)
    for y in (0.0, 0.2)
    for z in np.arange(0.5, 1.05, 0.1)
)
