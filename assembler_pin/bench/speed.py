"""Figures of the speed work: thread settings, the lazy start portfolio, the helper arm's
tail, the statics kernel, capacity memory. Library functions (no printing); each returns a
dict of plain numbers, times in seconds unless the key says otherwise.

They measure on the machine they run on, in this process: on a loaded machine the absolute
figures move, the comparisons made in one call (1 vs 2 threads, ``first`` vs ``all``, numba
vs numpy) much less.
"""

from __future__ import annotations

import functools
import math
import time
import tracemalloc
from typing import Any

import numpy as np

from ..config.bounds import check_bound
from ..config.options import casadi_missing
from ..config.schema import load_config
from ..kinematics import PlateArrays, plate_arrays
from ..model.assembler import AssemblerModel
from ..optimize import OptimizeOptions, optimize_internal_poses
from ..solver.capacity import PayloadModels, payload_capacity
from ..solver.pipeline import solve
from ..statics.kernel import closed_form_forces, kernel_available, kernel_result, reference_forces
from ..statics.pinocchio_statics import solve_statics_pinocchio
from ..supports.choice import chosen_distribution
from ..supports.two_point import two_point_statics
from .timing import LEVEL_GRID, median_time_us, random_reachable_plates

__all__ = [
    "LONG_STACK_SIZES",
    "LONG_STACK_TARGETS_S",
    "STARTUP_COMMANDS",
    "STARTUP_TARGETS_S",
    "THREAD_GOALS",
    "TWO_POINT_TARGETS_MS",
    "WORSE_THAN_ALL",
    "benchmark_capacity_memory",
    "benchmark_long_stacks",
    "benchmark_single_statics",
    "benchmark_solve_starts",
    "benchmark_startup",
    "benchmark_statics_kernel",
    "benchmark_threads",
    "benchmark_two_point",
    "long_stack",
    "rss_mb",
]

#: A goal where the default's Ω exceeds that of every start (``starts="all"``) by more than
#: this share counts as worse: 0.1 %, ten times the tolerance within which two optima are one
#: (:data:`~assembler_pin.solver.starts.SAME_OPTIMUM`).
WORSE_THAN_ALL = 1e-3

#: Goals of the thread comparison (level EE, world [m]).
THREAD_GOALS = ((0.1, 0.0, 0.8), (-0.2, 0.1, 0.7), (0.3, 0.0, 0.6), (0.0, 0.2, 0.9), (0.4, 0.0, 0.7))


