"""The constraint rows of the optimizer, one family per class, each with its Jacobian.

Every family gives rows that are >= 0 when the constraint holds (``values``) and their
derivatives in chart coordinates (``jacobian``), in the same order:

* :class:`LegLimitRows` — stroke, joint deflection (as cosines, smooth) and rise
  (:func:`~assembler_pin.constraints.leg_limit_margins`, rows ``LEG_LIMIT_ROWS``);
* :class:`ForceLimitRows` — ``limit_T - F >= 0`` and ``F + limit_C >= 0``;
* :class:`EpigraphRows` — ``s - F >= 0`` and ``s + F >= 0`` (the smooth method's bound
  ``s`` on max|F|);
* :class:`EETolerance` — the EE within its position and rotation tolerance (squared norms);
* :class:`MotionRows` — ``|L_i - L_i^prev| <= max_step`` along a motion;
* :class:`SagRows` — the EE's linear sag within ``max_sag``;
* :class:`ClearanceRows` — every checked pair of bodies (the stack's own, a scene's
  obstacles and floor) at least ``clearance`` apart.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..collision.check import NEAR, Clearance, clearance
from ..collision.scene import Scene
from ..config.options import GoalTolerance
from ..config.schema import LegConfig
from ..constraints import leg_limit_margins
from ..model.assembler import AssemblerModel
from .charts import LocalChart, TaaChart
from .options import MotionTerm
from .point import ChartDerivatives, Point

__all__ = [
    "ClearanceRows",
    "EETolerance",
    "EpigraphRows",
    "ForceLimitRows",
    "LegLimitRows",
    "MotionRows",
    "SagRows",
]


class LegLimitRows:
    """Stroke, deflection and rise of every leg, ``limit_margin`` inside each limit."""

    def __init__(self, leg: LegConfig, limit_margin: float, rise_margin: float) -> None:
        self.leg, self.limit_margin, self.rise_margin = leg, limit_margin, rise_margin

    def values(self, p: Point) -> np.ndarray:
        """(5·6n,) margins [m or cos]."""
        v = p.values
        margins = leg_limit_margins(
            self.leg, v.lengths, v.cos_deflection, v.rise, self.limit_margin, rise_margin=self.rise_margin
        )
        return margins.ravel()

    def jacobian(self, d: ChartDerivatives) -> np.ndarray:
        """(5·6n, m), in the order of :meth:`values`."""
        dL = d.lengths
        d_cos = d.pose.d_cos_deflection  # (n, 6, 2, 6n)
        bottom, top = d.chart(d_cos[:, :, 0]), d.chart(d_cos[:, :, 1])
        return np.vstack([dL, -dL, bottom, top, d.chart(d.pose.d_rise)])


class ForceLimitRows:
    """Tension and compression limits [N]: ``tension_limit - F`` and ``F + compression_limit``."""

    def __init__(self, tension_limit: float, compression_limit: float) -> None:
        self.tension_limit, self.compression_limit = tension_limit, compression_limit

    @property
    def symmetric(self) -> bool:
        """Equal limits: the epigraph variable can carry them in one row."""
        return self.tension_limit == self.compression_limit

    def values(self, forces: np.ndarray) -> np.ndarray:
        """(2·6n,) [N] of the forces (n, 6) [N]."""
        F = forces.ravel()
        return np.concatenate([self.tension_limit - F, F + self.compression_limit])

    def epigraph_values(self, forces: np.ndarray, s: float) -> np.ndarray:
        """The rows of the limits in the epigraph form: one on ``s`` when the limits are equal
        (``limit - s``), else :meth:`values`."""
        return np.array([self.tension_limit - s]) if self.symmetric else self.values(forces)

    def jacobian(self, d: ChartDerivatives) -> np.ndarray:
        """(2·6n, m)."""
        return np.vstack([-d.forces, d.forces])


class EpigraphRows:
    """``s - F_i >= 0`` and ``s + F_i >= 0``: the bound ``s`` [N] on every |F_i|."""

    def values(self, forces: np.ndarray, s: float) -> np.ndarray:
        """(2·6n,) [N] of the forces (n, 6) [N]."""
        F = forces.ravel()
        return np.concatenate([s - F, s + F])

    def jacobian(self, d: ChartDerivatives) -> tuple[np.ndarray, np.ndarray]:
        """(2·6n, m) w.r.t. the poses, and (2·6n,) w.r.t. ``s``."""
        return np.vstack([-d.forces, d.forces]), np.ones(2 * d.forces.shape[0])


class EETolerance:
    """The EE within ``tolerance`` of the goal: ``(0.999999·tol_p)² - |Δp|²`` and
    ``(0.999999·tol_r)² - |Δθ|²`` (slightly inside the tolerance the final check applies)."""

    SHRINK = 1.0 - 1e-6

    def __init__(self, goal: pin.SE3, tolerance: GoalTolerance, chart: LocalChart | TaaChart) -> None:
        self.goal, self.tolerance, self.chart = goal, tolerance, chart

    def values(self, p: Point) -> np.ndarray:
        """(2,) [m², rad²]."""
        n, tol = self.chart.n, self.tolerance
        dp = p.plates.p[n] - self.goal.translation
        rot = self.chart.ee_rotation(p.x, p.plates, self.goal)
        return np.array([(self.SHRINK * tol.position) ** 2 - dp @ dp, (self.SHRINK * tol.rotation) ** 2 - rot @ rot])

    def jacobian(self, p: Point, B_ee: np.ndarray) -> np.ndarray:
        """(2, m), for the local chart (the EE rotation is its last three coordinates), from
        ``B_ee`` (6, m): the EE's world twist per chart coordinate (its rows of ``B``)."""
        n, m = self.chart.n, self.chart.size
        dp = p.plates.p[n] - self.goal.translation
        # d p_n / d(world twist) = [I, -[p_n]x]
        jp = np.hstack([np.eye(3), -pin.skew(p.plates.p[n])]) @ B_ee
        ee = np.zeros((2, m))
        ee[0] = -2.0 * dp @ jp
        ee[1, m - 3 :] = -2.0 * p.x[m - 3 :]
        return ee


