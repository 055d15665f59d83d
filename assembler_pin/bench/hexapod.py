"""Benchmark of the hexapod: the whole structure's elastic stand, six stacks of four platforms."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..config.bounds import check_bound
from ..config.schema import PayloadConfig, load_config
from ..hexapod import ring_stacks, stand
from ..model.assembler import AssemblerModel
from .timing import median_time_us

__all__ = ["HEXAPOD_TARGETS_MS", "benchmark_hexapod"]

#: Targets [ms] of the hexapod figures (:func:`benchmark_hexapod`), by key stem.
HEXAPOD_TARGETS_MS = {"six_stack_welded_stand": 500.0, "six_stack_resting_stand": 500.0}


def _median_cpu_ms(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        c0 = time.process_time()
        fn()
        times.append(time.process_time() - c0)
    return 1e3 * float(np.median(times))


def benchmark_hexapod(repeat: int = 10) -> dict[str, Any]:
    """Per call [ms]: :func:`~assembler_pin.hexapod.stand` of six default stacks (four
    platforms, no tool) on a 0.6 m circle under a 20 kg body, its legs commanded 0.2 mm off
    their poses' lengths (a fixed pseudo-random pattern: the Newton solve has work to do),
    welded and resting, the clearance included; wall time (``..._ms``), this process's CPU time (``..._cpu_ms``), the
    target (``..._target_ms``, :data:`HEXAPOD_TARGETS_MS`) and whether it stood (``..._ok``).
    """
    check_bound("bench.repeat", repeat, "repeat")
    am = AssemblerModel.from_config(load_config().replace(payload=PayloadConfig(mass=0.0)))
    stacks = ring_stacks(am, 6, 0.6)
    com = np.array([0.0, 0.0, stacks[0].p[-1, 2] + 0.1])
    own = stand(am, stacks, 20.0, com).lengths
    lengths = own + 2e-4 * np.sin(np.arange(own.size)).reshape(own.shape)
    out: dict[str, Any] = {}
    for feet in ("welded", "resting"):
        key = f"six_stack_{feet}_stand"

        def call(feet=feet):
            return stand(am, stacks, 20.0, com, lengths=lengths, feet=feet)

        out[f"{key}_ok"] = bool(call().converged)
        out[f"{key}_ms"] = 1e-3 * median_time_us(call, repeat)
        out[f"{key}_cpu_ms"] = _median_cpu_ms(call, repeat)
        out[f"{key}_target_ms"] = HEXAPOD_TARGETS_MS[key]
    return out
