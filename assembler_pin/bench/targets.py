"""The speed targets: every figure of the speed work beside its target, from one run.

``assembler-pin bench --targets`` runs :func:`benchmark_targets` and prints
:func:`format_targets`: BLAS threads, ``solve`` on random and on grid goals, the default
start portfolio against every start on goals over the stroke, one
optimization of long stacks, one stack's statics, batched statics, one stack's clearance and
``solve`` among ten obstacles, and a capability map's memory on two local workers. Each row
says what was measured, its target and whether it is met; a figure that could not be
measured here (numba, CasADi or Dask missing) is shown as such and counts as not met.

Library functions (no printing), one BLAS thread in the timed calls; times are wall times
of this process on this machine (a loaded machine moves them, the comparisons made in one
call much less).
"""

from __future__ import annotations

import math
import threading
import time
import zlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..config.options import casadi_missing
from ..config.schema import load_config
from ..helper_arm import perturbed_plates, repair_stack
from ..kinematics import even_screw_pose
from ..maps import parse_grid, run_map
from ..model.assembler import AssemblerModel
from ..optimize import optimize_internal_poses
from .collision import benchmark_clearance, benchmark_solve_scene
from .speed import (
    THREAD_GOALS,
    benchmark_long_stacks,
    benchmark_single_statics,
    benchmark_solve_starts,
    benchmark_statics_kernel,
    benchmark_threads,
)
from .starts import STARTS_GOALS, benchmark_default_starts
from .timing import LEVEL_GRID, random_reachable_plates

__all__ = [
    "MAP_MEMORY_CELLS",
    "RANDOM_GOALS",
    "SEARCH_STARTS",
    "TARGET_SPECS",
    "TargetRow",
    "benchmark_map_memory",
    "benchmark_targets",
    "benchmark_wide_search",
    "format_targets",
    "random_goals",
    "target_rows",
    "wide_search",
]

#: How many random reachable goals the ``solve`` row times.
RANDOM_GOALS = 60

#: Cells of the map whose workers' memory is measured.
MAP_MEMORY_CELLS = 1000

#: Starts of :func:`wide_search` per goal. Its hit rate on the reachable goals of the grid
#: that ``solve`` leaves unsolved is ~1 in 150 starts (60 starts find one of them for one
#: seed in three): 300 give the row a ~87 % chance per such goal.
SEARCH_STARTS = 300

#: The random twists of :func:`wide_search` (translation [m], rotation [rad] per axis): the
#: first third of the starts as the helper arm's perturbed starts, the rest wider.
SEARCH_TWISTS = ((0.05, 0.3), (0.12, 0.8))


def benchmark_wide_search(am: AssemblerModel, goals: list, starts: int = SEARCH_STARTS) -> dict[str, Any]:
    """:func:`wide_search` on each level EE goal ``goals`` (xyz [m]; those ``solve`` left
    unsolved): how many it solves (``solved_by_search``), each with its max|F| [N], and the
    time [s]."""
    import pinocchio as pin

    t0 = time.perf_counter()
    found = []
    for xyz in goals:
        where = np.asarray(xyz, dtype=float)
        seed = zlib.crc32(np.round(where, 9).tobytes())  # the goal's own: the same answer in any list
        result = wide_search(am, pin.SE3(np.eye(3), where), starts, seed=seed)
        if result is not None:
            found.append([[float(v) for v in xyz], float(result.optimized.max_abs_force)])
    return {
        "searched": len(goals),
        "starts": starts,
        "solved_by_search": len(found),
        "found": found,
        "time_s": time.perf_counter() - t0,
    }


def wide_search(am: AssemblerModel, goal: Any, starts: int = SEARCH_STARTS, seed: int = 0) -> Any:
    """A wider search than ``solve``'s starts, for a goal it leaves unsolved: ``starts`` copies
    of the even screw pose with plates 1..n-1 moved by seeded random twists
    (:data:`SEARCH_TWISTS`), each repaired onto the leg limits and, where the repair holds,
    optimized from there. Returns the first optimizer result whose state meets every
    constraint (its Pinocchio re-check, :func:`~assembler_pin.state.evaluate_state`), else
    None."""
    rng = np.random.default_rng(seed)
    screw = even_screw_pose(am, goal)
    for k in range(starts):
        twist = SEARCH_TWISTS[0] if 3 * k < starts else SEARCH_TWISTS[1]
        (plates,) = perturbed_plates(screw, 1, twist=twist, rng=rng)
        repaired, violation = repair_stack(am, plates)
        if violation > 0.0:
            continue
        result = optimize_internal_poses(am, repaired, goal)
        if result.optimized.feasible:
            return result
    return None