class MotionRows:
    """``max_step - margin ∓ (L_i - L_i^prev) >= 0`` for every leg [m]: ``margin``
    (:data:`~assembler_pin.config.options.GEOMETRIC_MARGIN`) inside the step the final check applies,
    as the leg limits are: SLSQP honours its rows to ~1e-8, and an optimum on the step would
    otherwise be returned just outside it."""

    def __init__(self, motion: MotionTerm, margin: float) -> None:
        self.motion, self.margin = motion, float(margin)

    def values(self, p: Point) -> np.ndarray:
        """(2·6n,) [m]."""
        return self.motion.margins(p.lengths) - self.margin

    def jacobian(self, d: ChartDerivatives) -> np.ndarray:
        """(2·6n, m)."""
        return np.vstack([-d.lengths, d.lengths])


class SagRows:
    """``(0.999999·max_sag - sag) / max_sag >= 0``: the EE's linear sag
    (:func:`~assembler_pin.compliance.loaded.sag_and_gradient`) within ``max_sag`` [m], one
    dimensionless row (slightly inside the limit the final check applies)."""

    SHRINK = 1.0 - 1e-6

    def __init__(self, max_sag: float) -> None:
        self.max_sag = float(max_sag)

    def values(self, sag: float) -> np.ndarray:
        """(1,) from the sag [m] at the point."""
        return np.array([(self.SHRINK * self.max_sag - sag) / self.max_sag])

    def jacobian(self, d_sag: np.ndarray) -> np.ndarray:
        """(1, m) from the sag's chart gradient (m,) [m per chart unit]."""
        return -d_sag[None, :] / self.max_sag


class ClearanceRows:
    """``min(d - clearance - margin, BAND) >= 0`` for the pairs of bodies
    :func:`~assembler_pin.collision.check.clearance` checks [m]: the stack's own pairs and,
    with a scene, every body against every obstacle and the floor.

    The count of rows is fixed for a run, as SLSQP needs: one row for each pair within
    ``BAND + REACH`` of its bound at the run's start (its own row), and one more row for the
    nearest of all the other pairs (the smallest of their values, its gradient the nearest
    pair's), so that no pair is left unguarded while the solver's work grows with the near
    pairs only (a four-platform stack among ten obstacles: ~85 rows of ~680). A pair farther
    than ``BAND`` beyond its bound is held at ``BAND`` with a zero gradient, so only the pairs
    within the band move the solver, and pairs the clearance only bounds from below (beyond
    ``NEAR``) are never read. Each row's gradient is
    :meth:`~assembler_pin.collision.check.Clearance.gradient` (per world twist of the plates,
    the envelope theorem) through the chart's twist Jacobian ``B``; the tests hold it to
    central differences. A row is the smallest of a leg pair's capsule pairs, and the last row
    the smallest of the far pairs: continuous, with a kink where the closest pair switches,
    which SLSQP's line search tolerates.
    """

    #: Rows beyond this distance from their bound are held constant [m] (within ``NEAR``, so
    #: every row in the band is an exact distance).
    BAND = 0.5 * NEAR
    #: Pairs within ``BAND + REACH`` of their bound at the start have their own row [m].
    REACH = 0.1

    def __init__(self, am: AssemblerModel, scene: Scene | None, margin: float, start: Clearance | None = None) -> None:
        """``start``: the clearance of the run's start in ``scene`` (its near pairs get their
        own rows); None: every pair has its own row."""
        self.am, self.scene, self.margin = am, scene, float(margin)
        self._last: tuple[Point, Clearance] | None = None
        self.own: np.ndarray | None = None  # the pairs with their own row (None: all)
        self.rest: np.ndarray = np.zeros(0, dtype=int)  # the pairs guarded by the last row
        if start is not None:
            c = start
            near = c.distances - (c.limit + self.margin) < self.BAND + self.REACH
            self.own, self.rest = np.flatnonzero(near), np.flatnonzero(~near)

    def measure(self, p: Point) -> Clearance:
        """The clearance at the point (computed once per point)."""
        if self._last is None or self._last[0] is not p:
            self._last = (p, clearance(self.am, p.plates, self.scene))
        return self._last[1]

    def _all(self, p: Point) -> tuple[Clearance, np.ndarray]:
        c = self.measure(p)
        return c, np.minimum(c.distances - (c.limit + self.margin), self.BAND)

    def values(self, p: Point) -> np.ndarray:
        """(rows,) [m]: the own rows, then the nearest of the rest (when there is a rest)."""
        _, v = self._all(p)
        if self.own is None:
            return v
        tail = [float(v[self.rest].min())] if len(self.rest) else []
        return np.concatenate([v[self.own], tail])

    def jacobian(self, p: Point, d: ChartDerivatives) -> np.ndarray:
        """(rows, m), in the order of :meth:`values`: zero outside the band."""
        c, v = self._all(p)
        pairs = np.arange(len(v)) if self.own is None else self.own
        if self.own is not None and len(self.rest):
            pairs = np.append(pairs, self.rest[int(np.argmin(v[self.rest]))])
        near = np.flatnonzero(v[pairs] < self.BAND)
        out = np.zeros((len(pairs), d.B.shape[1]))
        if len(near):
            world = c.gradient(pairs[near])[:, 1:, :].reshape(len(near), -1)  # plates 1..n (plate 0 is fixed)
            out[near] = d.chart(world)
        return out
