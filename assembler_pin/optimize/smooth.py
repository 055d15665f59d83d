"""The smooth method (``"slsqp"``): max|F| through an epigraph variable ``s``.

x = [poses in the local chart, s]; minimize ``w1·s + w2·sqrt(Σ λ_k²) (+ w3·Σ ΔL²)`` (the
force objective; the sag objectives replace or extend it, :class:`~assembler_pin.optimize.objective.SagObjective`)
subject to ``-s <= F_i <= s``, the force limits (on ``s`` alone when they are equal), every
leg limit, the EE tolerance, the motion step, the sag limit and, with a scene, the clearance
rows. Smooth, so SLSQP gets exact gradients
(:mod:`assembler_pin.statics.derivatives`), all from the closed-form pass of each point.
"""

from __future__ import annotations

import numpy as np

from ..state import StackState
from .objective import deviation_term_gradient, motion_cost, motion_cost_gradient, omega
from .problem import Problem, finite_rows
from .rows import EpigraphRows

__all__ = ["SmoothForm"]


class SmoothForm:
    """Objective, constraints and their derivatives of the epigraph formulation."""

    def __init__(self, problem: Problem) -> None:
        self.problem = problem
        self.epigraph = EpigraphRows()

    def x0(self, initial: StackState) -> np.ndarray:
        """The start: the reference poses and ``s`` = the start's max|F| (0 when not finite)."""
        x0 = np.zeros(self.problem.nx_pose + 1)
        x0[-1] = np.abs(initial.forces).max() if np.all(np.isfinite(initial.forces)) else 0.0
        return x0

    def fun(self, x: np.ndarray) -> float:
        """The objective with ``s`` for max|F|: ``w1·s + w2·sqrt(Σ λ²)``, the sag term, ``w3·Σ ΔL²``."""
        pr = self.problem
        p = pr.point(x[:-1])
        omega_value = omega(x[-1], p.plate_angles, pr.opts.w1, pr.opts.w2)
        sag = pr.sag(p) if pr.objective.needs_sag else 0.0
        return pr.objective.value(omega_value, sag) + motion_cost(p.lengths, pr.motion)

    def grad(self, x: np.ndarray) -> np.ndarray:
        """Gradient of :meth:`fun`."""
        pr = self.problem
        p, d = pr.point(x[:-1]), pr.derivatives(x[:-1])
        d_omega = np.zeros_like(x)
        d_omega[:-1] = pr.opts.w2 * deviation_term_gradient(p.plate_angles, d.plate_angles_sq)
        d_omega[-1] = pr.opts.w1
        d_sag = np.append(pr.sag_gradient(x[:-1]), 0.0) if pr.objective.needs_sag else None
        grad = pr.objective.gradient(d_omega, d_sag)
        grad[:-1] += motion_cost_gradient(p.lengths, d.lengths, pr.motion)
        return grad

    def cons(self, x: np.ndarray) -> np.ndarray:
        """Rows >= 0: ``s ∓ F``, the force limits, the leg limits, EE tolerance, motion step, sag,
        clearance."""
        pr = self.problem
        p, s = pr.point(x[:-1]), x[-1]
        limits = pr.force_limits.epigraph_values(p.forces, s)
        rows = [self.epigraph.values(p.forces, s), limits, pr.rows(p)["leg"], *pr.optional_rows(p)]
        return finite_rows(np.concatenate(rows))

    def cons_jac(self, x: np.ndarray) -> np.ndarray:
        """Jacobian of :meth:`cons`, in its order (last column: d/ds)."""
        pr = self.problem
        p, d = pr.point(x[:-1]), pr.derivatives(x[:-1])
        dF, ds = self.epigraph.jacobian(d)
        blocks: list[tuple[np.ndarray, float | np.ndarray]] = [(dF, ds)]
        if pr.force_limits.symmetric:
            blocks.append((np.zeros((1, x.size - 1)), -1.0))
        else:
            blocks.append((pr.force_limits.jacobian(d), 0.0))
        blocks.append((pr.leg_limits.jacobian(d), 0.0))
        if pr.ee is not None:
            blocks.append((pr.ee.jacobian(p, d.B[-6:]), 0.0))
        if pr.motion_rows is not None:
            blocks.append((pr.motion_rows.jacobian(d), 0.0))
        if pr.sag_rows is not None:
            blocks.append((pr.sag_rows.jacobian(pr.sag_gradient(x[:-1])), 0.0))
        if pr.clearance_rows is not None:
            blocks.append((pr.clearance_rows.jacobian(p, d), 0.0))
        out = np.empty((sum(block.shape[0] for block, _ in blocks), x.size))
        row = 0
        for block, d_s in blocks:
            out[row : row + block.shape[0], :-1] = block
            out[row : row + block.shape[0], -1] = d_s
            row += block.shape[0]
        return out
