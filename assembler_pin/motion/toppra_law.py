"""The time-optimal law, by TOPP-RA (``toppra``): one implementation of
:class:`~assembler_pin.motion.laws.TimeLaw` (see :mod:`.laws`).

On a grid of the path (``grid_per_sample`` points per planned step) TOPP-RA finds the largest
``ṡ²`` profile, piecewise linear in ``s`` (so ``s̈`` constant between grid points), with

* every leg's speed ``|L'(s) ṡ| ≤ v_max`` (toppra's ``JointVelocityConstraint``);
* every leg's acceleration ``|L'(s) s̈ + L''(s) ṡ²| ≤ a_max`` (toppra's canonical linear
  constraint; at a planned sample, where the PCHIP's ``L''`` jumps, with both one-sided values);
* every leg's force ``F = a(s) s̈ + b(s) ṡ² + c(s)`` within ``[force_low, force_high]`` (a
  second-order constraint with the coefficients of
  :func:`~assembler_pin.dynamics.path_force_coefficients`),

each held at both ends of every grid interval (toppra's interpolation discretization), from
rest to rest. The output rows follow the profile exactly (constant ``s̈`` per interval).
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np

from ..exceptions import TrajectoryError
from .laws import Schedule, TimingProblem, row_counts

__all__ = ["OptimalLaw"]

logger = logging.getLogger(__name__)


def _toppra():
    import toppra
    import toppra.algorithm
    import toppra.constraint
    from toppra.constraint.linear_constraint import LinearConstraint, canlinear_colloc_to_interpolate
    from toppra.interpolator import AbstractGeometricPath

    logging.getLogger("toppra").setLevel(logging.ERROR)
    return toppra, LinearConstraint, canlinear_colloc_to_interpolate, AbstractGeometricPath


def _path(spline, s_end: float, dof: int):
    """The leg-length spline as a toppra geometric path."""
    _, _, _, Abstract = _toppra()

    class _LegPath(Abstract):  # type: ignore[misc, valid-type]  # toppra's base class, imported lazily
        def __call__(self, path_positions, order: int = 0):
            return spline(np.asarray(path_positions, dtype=float), order)

        @property
        def dof(self) -> int:
            return dof

        @property
        def path_interval(self) -> np.ndarray:
            return np.array([0.0, s_end])

    return _LegPath()


def _force_constraint(a: np.ndarray, b: np.ndarray, c: np.ndarray, low: float, high: float, interpolation: bool = True):
    """``low ≤ a s̈ + b ṡ² + c ≤ high`` row by row (arrays (N+1, k) on the grid): the force
    limits, and the legs' accelerations (``a = L'``, ``b = L''``, ``c = 0``)."""
    toppra, Linear, to_interpolate, _ = _toppra()

    class _Forces(Linear):  # type: ignore[misc, valid-type]  # toppra's base class, imported lazily
        def __init__(self) -> None:
            super().__init__()
            self.identical = True
            kind = toppra.constraint.DiscretizationType
            self.set_discretization_type(kind.Interpolation if interpolation else kind.Collocation)

        def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
            k = a.shape[1]
            F = np.vstack([np.eye(k), -np.eye(k)])
            g = np.concatenate([np.full(k, high), np.full(k, -low)])
            if interpolation:
                return to_interpolate(a, b, c, F, g, None, None, gridpoints, identical=True)
            return a, b, c, F, g, None, None

    return _Forces()


class OptimalLaw:
    """TOPP-RA under the legs' speed, acceleration and force limits (module docstring).

    Attributes:
        grid_per_sample: grid points per planned step.
        max_grid: largest grid (the grid is coarsened to it on long paths).
        interpolation: hold the acceleration and force rows at both ends of every grid
            interval (toppra's interpolation scheme; False: at the grid points only).
    """

    name = "optimal"

    def __init__(self, grid_per_sample: int = 8, max_grid: int = 4000, interpolation: bool = True) -> None:
        self.grid_per_sample = grid_per_sample
        self.max_grid = max_grid
        self.interpolation = interpolation
        self._cache: tuple[int, tuple] | None = None
        self.last_solve_s = math.nan

    def grid(self, problem: TimingProblem) -> np.ndarray:
        """The grid of s (planned samples included)."""
        steps = problem.samples - 1
        per = max(1, min(self.grid_per_sample, self.max_grid // max(1, steps)))
        return np.arange(steps * per + 1) / per

    def profile(self, problem: TimingProblem, grid: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(grid, ṡ at each grid point) of the time-optimal law.

        Raises:
            TrajectoryError: waypoint times (this law does not honour them), or limits that
                allow no motion along the path (with the reason).
        """
        if self._cache is not None and self._cache[0] == id(problem) and grid is None:
            return self._cache[1]
        if any(given is not None for *_, given in problem.pieces):
            raise TrajectoryError("the optimal time law does not honour waypoint times: use the quintic law")
        toppra, *_ = _toppra()
        grid = self.grid(problem) if grid is None else grid
        dof = problem.spline(np.zeros(1), 0).shape[1]
        # toppra's solver works to absolute tolerances: it is given the path on σ = s / S ∈ [0, 1]
        S = float(grid[-1])
        path = _path(lambda x, order=0: problem.spline(np.asarray(x) * S, order) * S**order, 1.0, dof)
        # the PCHIP's L'' jumps at the planned samples: both one-sided values are held there
        d1 = problem.spline(grid, 1)
        end = float(grid[-1])
        left, right = problem.spline(np.clip(grid - 1e-9, 0, end), 2), problem.spline(np.clip(grid + 1e-9, 0, end), 2)
        constraints = [
            toppra.constraint.JointVelocityConstraint(np.tile([-problem.v_max, problem.v_max], (dof, 1))),
            _force_constraint(
                np.hstack([d1, d1]) * S,
                np.hstack([left, right]) * S**2,
                np.zeros((len(grid), 2 * dof)),
                -problem.a_max,
                problem.a_max,
                self.interpolation,
            ),
        ]
        if problem.forces is not None:
            a, b, c = problem.forces(grid)
            _check_rest_forces(c, grid, problem)
            constraints.append(
                _force_constraint(a * S, b * S**2, c, problem.force_low, problem.force_high, self.interpolation)
            )
        t0 = time.perf_counter()
        algo = toppra.algorithm.TOPPRA(constraints, path, gridpoints=grid / S, solver_wrapper="seidel")
        _, sd, _ = algo.compute_parameterization(0.0, 0.0)
        self.last_solve_s = time.perf_counter() - t0
        if sd is None or not np.all(np.isfinite(sd)) or (len(sd) > 2 and not np.all(sd[1:-1] > 0)):
            raise TrajectoryError(
                "the legs' speed, acceleration and force limits allow no motion along this path (TOPP-RA: "
                "not controllable)"
            )
        sd = np.asarray(sd, dtype=float) * S
        out = (grid, sd)
        self._cache = (id(problem), out)
        return out

    def duration(self, problem: TimingProblem) -> float:
        grid, sd = self.profile(problem)
        return float(_interval_times(grid, sd).sum())

    def schedule(self, problem: TimingProblem, rate: float) -> Schedule:
        t0 = time.perf_counter()
        grid, sd = self.profile(problem)
        dt = _interval_times(grid, sd)
        total = float(dt.sum())
        count = row_counts([total], rate)[0]
        starts = np.concatenate([[0.0], np.cumsum(dt)])
        u = (sd[1:] ** 2 - sd[:-1] ** 2) / (2 * np.diff(grid))  # s̈ of each interval, consistent with ṡ²
        times = total * np.arange(count + 1) / count
        k = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, len(dt) - 1)
        tau = times - starts[k]
        s = np.minimum(grid[k] + sd[k] * tau + 0.5 * u[k] * tau**2, grid[k + 1])
        s_dot = np.maximum(sd[k] + u[k] * tau, 0.0)
        s[-1], s_dot[-1] = grid[-1], 0.0
        return Schedule(self.name, times, s, s_dot, u[k], time.perf_counter() - t0)


def _interval_times(grid: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """Duration of each grid interval at constant s̈ [s]."""
    return 2.0 * np.diff(grid) / (sd[1:] + sd[:-1])


def _check_rest_forces(c: np.ndarray, grid: np.ndarray, problem: TimingProblem) -> None:
    """A path whose static forces already leave the force limits cannot be followed at any speed."""
    over = (c > problem.force_high) | (c < problem.force_low)
    if over.any():
        k = int(np.argmax(over.any(axis=1)))
        worst = float(np.abs(c[k]).max())
        raise TrajectoryError(
            f"at s = {grid[k]:.3f} (planned sample index) the forces at rest ({worst:.2f} N) are already beyond "
            f"the force limits [{problem.force_low:g}, {problem.force_high:g}] N used by the time law"
        )
