"""The paper's literal formulation (``"paper"``), kept as the baseline to compare against.

x = the world TAA poses of the movable plates (:class:`~.charts.TaaChart`); minimize the
non-smooth ``Ω = w1·max|F| + w2·sqrt(Σ λ_k²)`` (paper eq. 10) with the plain force limits,
every leg limit and the EE tolerance; gradients by scipy's finite differences.
"""

from __future__ import annotations

import numpy as np

from ..state import StackState
from .objective import omega
from .problem import Problem, finite_rows

__all__ = ["PaperForm"]


class PaperForm:
    """Objective and constraints of the paper's formulation (no derivatives)."""

    def __init__(self, problem: Problem) -> None:
        self.problem = problem

    def x0(self, initial: StackState) -> np.ndarray:
        """The start's TAA poses."""
        return self.problem.chart.start()

    def fun(self, x: np.ndarray) -> float:
        """Ω (paper eq. 10)."""
        pr = self.problem
        p = pr.point(x)
        return omega(p.max_abs_force, p.plate_angles, pr.opts.w1, pr.opts.w2)

    def cons(self, x: np.ndarray) -> np.ndarray:
        """Rows >= 0: the force limits, the leg limits, the EE tolerance, the clearance."""
        pr = self.problem
        p = pr.point(x)
        rows = pr.rows(p)
        extra = [rows[k] for k in ("ee", "clearance") if k in rows]
        return finite_rows(np.concatenate([rows["force"], rows["leg"], *extra]))
