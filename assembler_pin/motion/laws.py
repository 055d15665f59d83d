"""Time laws of a planned motion: when the stack passes each point of its leg-length path.

The path is the planned samples joined by a monotone cubic (PCHIP) in the sample index ``s``
(:mod:`.timing`): ``L(s)``, (n, 6) leg lengths [m]. A time law gives ``s(t)`` and its first
two derivatives at the output rows; the legs then move at ``L'(s) ṡ`` and accelerate at
``L''(s) ṡ² + L'(s) s̈``. Two laws stand behind one interface (:class:`TimeLaw`):

* ``quintic`` (:class:`QuinticLaw`) — one quintic ``s(t)`` from rest to rest (or one per
  waypoint segment when the path has waypoint times), the shortest that keeps every leg within
  the speed and acceleration limits: simple, smooth (zero acceleration at both ends), not
  time-optimal.
* ``optimal`` (:class:`~.toppra_law.OptimalLaw`) — the time-optimal law of TOPP-RA (``toppra``, reachability
  analysis on a grid of the path) under the legs' speed and acceleration limits and the force
  limits with the motion's own part included: each leg's force along the path is
  ``F = a(s) s̈ + b(s) ṡ² + c(s)`` (:func:`~assembler_pin.dynamics.path_force_coefficients`,
  ``c`` the statics), a second-order constraint of exactly toppra's form. The profile is
  piecewise constant in ``s̈`` between grid points, rest to rest. Another solver (Drake's
  ``Toppra``, a C++ build) can replace it by implementing :class:`TimeLaw`.

Both are held to the full limits afterwards at every output row (:mod:`.timing`).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ..config.bounds import BOUNDS
from ..exceptions import TrajectoryError

__all__ = ["TIME_LAWS", "QuinticLaw", "Schedule", "TimeLaw", "TimingProblem"]

logger = logging.getLogger(__name__)

#: The laws ``plan --time-law`` offers (``auto``: the faster valid one).
TIME_LAWS = ("quintic", "optimal")


@dataclass(frozen=True)
class TimingProblem:
    """What a time law needs.

    Attributes:
        spline: ``L(s)``: callable ``spline(s, order)`` → (len(s), 6n) [m, m, m] (PCHIP).
        samples: number of planned samples (s runs over 0 … samples-1).
        pieces: (first sample, last sample, given duration [s] or None) per rest-to-rest piece.
        v_max, a_max: leg speed [m/s] and acceleration [m/s²] limits the law keeps to.
        force_low, force_high: force limits the law keeps to [N], tension positive.
        forces: callable ``forces(s_grid)`` → (a, b, c), each (len, 6n) [N]: the leg forces
            along the path as ``a s̈ + b ṡ² + c`` (needed by laws with force limits only).
        grid_per_sample: grid points per planned step.
    """

    spline: Any
    samples: int
    pieces: list[tuple[int, int, float | None]]
    v_max: float
    a_max: float
    force_low: float = -math.inf
    force_high: float = math.inf
    forces: Any = None
    grid_per_sample: int = 16


@dataclass(frozen=True)
class Schedule:
    """A time law's answer: the path position of each output row and its derivatives.

    Attributes:
        law: the law's name.
        times: (T,) [s], from 0; s, s_dot, s_ddot: (T,) [1, 1/s, 1/s²].
        solve_time_s: wall time of the law [s].
    """

    law: str
    times: np.ndarray
    s: np.ndarray
    s_dot: np.ndarray
    s_ddot: np.ndarray
    solve_time_s: float = 0.0

    @property
    def duration(self) -> float:
        return float(self.times[-1])


class TimeLaw(Protocol):
    """A time law: ``duration`` (the motion's length [s]) and ``schedule`` (its rows at ``rate`` Hz).

    Raises (both): :class:`~assembler_pin.exceptions.TrajectoryError` with the reason when the
    limits allow no motion along the path.
    """

    name: str

    def duration(self, problem: TimingProblem) -> float: ...

    def schedule(self, problem: TimingProblem, rate: float) -> Schedule: ...


def _quintic(tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """σ(τ) = 10τ³ − 15τ⁴ + 6τ⁵ and its first two derivatives: rest to rest on [0, 1]."""
    return (
        tau**3 * (10 - 15 * tau + 6 * tau**2),
        30 * tau**2 * (1 - tau) ** 2,
        60 * tau * (1 - tau) * (1 - 2 * tau),
    )


def row_counts(durations: list[float], rate: float) -> list[int]:
    """Output intervals of each piece, after checking the duration and row bounds."""
    total = sum(durations)
    limit = BOUNDS["plan.duration"].high
    if not total <= limit:
        raise TrajectoryError(
            f"the motion would take {total:.4g} s (leg.max_speed, leg.max_acceleration, waypoint times), "
            f"over the {limit:g} s a planned motion may last (plan.duration)"
        )
    counts = [max(1, math.ceil(d * rate - 1e-9)) for d in durations]
    if sum(counts) + 1 > BOUNDS["plan.samples"].high:
        raise TrajectoryError(
            f"{sum(counts) + 1} output samples ({rate:g} Hz x {total:.4g} s) is over the "
            f"{BOUNDS['plan.samples'].high:,.0f} a trajectory may hold: lower the rate"
        )
    return counts


class QuinticLaw:
    """One quintic ``s(t)`` per rest-to-rest piece (module docstring)."""

    name = "quintic"

    @staticmethod
    def _shortest(problem: TimingProblem, s0: float, s1: float) -> float:
        """Smallest T keeping every leg within the limits: speed ``L'·span·σ'/T`` and
        acceleration ``(L''·span²·σ'² + L'·span·σ'')/T²`` on a dense grid of τ."""
        span = s1 - s0
        tau = np.linspace(0.0, 1.0, problem.grid_per_sample * round(span + 1) + 1)
        _, d_sigma, dd_sigma = _quintic(tau)
        s = s0 + span * _quintic(tau)[0]
        d1, d2 = problem.spline(s, 1), problem.spline(s, 2)
        speed = np.abs(d1 * (span * d_sigma)[:, None]).max()
        accel = np.abs(d2 * ((span * d_sigma) ** 2)[:, None] + d1 * (span * dd_sigma)[:, None]).max()
        return max(speed / problem.v_max, np.sqrt(accel / problem.a_max), 1e-9)

    def _durations(self, problem: TimingProblem) -> list[float]:
        out = []
        for i0, i1, given in problem.pieces:
            shortest = self._shortest(problem, i0, i1)
            if given is not None and shortest > given * (1 + 1e-9):
                raise TrajectoryError(
                    f"waypoint times: the segment from sample {i0} to {i1} needs at least {shortest:.4g} s "
                    f"at the legs' limits (x safety), the path gives {given:.4g} s"
                )
            out.append(shortest if given is None else given)
        return out

    def duration(self, problem: TimingProblem) -> float:
        return float(sum(self._durations(problem)))

    def schedule(self, problem: TimingProblem, rate: float) -> Schedule:
        t0 = time.perf_counter()
        durations = self._durations(problem)
        counts = row_counts(durations, rate)
        times, s, sd, sdd = [np.zeros(1)], [np.zeros(1)], [np.zeros(1)], [np.zeros(1)]
        start = 0.0
        for (i0, i1, _), d, c in zip(problem.pieces, durations, counts, strict=True):
            tau = np.arange(1, c + 1) / c
            sigma, d_sigma, dd_sigma = _quintic(tau)
            times.append(start + d * tau)
            s.append(i0 + (i1 - i0) * sigma)
            sd.append((i1 - i0) * d_sigma / d)
            sdd.append((i1 - i0) * dd_sigma / d**2)
            start += d
        sdd[0][0] = 0.0
        cat = np.concatenate
        return Schedule(self.name, cat(times), cat(s), cat(sd), cat(sdd), time.perf_counter() - t0)
