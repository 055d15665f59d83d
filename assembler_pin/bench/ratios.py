"""The user's path against the core it stands on: ratios measured in one process.

``assembler-pin bench --ratios`` runs :func:`benchmark_ratios` and prints
:func:`format_ratios`: the time of what a user calls (:func:`~assembler_pin.state.evaluate_state`
with its self clearance, :func:`~assembler_pin.statics.engine.solve_statics`) divided by bare
Pinocchio on the exported model (``computeGeneralizedGravity`` + ``computeJointJacobians`` at
the same poses), and ``solve``'s p50 / p95 on random reachable goals. Ratios taken in one
process move far less with the machine's load than the times themselves; the table of
docs/benchmarks.md is this function's output (``docs/gen_ratios.py``).

Every timed call runs under one BLAS thread.
"""

from __future__ import annotations

import itertools
import time
from typing import Any

import numpy as np
import pinocchio as pin

from ..kinematics import q_from_plates
from ..model.assembler import AssemblerModel
from ..solver import solve
from ..state import evaluate_state
from ..statics.engine import solve_statics
from .timing import median_time_us, random_reachable_plates

__all__ = ["RATIO_TARGETS", "benchmark_ratios", "format_ratios"]

#: The rows of :func:`format_ratios`: (key, what, unit, target, sense).
RATIO_TARGETS: tuple[tuple[str, str, str, float, str], ...] = (
    ("evaluate_state_ratio", "`evaluate_state` (self clearance included) ÷ bare Pinocchio", "×", 10.0, "<="),
    ("solve_statics_ratio", "`solve_statics` ÷ bare Pinocchio", "×", 2.0, "<="),
    ("solve_p50_ms", "`solve`, random reachable goals, p50", "ms", 15.0, "<="),
    ("solve_p95_over_p50", "`solve`, random reachable goals, p95 ÷ p50", "×", 3.0, "<="),
)


def benchmark_ratios(am: AssemblerModel, repeat: int = 300, goals: int = 40, seed: int = 0) -> dict[str, Any]:
    """The figures of :data:`RATIO_TARGETS` and the times behind them.

    Args:
        repeat: timed calls per per-call figure (medians, cycling through 20 random reachable
            poses, plate arrays as results carry them).
        goals: random reachable goals ``solve`` is timed on (0: no solve rows).

    Returns:
        ``bare_pinocchio_us``, ``evaluate_state_us``, ``solve_statics_us`` [µs] and their
        ratios; ``solve_p50_ms``, ``solve_p95_ms`` and ``solve_p95_over_p50`` with ``goals``.
    """
    from threadpoolctl import threadpool_limits

    rng = np.random.default_rng(seed)
    poses = [random_reachable_plates(am, rng)[1] for _ in range(20)]
    qs = [q_from_plates(am, pa) for pa in poses]
    data = am.model.createData()
    out: dict[str, Any] = {"platforms": am.n, "repeat": repeat}
    with threadpool_limits(limits=1):
        cycle_q, cycle_pa, cycle_st = itertools.cycle(qs), itertools.cycle(poses), itertools.cycle(poses)

        def bare() -> None:
            q = next(cycle_q)
            pin.computeGeneralizedGravity(am.model, data, q)
            pin.computeJointJacobians(am.model, data, q)

        out["bare_pinocchio_us"] = median_time_us(bare, repeat)
        out["evaluate_state_us"] = median_time_us(lambda: evaluate_state(am, next(cycle_pa)), repeat)
        out["solve_statics_us"] = median_time_us(lambda: solve_statics(am, next(cycle_st)), repeat)
        for key in ("evaluate_state", "solve_statics"):
            out[f"{key}_ratio"] = out[f"{key}_us"] / out["bare_pinocchio_us"]
        if goals:
            times = []
            for pa in (random_reachable_plates(am, rng)[1] for _ in range(goals)):
                t0 = time.perf_counter()
                solve(am, pa.se3(am.n))
                times.append(time.perf_counter() - t0)
            p50, p95 = np.percentile(times, 50) * 1e3, np.percentile(times, 95) * 1e3
            out.update({"solve_p50_ms": float(p50), "solve_p95_ms": float(p95), "solve_p95_over_p50": float(p95 / p50)})
    return out


def format_ratios(doc: dict[str, Any]) -> str:
    """The figures of :func:`benchmark_ratios` as a Markdown table: figure, value, target,
    met; figures not measured are left out."""
    lines = ["| figure | value | target | met |", "| --- | --- | --- | --- |"]
    for key, what, unit, target, sense in RATIO_TARGETS:
        if key not in doc:
            continue
        value = float(doc[key])
        met = value <= target if sense == "<=" else value >= target
        lines.append(f"| {what} | {value:.3g} {unit} | {sense} {target:g} {unit} | {'yes' if met else 'no'} |")
    lines.append(
        f"\nbare Pinocchio {doc['bare_pinocchio_us']:.3g} µs, `evaluate_state` {doc['evaluate_state_us']:.3g} µs, "
        f"`solve_statics` {doc['solve_statics_us']:.3g} µs ({doc['platforms']} platforms, median of {doc['repeat']})."
    )
    return "\n".join(lines)