def random_goals(am: AssemblerModel, count: int = RANDOM_GOALS, seed: int = 0) -> list:
    """EE poses (``pin.SE3``, world) of ``count`` random stacks with in-stroke legs
    (:func:`~assembler_pin.bench.timing.random_reachable_plates`): goals known to be reachable."""
    import pinocchio as pin

    rng = np.random.default_rng(seed)
    goals = []
    for _ in range(count):
        plates = random_reachable_plates(am, rng)[1]
        goals.append(pin.SE3(plates.R[-1].copy(), plates.p[-1].copy()))
    return goals


class _PeakMemory:
    """Resident memory [MB] of every process below this one, sampled in a thread every
    ``period`` s (psutil): each process's peak, and its samples for the growth."""

    def __init__(self, period: float = 0.25) -> None:
        import psutil

        self._me = psutil.Process()
        self._period = period
        self.peak: dict[int, float] = {}
        self.samples: dict[int, list[tuple[float, float]]] = {}
        self.names: dict[int, str] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _sample(self) -> None:
        import psutil

        for child in self._me.children(recursive=True):
            try:
                rss = child.memory_info().rss / 2**20
                cmd = " ".join(child.cmdline())
            except psutil.Error:
                continue
            self.peak[child.pid] = max(self.peak.get(child.pid, 0.0), rss)
            self.samples.setdefault(child.pid, []).append((time.perf_counter(), rss))
            self.names[child.pid] = cmd

    def _run(self) -> None:
        while not self._stop.is_set():
            self._sample()
            self._stop.wait(self._period)

    def __enter__(self) -> _PeakMemory:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def workers(self) -> list[int]:
        """The pids of the Dask worker processes seen (spawned by their nannies)."""
        return [pid for pid, cmd in self.names.items() if "spawn_main" in cmd]

    def growth(self, pid: int) -> float:
        """How much the process grew [MB] over the second half of its life: its last sample
        less its largest sample of the first half (start-up's imports are not growth)."""
        samples = self.samples[pid]
        middle = 0.5 * (samples[0][0] + samples[-1][0])
        first_half = [rss for t, rss in samples if t <= middle]
        return samples[-1][1] - max(first_half)


def benchmark_map_memory(cells: int = MAP_MEMORY_CELLS, workers: int = 2) -> dict[str, Any]:
    """A capability map of ``cells`` level-EE goals (x in [-0.4, 0.5] m, y in [0, 0.3] m,
    z in [0.55, 1.0] m) on ``workers`` local Dask workers, with the memory of every worker
    process sampled: its peak and its growth from its first to its last sample [MB], the
    cells per second, and a map of about a tenth of the cells over the same box on one worker
    for the speed-up (both runs include starting their cluster, whose share is larger in the
    shorter run: the speed-up is the slightly generous side). The growth is over the second half of
    each worker's life (:meth:`_PeakMemory.growth`). Each run writes into a fresh temporary
    directory."""
    import tempfile

    side = max(2, round(cells ** (1 / 3)))
    nz = max(1, math.ceil(cells / side**2))
    spec = f"x=-0.4:0.5:{side},y=0:0.3:{side},z=0.55:1.0:{nz}"
    small = max(2, round(side / 10 ** (1 / 3)))  # a tenth of the cells, over the same box
    small_spec = f"x=-0.4:0.5:{small},y=0:0.3:{small},z=0.55:1.0:{max(1, round(nz / 10 ** (1 / 3)))}"
    out: dict[str, Any] = {"grid": spec}
    with tempfile.TemporaryDirectory() as tmp:
        one = run_map(parse_grid(small_spec), [("default", load_config())], f"{tmp}/one", workers=1)
        with _PeakMemory() as memory:
            run = run_map(parse_grid(spec), [("default", load_config())], f"{tmp}/many", workers=workers)
    pids = memory.workers() or list(memory.peak)
    out["cells"] = int(run.computed)
    out["cells_per_s"] = float(run.cells_per_second)
    out["one_worker_cells_per_s"] = float(one.cells_per_second)
    out["speedup"] = float(run.cells_per_second / one.cells_per_second) if one.cells_per_second else math.nan
    out["worker_peak_mb"] = max((memory.peak[p] for p in pids), default=math.nan)
    out["worker_growth_mb"] = max((memory.growth(p) for p in pids), default=math.nan)
    out["workers_seen"] = len(pids)
    return out


