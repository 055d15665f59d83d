"""Figures of the clearance: one stack's own pairs on each engine, the truss bay, and ``solve``
with a scene of ten obstacles against ``solve`` without one.

Library functions (no printing); times are medians of this process's wall time, world frame
and metres for the scenes.
"""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np

from ..collision.check import clearance
from ..collision.scene import Scene, scene_from_dict
from ..kinematics import PlateArrays
from ..model.assembler import AssemblerModel
from ..solver.pipeline import solve
from .timing import median_time_us

__all__ = [
    "SOLVE_SCENE",
    "SOLVE_SCENE_GOAL",
    "TRUSS_BAY",
    "benchmark_clearance",
    "benchmark_solve_scene",
]

_STRUT = 1.5707963267948966  # a strut's axis along y: its frame turned a quarter about x [rad]

#: ``examples/truss_bay.yaml`` (the package does not ship ``examples/``; a test holds the two
#: equal): two columns 0.36 m in front of the base, struts at 0.52 m and 1.10 m, their four
#: nodes, a footing, and the floor the base plate stands on.
TRUSS_BAY: dict[str, Any] = {
    "floor": {"z": 0.0},
    "obstacles": [
        {"name": "column -y", "cylinder": {"radius": 0.015, "length": 1.2, "pose": [0.36, -0.45, 0.6, 0.0, 0.0, 0.0]}},
        {"name": "column +y", "cylinder": {"radius": 0.015, "length": 1.2, "pose": [0.36, 0.45, 0.6, 0.0, 0.0, 0.0]}},
        {"name": "lower strut", "cylinder": {"radius": 0.015, "length": 0.9, "pose": [0.36, 0.0, 0.52, _STRUT, 0, 0]}},
        {"name": "upper strut", "cylinder": {"radius": 0.015, "length": 0.9, "pose": [0.36, 0.0, 1.10, _STRUT, 0, 0]}},
        {"name": "node -y low", "sphere": {"radius": 0.03, "center": [0.36, -0.45, 0.52]}},
        {"name": "node +y low", "sphere": {"radius": 0.03, "center": [0.36, 0.45, 0.52]}},
        {"name": "node -y high", "sphere": {"radius": 0.03, "center": [0.36, -0.45, 1.10]}},
        {"name": "node +y high", "sphere": {"radius": 0.03, "center": [0.36, 0.45, 1.10]}},
        {"name": "footing", "box": {"size": [0.12, 1.02, 0.04], "pose": [0.36, 0.0, 0.02, 0.0, 0.0, 0.0]}},
    ],
}

#: The scene of :func:`benchmark_solve_scene`: the truss bay and a wall behind the stack,
#: ten obstacles and the floor.
SOLVE_SCENE: dict[str, Any] = {
    "floor": TRUSS_BAY["floor"],
    "obstacles": [
        *TRUSS_BAY["obstacles"],
        {"name": "back wall", "box": {"size": [0.04, 1.0, 1.2], "pose": [-0.26, 0.0, 0.6, 0.0, 0.0, 0.0]}},
    ],
}

#: The goal of :func:`benchmark_solve_scene`: a level EE at this point, world [m]. The free
#: optimum passes 0.04 m from the wall, 0.07 m from the upper strut and 0.023 m above the
#: floor: near, within the clearance's screen, but the scene does not move it.
SOLVE_SCENE_GOAL = (0.2, 0.1, 0.9)


def benchmark_clearance(am: AssemblerModel, poses: list[PlateArrays], repeat: int) -> dict[str, float]:
    """Median time per :func:`~assembler_pin.collision.check.clearance` call [µs], cycling
    through ``poses``: the stack's own pairs (``clearance_us``) and among the truss bay
    (:data:`TRUSS_BAY`, ``clearance_scene_us``)."""
    scene = scene_from_dict(TRUSS_BAY)
    counter = iter(range(10**9))

    def pick() -> PlateArrays:
        return poses[next(counter) % len(poses)]

    return {
        "clearance_us": median_time_us(lambda: clearance(am, pick()), repeat),
        "clearance_scene_us": median_time_us(lambda: clearance(am, pick(), scene), repeat),
    }


def benchmark_solve_scene(am: AssemblerModel, rounds: int = 5) -> dict[str, Any]:
    """``solve`` of :data:`SOLVE_SCENE_GOAL` without a scene and with :data:`SOLVE_SCENE` (ten
    obstacles and the floor), interleaved round by round after one warm-up of each: medians
    [ms], their ratio (``solve_scene_ratio``, target ≤ 2), and whether both found the same
    optimum (plate origins within 1e-5 m: the two problems differ by their clearance rows, so
    SLSQP stops at points of the same optimum a few µm apart)."""
    import pinocchio as pin

    goal = pin.SE3(np.eye(3), np.array(SOLVE_SCENE_GOAL, dtype=float))
    scene: Scene = scene_from_dict(SOLVE_SCENE)
    free, within = solve(am, goal), solve(am, goal, scene=scene)
    times: dict[str, list[float]] = {"free": [], "scene": []}
    for _ in range(max(1, int(rounds))):
        for key, around in (("free", None), ("scene", scene)):
            t0 = time.perf_counter()
            solve(am, goal, scene=around)
            times[key].append(time.perf_counter() - t0)
    free_ms, scene_ms = (1e3 * statistics.median(times[k]) for k in ("free", "scene"))
    same = (
        free.best is not None
        and within.best is not None
        and bool(np.abs(free.best.plates.p - within.best.plates.p).max() < 1e-5)
    )
    return {
        "solve_free_ms": free_ms,
        "solve_scene_ms": scene_ms,
        "solve_scene_ratio": scene_ms / free_ms,
        "solve_scene_same_optimum": same,
    }