def rss_mb() -> float:
    """Resident memory of this process [MB] (Linux ``/proc``; NaN elsewhere)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return float("nan")


def _goal(xyz: Any) -> Any:
    """A level EE goal at ``xyz`` [m, world], or ``xyz`` itself when it is a pose already."""
    import pinocchio as pin

    return xyz if isinstance(xyz, pin.SE3) else pin.SE3(np.eye(3), np.array(xyz, dtype=float))


def benchmark_threads(am: AssemblerModel, goals: tuple = THREAD_GOALS, limits: tuple[int, ...] = (1, 2)) -> dict:
    """``solve`` on ``goals`` under each caller's BLAS thread limit: total time [s] per limit
    and whether every answer (the optimized plates) is bit-identical across the limits."""
    from threadpoolctl import threadpool_limits

    out: dict[str, Any] = {}
    answers = []
    for limit in limits:
        with threadpool_limits(limits=limit):
            t0 = time.perf_counter()
            got = [solve(am, _goal(xyz)) for xyz in goals]
            out[f"threads_{limit}_solve_s"] = time.perf_counter() - t0
        answers.append([r.best.plates.p.tobytes() + r.best.plates.R.tobytes() for r in got if r.best is not None])
    out["threads_identical"] = all(a == answers[0] for a in answers)
    return out


def benchmark_solve_starts(
    am: AssemblerModel, goals: tuple = LEVEL_GRID, modes: tuple[str, ...] = ("first", "all")
) -> dict:
    """``solve`` over ``goals`` (default: the 120-goal grid, a few minutes per mode) with each
    ``starts`` mode, interleaved goal by goal (a changing load hits every mode alike): p50, p95,
    max and total [s], the helper arm's p50 / p90 / p95 (``timing_s["initial"]``) [s], goals
    solved (``{mode}_unsolved``: the others), optimizer runs and time [s], and, for ``first``
    against ``all``, the largest relative loss of Ω, how many goals lose more than
    :data:`WORSE_THAN_ALL` (``first_goals_worse``), the total time's ratio
    (``first_time_over_all``) and the largest ratio of one goal's times
    (``first_slowest_goal_over_all``)."""
    times: dict[str, list[float]] = {m: [] for m in modes}
    initial: dict[str, list[float]] = {m: [] for m in modes}
    objectives: dict[str, list[float]] = {m: [] for m in modes}
    counts = {m: {"runs": 0, "solved": 0, "optimize_s": 0.0} for m in modes}
    for xyz in goals:
        for mode in modes:
            t0 = time.perf_counter()
            result = solve(am, _goal(xyz), starts=mode)
            times[mode].append(time.perf_counter() - t0)
            initial[mode].append(result.timing_s["initial"])
            counts[mode]["runs"] += len(result.runs)
            counts[mode]["solved"] += bool(result.success)
            counts[mode]["optimize_s"] += result.timing_s.get("optimize", 0.0)
            opt = result.optimization
            objectives[mode].append(opt.objective_optimized if result.success and opt is not None else np.inf)
    out: dict[str, Any] = {"goals": len(goals)}
    for mode in modes:
        t = np.array(times[mode])
        out.update(
            {
                f"{mode}_p50_s": float(np.percentile(t, 50)),
                f"{mode}_p95_s": float(np.percentile(t, 95)),
                f"{mode}_max_s": float(t.max()),
                f"{mode}_total_s": float(t.sum()),
                **{f"{mode}_initial_p{q}_s": float(np.percentile(initial[mode], q)) for q in (50, 90, 95)},
            }
        )
        out.update({f"{mode}_{k}": v for k, v in counts[mode].items()})
        lost = zip(goals, objectives[mode], strict=True)
        out[f"{mode}_unsolved"] = [[float(v) for v in xyz] for xyz, o in lost if o == np.inf]
    if "first" in objectives and "all" in objectives:
        lazy, every = np.array(objectives["first"]), np.array(objectives["all"])
        both = np.isfinite(lazy) & np.isfinite(every)
        loss = (lazy[both] - every[both]) / every[both]
        out["first_worst_loss"] = float(loss.max()) if loss.size else 0.0
        out["first_goals_worse"] = int((loss > WORSE_THAN_ALL).sum())
        out["first_time_over_all"] = float(np.sum(times["first"]) / np.sum(times["all"]))
        out["first_slowest_goal_over_all"] = float(np.max(np.array(times["first"]) / np.array(times["all"])))
    return out


def benchmark_statics_kernel(
    am: AssemblerModel, batch_sizes: tuple[int, ...] = (1_000, 10_000, 100_000), repeat: int = 200, seed: int = 0
) -> dict:
    """The closed-form statics, compiled (``numba_...``) and its numpy reference
    (``numpy_...``): the kernel's first call in this process (numba import + compile or
    cache load) [s], one stack from arrays [µs] and stacks per second at each batch size
    (one thread) and the peak of the memory allocated per stack
    [KB] (tracemalloc, a second call); and Pinocchio's single statics [µs] for comparison."""
    rng = np.random.default_rng(seed)
    samples = [random_reachable_plates(am, rng)[1] for _ in range(20)]
    R1, p1 = samples[0].R[None], samples[0].p[None]
    out: dict[str, Any] = {}
    t0 = time.perf_counter()
    closed_form_forces(am, R1, p1)
    out["kernel_first_call_s"] = time.perf_counter() - t0
    out["pinocchio_single_us"] = median_time_us(lambda: solve_statics_pinocchio(am, samples[0]), repeat)
    R = np.array([s.R for s in samples])
    p = np.array([s.p for s in samples])
    for backend, forces in (("numpy", reference_forces), ("numba", closed_form_forces)):
        out[f"{backend}_single_us"] = median_time_us(functools.partial(forces, am, R1, p1), repeat)
        for size in batch_sizes:
            reps = max(1, size // len(samples))
            Rb, pb = np.tile(R, (reps, 1, 1, 1)), np.tile(p, (reps, 1, 1))
            t1 = time.perf_counter()
            forces(am, Rb, pb)
            out[f"{backend}_{size}_stacks_per_s"] = len(Rb) / (time.perf_counter() - t1)
            tracemalloc.start()
            forces(am, Rb, pb)
            out[f"{backend}_{size}_peak_kb_per_stack"] = tracemalloc.get_traced_memory()[1] / 1024 / len(Rb)
            tracemalloc.stop()
    return out


def _statics_calls(am: AssemblerModel, poses: list, has_kernel: bool) -> dict[str, Any]:
    """The calls timed by :func:`benchmark_single_statics`, cycling through ``poses``."""
    counter = iter(range(10**9))
    calls = {"pinocchio": lambda: solve_statics_pinocchio(am, poses[next(counter) % len(poses)])}
    if has_kernel:
        calls["kernel"] = lambda: kernel_result(am, poses[next(counter) % len(poses)])
    return calls


def benchmark_single_statics(
    platforms: tuple[int, ...] = (4, 8, 16), repeat: int = 300, rounds: int = 3, seed: int = 0
) -> dict[str, float]:
    """One stack's whole statics per call [µs] at each stack size: Pinocchio's
    :func:`~assembler_pin.statics.engine.solve_statics` and the compiled kernel's
    :func:`~assembler_pin.statics.kernel.kernel_result` (the same result), from plate arrays
    and from 4×4 matrices (``..._4x4_us``: their validation included). Medians of ``repeat``
    calls cycling through 20 random reachable poses, the best of ``rounds`` interleaved
    rounds; NaN for the kernel without numba."""
    check_bound("bench.repeat", repeat, "repeat")
    has_kernel = kernel_available()
    out: dict[str, float] = {}
    for n in platforms:
        am = AssemblerModel.from_config(load_config().replace(platforms=n))
        rng = np.random.default_rng(seed)
        arrays = [random_reachable_plates(am, rng)[1] for _ in range(20)]
        sources: dict[str, list] = {"": arrays, "_4x4": [a.as_matrices() for a in arrays]}
        for _ in range(rounds):
            for suffix, poses in sources.items():
                for name, call in _statics_calls(am, poses, has_kernel).items():
                    key = f"n{n}_{name}{suffix}_us"
                    out[key] = min(out.get(key, math.inf), median_time_us(call, repeat))
        if not has_kernel:
            out[f"n{n}_kernel_us"] = out[f"n{n}_kernel_4x4_us"] = float("nan")
    return out


#: Goals of the capacity memory figure (level EE, world [m]).
CAPACITY_GOALS = ((0.1, 0.05, 0.75), (0.1, 0.05, 0.9), (0.25, 0.05, 0.75), (0.25, 0.05, 0.9))


def benchmark_capacity_memory(am: AssemblerModel, goals: tuple = CAPACITY_GOALS) -> dict:
    """``payload_capacity`` over ``goals`` with one shared :class:`PayloadModels` (as a map's
    worker keeps it): resident memory after each call [MB], payload models kept, time [s]."""
    models = PayloadModels(am)
    out: dict[str, Any] = {"rss_start_mb": rss_mb(), "rss_mb": [], "capacity_kg": [], "models_kept": []}
    t0 = time.perf_counter()
    for xyz in goals:
        result = payload_capacity(am, _goal(xyz), models)
        out["rss_mb"].append(rss_mb())
        out["capacity_kg"].append(result.capacity_kg)
        out["models_kept"].append(len(models))
    out["time_s"] = time.perf_counter() - t0
    out["rss_growth_per_call_mb"] = (out["rss_mb"][-1] - out["rss_mb"][0]) / max(1, len(goals) - 1)
    return out


#: The start-up targets [s] of :func:`benchmark_startup`, wall time of a fresh process.
STARTUP_TARGETS_S = {"cli_help_s": 0.2, "cli_statics_home_json_s": 0.25}

#: The commands of :func:`benchmark_startup`: figure -> ``assembler-pin`` arguments.
STARTUP_COMMANDS = {"cli_help_s": ("--help",), "cli_statics_home_json_s": ("statics", "--home", "--json")}


def _child_cpu_s() -> float:
    """CPU time [s] of this process's finished children (user + system; NaN without ``resource``)."""
    try:
        import resource
    except ImportError:  # not on Windows
        return float("nan")
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def benchmark_startup(repeat: int = 5) -> dict[str, float]:
    """Wall time [s] of fresh ``assembler-pin`` processes, medians of ``repeat``: ``--help``
    and ``statics --home --json`` (run as ``python -m assembler_pin.cli`` from the directory
    holding this package, so that the package measured is this one), each beside its target
    (``..._target_s``, :data:`STARTUP_TARGETS_S`) and with its CPU time (``..._cpu_s``, which
    a loaded machine moves much less than the wall time), and a bare ``python -c pass`` (the
    interpreter's own start, which no command can go below). The commands run interleaved,
    round by round, so that a machine's changing load hits each alike.
    """
    import subprocess
    import sys
    from pathlib import Path

    check_bound("bench.repeat", repeat, "repeat")
    home = Path(__file__).resolve().parent.parent
    argvs = {key: ["-m", "assembler_pin.cli", *args] for key, args in STARTUP_COMMANDS.items()}
    argvs["bare_python_s"] = ["-c", "pass"]
    wall: dict[str, list[float]] = {key: [] for key in argvs}
    cpu: dict[str, list[float]] = {key: [] for key in argvs}
    for _ in range(int(repeat)):
        for key, argv in argvs.items():
            c0, t0 = _child_cpu_s(), time.perf_counter()
            subprocess.run([sys.executable, *argv], capture_output=True, check=True, cwd=home)
            wall[key].append(time.perf_counter() - t0)
            cpu[key].append(_child_cpu_s() - c0)
    out: dict[str, float] = {}
    for key in argvs:
        stem = key.removesuffix("_s")
        out[key] = float(np.median(wall[key]))
        out[f"{stem}_cpu_s"] = float(np.median(cpu[key]))
        if key in STARTUP_TARGETS_S:
            out[f"{stem}_target_s"] = STARTUP_TARGETS_S[key]
    return out


def _median_cpu_ms(fn, repeat: int) -> float:
    """Median CPU time of this process per call of ``fn()`` over ``repeat`` calls [ms]."""
    times = []
    for _ in range(repeat):
        c0 = time.process_time()
        fn()
        times.append(time.process_time() - c0)
    return 1e3 * float(np.median(times))


#: Targets [ms] of the two-point support figures (:func:`benchmark_two_point`), by key stem.
TWO_POINT_TARGETS_MS = {"n4_two_point_statics": 1.0, "n64_two_point_statics": 50.0, "n4_chosen_distribution": 5.0}


def benchmark_two_point(platforms: tuple[int, ...] = (4, 64), repeat: int = 20) -> dict[str, float]:
    """Two-point support per call [ms] at the home pose, both ends welded: the elastic
    distribution :func:`~assembler_pin.supports.two_point.two_point_statics` at each stack size and the
    chosen distribution :func:`~assembler_pin.supports.choice.chosen_distribution` (its check
    included) at n = 4, each a median of ``repeat`` calls (``repeat // 4`` at n > 16), wall time
    (``..._ms``) and this process's CPU time (``..._cpu_ms``, which a loaded machine moves much
    less), beside its target (``..._target_ms``, :data:`TWO_POINT_TARGETS_MS`); ``..._ok`` says
    a call succeeded.
    """
    check_bound("bench.repeat", repeat, "repeat")
    out: dict[str, float] = {}
    for n in platforms:
        am = AssemblerModel.from_config(load_config().replace(platforms=n))
        pa = plate_arrays(am, am.home)
        calls: dict[str, Any] = {"two_point_statics": lambda am=am, pa=pa: two_point_statics(am, pa)}
        if n == 4:
            calls["chosen_distribution"] = lambda am=am, pa=pa: chosen_distribution(am, pa)
        for name, call in calls.items():
            key = f"n{n}_{name}"
            out[f"{key}_ok"] = bool(call().success)
            calls_made = max(1, repeat // 4) if n > 16 else repeat
            out[f"{key}_ms"] = 1e-3 * median_time_us(call, calls_made)
            out[f"{key}_cpu_ms"] = _median_cpu_ms(call, calls_made)
            if key in TWO_POINT_TARGETS_MS:
                out[f"{key}_target_ms"] = TWO_POINT_TARGETS_MS[key]
    return out


#: Stack sizes of :func:`benchmark_long_stacks`.
LONG_STACK_SIZES = (8, 16, 32, 64)

#: Targets [s] of one optimization per stack size (:func:`benchmark_long_stacks`).
LONG_STACK_TARGETS_S = {32: 2.0, 64: 5.0}

#: The bend of one platform of :func:`long_stack` at n = 8 (a twist [m, rad] in its home
#: step's frame: 2 mm along x, 5 mrad about y), scaled by 8/n.
LONG_STACK_BEND = (0.002, 0.0, 0.0, 0.0, 0.005, 0.0)


def long_stack(n: int) -> tuple[AssemblerModel, Any]:
    """A stack of ``n`` default platforms and its start: every platform bent alike from its
    home step by :data:`LONG_STACK_BEND` times 8/n (the EE about 5 cm off the vertical,
    leaning 2.3°, at every size); the goal is the start's plate n."""
    import pinocchio as pin

    am = AssemblerModel.from_config(load_config().replace(platforms=n))
    step = pin.SE3(np.eye(3), np.array([0.0, 0.0, am.config.home_height]))
    step = step * pin.exp6(np.array(LONG_STACK_BEND) * 8.0 / n)
    plates = [pin.SE3.Identity()]
    for _ in range(n):
        plates.append(plates[-1] * step)
    return am, PlateArrays.from_se3(plates)


def benchmark_long_stacks(
    sizes: tuple[int, ...] = LONG_STACK_SIZES, methods: tuple[str, ...] = ("slsqp", "ipopt"), slsqp_up_to: int = 32
) -> dict[str, Any]:
    """One optimization (:func:`~assembler_pin.optimize.optimize_internal_poses`, one BLAS
    thread) of :func:`long_stack` per size and method: wall and CPU time [s], iterations,
    time per iteration [ms], max|F| of the answer [N] and success; SLSQP only up to
    ``slsqp_up_to`` platforms (above, its dense step takes minutes). Then, per method, the
    exponent p of time per iteration ∝ n^p (least squares over the sizes, of the wall time
    and of the CPU time, the steadier one on a shared machine; target 1.5) and the targets
    of :data:`LONG_STACK_TARGETS_S` beside the times."""
    methods = tuple(m for m in methods if m != "ipopt" or not casadi_missing())
    out: dict[str, Any] = {}
    per_iteration: dict[str, list[tuple[int, float, float]]] = {m: [] for m in methods}
    for n in sizes:
        am, start = long_stack(n)
        for method in methods:
            if method == "slsqp" and n > slsqp_up_to:
                continue
            cpu = time.process_time()
            result = optimize_internal_poses(am, start, options=OptimizeOptions(method=method))
            cpu = time.process_time() - cpu
            key, iterations = f"n{n}_{method}", max(result.iterations, 1)
            out[f"{key}_s"] = result.time_s
            out[f"{key}_cpu_s"] = cpu
            out[f"{key}_iterations"] = result.iterations
            out[f"{key}_ms_per_iteration"] = 1e3 * result.time_s / iterations
            out[f"{key}_max_abs_force_N"] = result.optimized.max_abs_force
            out[f"{key}_success"] = bool(result.success)
            per_iteration[method].append((n, result.time_s / iterations, cpu / iterations))
            if n in LONG_STACK_TARGETS_S:
                out[f"{key}_target_s"] = LONG_STACK_TARGETS_S[n]
    for method, points in per_iteration.items():
        if len(points) >= 2:
            ns = np.log([p[0] for p in points])
            out[f"{method}_per_iteration_exponent"] = float(np.polyfit(ns, np.log([p[1] for p in points]), 1)[0])
            out[f"{method}_per_iteration_exponent_cpu"] = float(np.polyfit(ns, np.log([p[2] for p in points]), 1)[0])
    out["per_iteration_exponent_target"] = 1.5
    return out
