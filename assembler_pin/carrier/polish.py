"""The carrier's joints and the stack's internal plates optimized together (the last step of
:func:`~assembler_pin.carrier.solve_on_carrier`).

One SLSQP over x = [q, ξ_1..ξ_{n-1}, s, t] from a verified placement; its answer is kept only
when SLSQP reports convergence *and* a fresh :func:`~assembler_pin.carrier.carrier_statics` of
the point holds every limit.
"""

from __future__ import annotations

import logging

import numpy as np
import pinocchio as pin

from ..config.options import GoalTolerance, OptimizeOptions
from ..constraints import leg_limit_margins
from ..kinematics import PlateArrays, leg_state, plate_deviation
from ..model.assembler import AssemblerModel
from ..optimize import SINGULAR_FORCE
from ..optimize.objective import omega
from ..statics.engine import solve_statics
from .robot import Carrier
from .statics import CarrierStatics, carrier_statics, carrier_torques

__all__ = ["JointProblem", "joint_polish"]

logger = logging.getLogger(__name__)


class JointProblem:
    """The carrier's joints and the internal plates together: x = [q, ξ_1..ξ_{n-1}, s, t],
    the plates as twists in the base plate's frame (``T_k = T_k⁰·exp6(ξ_k)``), plate n at the
    goal (``T_n = base(q)⁻¹·goal``), ``s >= |F_i|`` within the force limits and
    ``t >= |τ_k|/τ_max,k``, ``t <= 1``; every leg limit. Ω_c = w1·s + w2·sqrt(Σλ²) + w_c·t
    (w1 [1/N], w2 [1/rad] from ``options``, w_c [N]). Gradients by forward differences (one
    statics evaluation per variable)."""

    def __init__(
        self,
        am: AssemblerModel,
        carrier: Carrier,
        goal: pin.SE3,
        start: CarrierStatics,
        w_carrier: float,
        options: OptimizeOptions,
    ) -> None:
        self.am, self.carrier, self.goal, self.w_carrier = am, carrier, goal, w_carrier
        self.opts = options
        base = carrier.base_pose(start.q)
        self.ref = [base.actInv(start.state.plates.se3(k)) for k in range(am.n + 1)]
        self.nq = carrier.model.nq
        self.nx = self.nq + 6 * (am.n - 1) + 2
        self._cache: dict[bytes, np.ndarray] = {}

    def world(self, x: np.ndarray) -> tuple[np.ndarray, PlateArrays]:
        """(q, world plate poses) of the point ``x``."""
        q = x[: self.nq]
        base = self.carrier.base_pose(q)
        inner = [self.ref[k] * pin.exp6(x[self.nq + 6 * (k - 1) : self.nq + 6 * k]) for k in range(1, self.am.n)]
        rel = [self.ref[0], *inner, base.actInv(self.goal)]
        return q, PlateArrays.from_se3([base * T for T in rel])

    def vector(self, x: np.ndarray) -> np.ndarray:
        """[Ω_c, constraint rows (>= 0)...] at x (cached)."""
        key = x.tobytes()
        if key in self._cache:
            return self._cache[key]
        q, world = self.world(x)
        leg = self.am.config.leg
        legs = leg_state(self.am, world)
        statics = solve_statics(self.am, world, legs=legs)
        forces = np.where(np.isfinite(statics.forces), statics.forces, SINGULAR_FORCE).ravel()
        margins = leg_limit_margins(
            leg,
            legs.lengths,
            np.cos(legs.deflection),
            legs.rise,
            self.opts.limit_margin,
            rise_margin=self.opts.rise_margin,
        ).ravel()
        angles = plate_deviation(self.am, world).angles
        ratio = carrier_torques(self.carrier, q, world.p[0], statics.base_wrench) / self.carrier.effort_limit
        s, t = x[-2], x[-1]
        omega_c = omega(s, angles, self.opts.w1, self.opts.w2) + self.w_carrier * t
        limits = [leg.max_tension - 1e-6 - forces, forces + leg.max_compression - 1e-6]
        rows = np.concatenate([[omega_c], s - forces, s + forces, *limits, t - ratio, t + ratio, margins])
        if len(self._cache) > 512:
            self._cache.clear()
        self._cache[key] = rows
        return rows

    def jacobian(self, x: np.ndarray, step: float = 1e-7) -> np.ndarray:
        """Forward-difference Jacobian of :meth:`vector`."""
        f0 = self.vector(x)
        out = np.empty((f0.size, x.size))
        for i in range(x.size):
            xp = x.copy()
            xp[i] += step
            out[:, i] = (self.vector(xp) - f0) / step
        return out


def joint_polish(
    am: AssemblerModel,
    carrier: Carrier,
    goal: pin.SE3,
    start: CarrierStatics,
    w_carrier: float,
    options: OptimizeOptions,
    max_iterations: int,
    tolerance: GoalTolerance,
) -> tuple[CarrierStatics | None, np.ndarray, str]:
    """SLSQP over the carrier's joints and the internal plates from a valid mounted state.

    Returns:
        (statics, q, why): ``statics`` is the answer's fresh :class:`CarrierStatics` when SLSQP
        converged (status 0) to a point within every limit, else None; ``q`` the last
        iterate's joint angles [rad]; ``why`` what SLSQP said, or why its point was refused.
    """
    from scipy.optimize import minimize

    problem = JointProblem(am, carrier, goal, start, w_carrier, options)
    nq, margin = problem.nq, 1e-3
    x0 = np.zeros(problem.nx)
    x0[:nq] = np.clip(start.q, carrier.lower + margin, carrier.upper - margin)
    x0[-2], x0[-1] = start.state.max_abs_force, min(start.carrier_ratio, 1.0 - 1e-6)
    bounds = [(lo + margin, hi - margin) for lo, hi in zip(carrier.lower, carrier.upper, strict=True)]
    bounds += [(None, None)] * (6 * (am.n - 1)) + [(0.0, None), (0.0, 1.0 - 1e-6)]
    jac_cache: dict[bytes, np.ndarray] = {}

    def jac(x: np.ndarray) -> np.ndarray:
        key = x.tobytes()
        if key not in jac_cache:
            jac_cache.clear()
            jac_cache[key] = problem.jacobian(x)
        return jac_cache[key]

    rows = {"type": "ineq", "fun": lambda x: problem.vector(x)[1:], "jac": lambda x: jac(x)[1:]}
    res = minimize(
        lambda x: problem.vector(x)[0],
        x0,
        jac=lambda x: jac(x)[0],
        method="SLSQP",
        bounds=bounds,
        constraints=[rows],
        options={"maxiter": max_iterations, "ftol": options.ftol},
    )
    said = f"{res.message} ({res.nit} iterations)"
    if not np.all(np.isfinite(res.x)):
        return None, start.q, f"SLSQP returned a non-finite point: {said}"
    q = np.clip(res.x[:nq], carrier.lower, carrier.upper)
    if not res.success:
        return None, q, f"SLSQP did not converge (status {res.status}: {said})"
    _, world = problem.world(res.x)
    base = carrier.base_pose(q)
    rel = [pin.SE3.Identity()] + [base.actInv(world.se3(k)) for k in range(1, am.n + 1)]
    statics = carrier_statics(am, carrier, q, rel, goal=goal, tolerance=tolerance)
    if not statics.within_limits:
        logger.info("joint optimization converged outside the limits: %s", statics)
        return None, q, f"SLSQP converged to a point outside the limits ({said})"
    return statics, q, said