def benchmark_targets(am: AssemblerModel, map_cells: int = MAP_MEMORY_CELLS, quick: bool = False) -> dict[str, Any]:
    """Every figure of :func:`target_rows`, one group per row family (the functions of
    :mod:`~assembler_pin.bench.speed`, :mod:`~assembler_pin.bench.collision` and
    :func:`benchmark_map_memory`), each timed call
    under one BLAS thread. ``map_cells=0`` skips the map. ``quick``: a smoke test of the
    bench (4 random goals, no grid, long stacks of 4 and 8 platforms, small batches), not
    figures."""
    from threadpoolctl import threadpool_limits

    doc: dict[str, Any] = {"threads": benchmark_threads(am, goals=THREAD_GOALS[:2] if quick else THREAD_GOALS)}
    with threadpool_limits(limits=1):
        goals = random_goals(am, 4 if quick else RANDOM_GOALS)
        doc["random_solves"] = benchmark_solve_starts(am, tuple(goals))
        doc["default_starts"] = benchmark_default_starts(am, count=3 if quick else STARTS_GOALS)
        if not quick:
            doc["grid_solves"] = benchmark_solve_starts(am, LEVEL_GRID)
            doc["grid_search"] = benchmark_wide_search(am, doc["grid_solves"]["first_unsolved"])
        sizes = (4, 8) if quick else (8, 16, 32, 64)
        doc["long_stacks"] = {} if casadi_missing() else benchmark_long_stacks(sizes, methods=("ipopt",))
        doc["single_statics"] = benchmark_single_statics(platforms=(4,), repeat=20 if quick else 300)
        batches = (1_000, 10_000) if quick else (1_000, 100_000)
        doc["statics_kernel"] = benchmark_statics_kernel(am, batch_sizes=batches, repeat=20 if quick else 200)
        poses = [random_reachable_plates(am, np.random.default_rng(k))[1] for k in range(20)]
        doc["collision"] = {
            **benchmark_clearance(am, poses, repeat=20 if quick else 300),
            **benchmark_solve_scene(am, rounds=1 if quick else 5),
        }
    if map_cells:
        try:
            doc["map_memory"] = benchmark_map_memory(map_cells)
        except ImportError:  # Dask (the ``maps`` extra) missing
            doc["map_memory"] = {}
    return doc


@dataclass(frozen=True)
class TargetRow:
    """One figure beside its target.

    Attributes:
        what: the figure, with its unit.
        value: the measured value (NaN: not measured here).
        target: the target value.
        sense: ``"<="`` (at most the target), ``">="`` (at least) or ``"=="``.
        text: the value as shown.
    """

    what: str
    value: float
    target: float
    sense: str
    text: str

    @property
    def met(self) -> bool:
        """Whether the value meets its target (never when not measured)."""
        if not math.isfinite(self.value):
            return False
        if self.sense == "<=":
            return self.value <= self.target
        if self.sense == ">=":
            return self.value >= self.target
        return self.value == self.target


def _get(doc: dict, group: str, key: str) -> float:
    value = doc.get(group, {}).get(key, math.nan)
    return float(value) if isinstance(value, (int, float, bool, np.floating)) else math.nan


def _row(what: str, value: float, target: float, sense: str) -> TargetRow:
    """A row; ``value`` and ``target`` in the unit ``what`` names."""
    text = "not measured" if not math.isfinite(value) else f"{value:.4g}"
    return TargetRow(what, value, target, sense, text)


#: The rows of :func:`target_rows`: (figure and unit, group, key, scale to that unit,
#: target, sense); the map's rows and the grid's solved count are added where measured.
TARGET_SPECS: tuple[tuple[str, str, str, float, float, str], ...] = (
    ("answers identical under 1 and 2 BLAS threads (1 = yes)", "threads", "threads_identical", 1, 1, "=="),
    ("solve, random goals, p50 [ms]", "random_solves", "first_p50_s", 1e3, 40, "<="),
    ("solve, random goals, p95 [ms]", "random_solves", "first_p95_s", 1e3, 100, "<="),
    ("random goals with an optimum 0.1 % worse than every start's", "random_solves", "first_goals_worse", 1, 0, "=="),
    ("solve, goals over the stroke, p95 ÷ p50", "default_starts", "solve_p95_over_p50", 1, 3, "<="),
    ("solve, goals over the stroke, time ÷ every start's", "default_starts", "solve_time_over_all", 1, 1, "<="),
    ("solve, slowest goal's time ÷ every start's", "default_starts", "solve_slowest_goal_over_all", 1, 2, "<="),
    (
        "goals over the stroke with an optimum 0.1 % worse than every start's",
        "default_starts",
        "solve_goals_worse_than_all",
        1,
        0,
        "==",
    ),
    ("solve, 120-goal grid, p95 [s]", "grid_solves", "first_p95_s", 1, 0.3, "<="),
    (f"grid goals unsolved that a {SEARCH_STARTS}-start search solves", "grid_search", "solved_by_search", 1, 0, "=="),
    ("one optimization, n = 32, IPOPT [s]", "long_stacks", "n32_ipopt_s", 1, 2.0, "<="),
    ("one optimization, n = 64, IPOPT [s]", "long_stacks", "n64_ipopt_s", 1, 5.0, "<="),
    ("IPOPT time per iteration ∝ n^p, p", "long_stacks", "ipopt_per_iteration_exponent", 1, 1.5, "<="),
    ("one stack's statics from arrays, n = 4 [µs]", "single_statics", "n4_kernel_us", 1, 20, "<="),
    ("one stack's statics from 4×4 matrices, n = 4 [µs]", "single_statics", "n4_kernel_4x4_us", 1, 40, "<="),
    ("self-collision clearance, one stack, compiled kernel [µs]", "collision", "clearance_us", 1, 50, "<="),
    ("solve with ten obstacles against without [×]", "collision", "solve_scene_ratio", 1, 2, "<="),
    ("batched statics, 100,000 stacks [stacks/s]", "statics_kernel", "numba_100000_stacks_per_s", 1, 250_000, ">="),
    ("batched statics, peak memory per stack [KB]", "statics_kernel", "numba_100000_peak_kb_per_stack", 1, 1.0, "<="),
    ("map, peak memory per worker [MB]", "map_memory", "worker_peak_mb", 1, 300, "<="),
    ("map, 2 local workers against one [×]", "map_memory", "speedup", 1, 1.8, ">="),
)


def target_rows(doc: dict[str, Any]) -> list[TargetRow]:
    """The rows of :data:`TARGET_SPECS` from :func:`benchmark_targets`' document (the
    groups it skipped are left out), and the grid's solved count beside every start's."""
    rows = [
        _row(what, scale * _get(doc, group, key), target, sense)
        for what, group, key, scale, target, sense in TARGET_SPECS
        if group in doc
    ]
    if "grid_solves" in doc:
        solved_all = _get(doc, "grid_solves", "all_solved")
        rows.append(
            _row(
                "grid goals solved (target: as many as every start)",
                _get(doc, "grid_solves", "first_solved"),
                solved_all,
                ">=",
            )
        )
    return rows


def format_targets(rows: list[TargetRow]) -> str:
    """The rows as a table of at most 100 columns: figure, value, target, met."""
    width = max(len(r.what) for r in rows)
    lines = [f"{'figure':<{width}}  {'value':>12}  {'target':>10}  met"]
    for r in rows:
        target = f"{r.sense} {r.target:.4g}" if r.sense != "==" else f"= {r.target:.4g}"
        lines.append(f"{r.what:<{width}}  {r.text:>12}  {target:>10}  {'yes' if r.met else 'no'}")
    met = sum(r.met for r in rows)
    lines.append(f"{met} of {len(rows)} targets met")
    return "\n".join(lines)
