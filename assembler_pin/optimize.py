"""Force-optimized internal poses (paper §IV): choose the intermediate plate poses that
minimize the largest actuator force, subject to every physical constraint.

Decision variables: the poses of plates 1..n-1, each as a twist ``x_k`` in a fixed chart
around its starting pose, ``T_k = T_k⁰ · exp6(x_k)`` (local frame; plate 0 stays put).
Plate n sits at the goal; when the user allows an end-effector tolerance it becomes a
variable too, ``T_n = T_goal · exp6(x_n)``, with ``|x_n[3:]| <= rotation tolerance`` and
``|p_n - p_goal| <= position tolerance``.

Objective (paper eq. 10): ``Ω = w1·max|F| + w2·sqrt(Σ λ_k²)``, with λ_k the angle between
``p_k - p_{k-1}`` and the rest direction of plate k on plate k-1 (eq. 9).

Methods:

* ``"slsqp"`` (default): max|F| through an epigraph variable ``s`` (``-s <= F_i <= s``),
  so the problem is smooth, and analytic gradients of every force, length, deflection and
  angle (:mod:`assembler_pin.gradients`) — scipy's SLSQP.
* ``"paper"``: the paper's literal formulation — the non-smooth ``max`` in the objective,
  the poses as TAA vectors in the world frame, gradients by scipy's finite differences —
  kept as the baseline to compare against.

Constraints (all methods): leg lengths, joint deflection (as cosines, smooth), tension and
compression limits (each also capped by the start's max|F|, so max|F| never increases),
continuous translation (every top joint at least ``rise_margin``
above its bottom joint in the bottom plate's frame), end effector within tolerance.

The result never calls a constraint-violating state a success: the returned state is the
best *feasible* one met (checked again with the Pinocchio statics), the initial one when
nothing better was found, with the reason.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from scipy.optimize import minimize

from .constraints import GoalTolerance
from .gradients import PoseDerivatives, pose_derivatives
from .kinematics import PlateArrays, leg_state, plate_arrays
from .model import AssemblerModel
from .state import StackState, evaluate_state
from .statics import solve_statics

__all__ = ["METHODS", "OptimizeOptions", "OptimizeResult", "objective_value", "optimize_internal_poses"]

logger = logging.getLogger(__name__)

METHODS = ("slsqp", "paper")


@dataclass(frozen=True)
class OptimizeOptions:
    """Settings of :func:`optimize_internal_poses`.

    Attributes:
        method: ``"slsqp"`` (smooth epigraph form, analytic gradients) or ``"paper"``.
        w1: weight of max|F| [1/N]; w2: weight of the plate-deviation term [1/rad].
        ee_tolerance: allow the EE plate to move this far from the goal (position [m],
            rotation [rad]); None keeps it exactly at the goal.
        max_iterations: solver iteration limit.
        ftol: solver's convergence tolerance on the objective.
        rise_margin: smallest rise of a top joint above its bottom joint [m].
        goal_tolerance: tolerance the final state is checked against when the EE is fixed.
    """

    method: str = "slsqp"
    w1: float = 1.0
    w2: float = 1.0
    ee_tolerance: GoalTolerance | None = None
    max_iterations: int = 200
    ftol: float = 1e-7
    rise_margin: float = 1e-3
    goal_tolerance: GoalTolerance = field(default_factory=lambda: GoalTolerance(1e-9, 1e-9))

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ValueError(f"method must be one of {', '.join(METHODS)}, got {self.method!r}")
        if self.w1 < 0 or self.w2 < 0 or self.w1 + self.w2 == 0:
            raise ValueError("weights w1, w2 must be >= 0 and not both 0")
        if self.max_iterations < 1:
            raise ValueError("max_iterations must be >= 1")


@dataclass
class OptimizeResult:
    """Outcome of an internal-pose optimization.

    Attributes:
        success: the solver converged and the returned state satisfies every constraint.
        message: what happened, and why not when it failed.
        status, solver_message: scipy's own status code and message.
        iterations, evaluations, gradient_evaluations: solver counters.
        time_s: wall time of the optimization [s].
        initial, optimized: the starting state and the best feasible state found (the
            initial one when nothing better was found).
        objective_initial, objective_optimized: Ω of both states.
        method: the method used.
    """

    success: bool
    message: str
    status: int
    solver_message: str
    iterations: int
    evaluations: int
    gradient_evaluations: int
    time_s: float
    initial: StackState
    optimized: StackState
    objective_initial: float
    objective_optimized: float
    method: str


def plate_deviation(pa: PlateArrays, am: AssemblerModel) -> np.ndarray:
    """λ_k, k = 1..n: angle between ``p_k - p_{k-1}`` and plate k's rest direction on
    plate k-1 (paper eq. 9) [rad]."""
    rest = np.array([m.translation for m in am.plate_joint_placement[1:]])
    rest_dir = np.matmul(pa.R[:-1], (rest / np.linalg.norm(rest, axis=1, keepdims=True))[..., None])[..., 0]
    step = pa.p[1:] - pa.p[:-1]
    cross = np.linalg.norm(np.cross(step, rest_dir), axis=1)
    return np.arctan2(cross, np.einsum("jk,jk->j", step, rest_dir))


def objective_value(am: AssemblerModel, state: StackState, w1: float = 1.0, w2: float = 1.0) -> float:
    """Ω = w1·max|F| + w2·sqrt(Σ λ_k²) of a state (paper eq. 10)."""
    lam = plate_deviation(state.plates, am)
    return float(w1 * state.max_abs_force + w2 * np.sqrt(np.sum(lam**2)))


class _Problem:
    """Maps decision vectors to plate poses and evaluates the constraint set."""

    def __init__(self, am: AssemblerModel, start: PlateArrays, goal: pin.SE3, opts: OptimizeOptions):
        self.am, self.opts, self.goal = am, opts, goal
        self.n = am.n
        self.free_ee = opts.ee_tolerance is not None
        self.movable = list(range(1, self.n)) + ([self.n] if self.free_ee else [])
        self.ref = [start.se3(k) for k in range(self.n + 1)]
        self.ref[self.n] = goal
        self.nx_pose = 6 * len(self.movable)
        leg = am.config.leg
        self.cos_max = np.cos(leg.max_deflection)
        # never accept a larger max|F| than the start: cap both force limits by it
        start_max = float(np.abs(solve_statics(am, start).forces).max())
        self.tension_limit = min(leg.max_tension, start_max)
        self.compression_limit = min(leg.max_compression, start_max)
        self.best: tuple[float, np.ndarray] | None = None
        self.evaluations = 0
        self.gradient_evaluations = 0
        self._cache: dict[bytes, object] = {}

    # ----------------------------------------------------------- pose maps
    def plates_local(self, x: np.ndarray) -> PlateArrays:
        """Chart of the smooth method: T_k = T_k⁰ exp6(x_k)."""
        poses = list(self.ref)
        for slot, k in enumerate(self.movable):
            poses[k] = self.ref[k] * pin.exp6(x[6 * slot : 6 * slot + 6])
        return PlateArrays(np.array([m.rotation for m in poses]), np.array([m.translation for m in poses]))

    def plates_taa(self, x: np.ndarray) -> PlateArrays:
        """Chart of the paper method: world TAA (p, rotation vector) of each movable plate."""
        R = np.array([m.rotation for m in self.ref])
        p = np.array([m.translation for m in self.ref])
        for slot, k in enumerate(self.movable):
            p[k] = x[6 * slot : 6 * slot + 3]
            R[k] = pin.exp3(x[6 * slot + 3 : 6 * slot + 6])
        return PlateArrays(R, p)

    def taa_start(self) -> np.ndarray:
        return np.concatenate(
            [np.concatenate([self.ref[k].translation, pin.log3(self.ref[k].rotation)]) for k in self.movable]
        )

    # ----------------------------------------------------------- constraints
    def _physical(self, forces, lengths, cos_defl, rise) -> np.ndarray:
        """Every physical constraint as g(x) >= 0 (with tiny margins inside the limits)."""
        leg = self.am.config.leg
        return np.concatenate(
            [
                (leg.max_tension - 1e-6) - forces.ravel(),
                forces.ravel() + (leg.max_compression - 1e-6),
                lengths.ravel() - (leg.min_length + 1e-9),
                (leg.max_length - 1e-9) - lengths.ravel(),
                cos_defl.ravel() - (self.cos_max + 1e-9),
                rise.ravel() - self.opts.rise_margin,
            ]
        )

    def _ee(self, pa: PlateArrays, x: np.ndarray) -> np.ndarray:
        if not self.free_ee:
            return np.zeros(0)
        tol = self.opts.ee_tolerance
        dp = pa.p[self.n] - self.goal.translation
        if self.opts.method == "paper":
            rot = pin.log3(self.goal.rotation.T @ pa.R[self.n])
        else:
            rot = x[self.nx_pose - 3 : self.nx_pose]
        shrink = 1.0 - 1e-6  # stay strictly inside the tolerance the final check applies
        return np.array([(shrink * tol.position) ** 2 - dp @ dp, (shrink * tol.rotation) ** 2 - rot @ rot])

    def _track(self, x: np.ndarray, physical: np.ndarray, ee: np.ndarray, omega: float) -> None:
        if np.all(physical >= 0) and np.all(ee >= 0) and (self.best is None or omega < self.best[0]):
            self.best = (omega, x.copy())

    # ----------------------------------------------------------- smooth method
    def smooth(self, x: np.ndarray) -> tuple[PoseDerivatives, PlateArrays, np.ndarray]:
        key = x.tobytes()
        hit = self._cache.get(key)
        if hit is None:
            pa = self.plates_local(x)
            d = pose_derivatives(self.am, pa)
            # world twist of plate k per chart coordinate: Ad(T_k) · Jexp6(x_k)
            B = np.zeros((6 * self.n, self.nx_pose))
            for slot, k in enumerate(self.movable):
                xk = x[6 * slot : 6 * slot + 6]
                B[6 * (k - 1) : 6 * k, 6 * slot : 6 * slot + 6] = pa.se3(k).action @ pin.Jexp6(xk)
            hit = (d, pa, B)
            self._cache = {key: hit}
            self.evaluations += 1
            o = self.opts
            omega = o.w1 * np.abs(d.forces).max() + o.w2 * np.sqrt(np.sum(d.plate_angles**2))
            self._track(x[:-1], self._physical(d.forces, d.lengths, d.cos_deflection, d.rise), self._ee(pa, x), omega)
        return hit

    def smooth_fun(self, x: np.ndarray) -> float:
        d, _, _ = self.smooth(x)
        return float(self.opts.w1 * x[-1] + self.opts.w2 * np.sqrt(np.sum(d.plate_angles**2)))

    def smooth_grad(self, x: np.ndarray) -> np.ndarray:
        d, _, B = self.smooth(x)
        self.gradient_evaluations += 1
        grad = np.zeros_like(x)
        s = np.sqrt(np.sum(d.plate_angles**2))
        if s > 1e-12:
            grad[:-1] = self.opts.w2 * (0.5 / s) * (d.d_plate_angles_sq.sum(axis=0) @ B)
        grad[-1] = self.opts.w1
        return grad

    def smooth_cons(self, x: np.ndarray) -> np.ndarray:
        d, pa, _ = self.smooth(x)
        F = d.forces.ravel()
        return np.concatenate(
            [x[-1] - F, x[-1] + F, self._physical(d.forces, d.lengths, d.cos_deflection, d.rise), self._ee(pa, x[:-1])]
        )

    def smooth_cons_jac(self, x: np.ndarray) -> np.ndarray:
        d, pa, B = self.smooth(x)
        C = 6 * self.n
        dF = d.d_forces.reshape(-1, C) @ B
        dL = d.d_lengths.reshape(-1, C) @ B
        dc = d.d_cos_deflection.reshape(-1, C) @ B
        dr = d.d_rise.reshape(-1, C) @ B
        m = dF.shape[0]
        ones = np.ones((m, 1))
        zeros = np.zeros((m, 1))
        rows = [
            np.hstack([-dF, ones]),
            np.hstack([dF, ones]),
            np.hstack([-dF, zeros]),
            np.hstack([dF, zeros]),
            np.hstack([dL, zeros]),
            np.hstack([-dL, zeros]),
            np.hstack([dc, np.zeros((dc.shape[0], 1))]),
            np.hstack([dr, zeros]),
        ]
        if self.free_ee:
            k = self.n
            dp = pa.p[k] - self.goal.translation
            # d p_n / d(world twist) = [I, -[p_n]x]
            jp = np.hstack([np.eye(3), -pin.skew(pa.p[k])]) @ B[6 * (k - 1) : 6 * k]
            ee = np.zeros((2, x.size))
            ee[0, :-1] = -2.0 * dp @ jp
            ee[1, self.nx_pose - 3 : self.nx_pose] = -2.0 * x[self.nx_pose - 3 : self.nx_pose]
            rows.append(ee)
        return np.vstack(rows)

    # ----------------------------------------------------------- paper method
    def paper_values(self, x: np.ndarray) -> tuple[float, np.ndarray]:
        key = x.tobytes()
        hit = self._cache.get(key)
        if hit is None:
            pa = self.plates_taa(x)
            legs = leg_state(self.am, pa)
            forces = solve_statics(self.am, pa).forces
            lam = plate_deviation(pa, self.am)
            omega = self.opts.w1 * np.abs(forces).max() + self.opts.w2 * np.sqrt(np.sum(lam**2))
            physical = self._physical(forces, legs.lengths, np.cos(legs.deflection), legs.rise)
            ee = self._ee(pa, x)
            self._track(x, physical, ee, omega)
            hit = (float(omega), np.concatenate([physical, ee]))
            self._cache = {key: hit}
            self.evaluations += 1
        return hit


def optimize_internal_poses(
    am: AssemblerModel,
    initial: StackState | PlateArrays | list,
    goal: pin.SE3 | None = None,
    options: OptimizeOptions | None = None,
) -> OptimizeResult:
    """Minimize Ω over the intermediate plate poses, from a valid initial state.

    Args:
        initial: the starting pose (a state or plate poses), e.g. the helper-arm initial
            condition; plate n is taken as the goal unless ``goal`` is given.
        goal: the EE goal pose (default: the initial state's plate n).
        options: see :class:`OptimizeOptions`.
    """
    opts = options or OptimizeOptions()
    start = initial.plates if isinstance(initial, StackState) else plate_arrays(am, initial)
    goal = start.se3(am.n) if goal is None else goal
    check_tol = opts.ee_tolerance or opts.goal_tolerance
    initial_state = evaluate_state(am, start, goal=goal, tolerance=check_tol)
    omega0 = objective_value(am, initial_state, opts.w1, opts.w2)
    problem = _Problem(am, start, goal, opts)
    t0 = time.perf_counter()
    if opts.method == "slsqp":
        x0 = np.zeros(problem.nx_pose + 1)
        x0[-1] = np.abs(initial_state.forces).max()
        res = minimize(
            problem.smooth_fun,
            x0,
            jac=problem.smooth_grad,
            method="SLSQP",
            constraints=[{"type": "ineq", "fun": problem.smooth_cons, "jac": problem.smooth_cons_jac}],
            options={"maxiter": opts.max_iterations, "ftol": opts.ftol},
        )
        to_plates = problem.plates_local
        x_final = res.x[:-1]
    else:
        x0 = problem.taa_start()
        res = minimize(
            lambda x: problem.paper_values(x)[0],
            x0,
            method="SLSQP",
            constraints=[{"type": "ineq", "fun": lambda x: problem.paper_values(x)[1]}],
            options={"maxiter": opts.max_iterations, "ftol": opts.ftol},
        )
        to_plates = problem.plates_taa
        x_final = res.x
    elapsed = time.perf_counter() - t0

    # candidates: the solver's answer and the best feasible point met; keep the best
    # one that the Pinocchio statics confirm feasible, never worse than the start
    candidates = [x_final] + ([problem.best[1]] if problem.best is not None else [])
    chosen, omega_chosen = initial_state, omega0
    for x in candidates:
        pad = np.concatenate([x, [0.0]]) if opts.method == "slsqp" else x
        state = evaluate_state(am, to_plates(pad), goal=goal, tolerance=check_tol)
        omega = objective_value(am, state, opts.w1, opts.w2)
        no_worse = state.max_abs_force <= initial_state.max_abs_force + 1e-9
        if state.feasible and (not chosen.feasible or (omega < omega_chosen and no_worse)):
            chosen, omega_chosen = state, omega
    converged = bool(res.success)
    if chosen is initial_state:
        if not initial_state.feasible:
            message = "no feasible state found: " + ("; ".join(str(v) for v in initial_state.violations[:3]))
        else:
            message = "the optimizer found no better feasible state than the initial one"
        if not converged:
            message += f" (solver: {res.message})"
        success = False if not initial_state.feasible else converged
    else:
        success = converged and chosen.feasible
        message = "converged" if success else f"solver did not converge ({res.message}); best feasible state returned"
    logger.info(
        "optimize[%s]: %s, Ω %.4g -> %.4g in %.3f s, %d iterations",
        opts.method,
        message,
        omega0,
        omega_chosen,
        elapsed,
        res.nit,
    )
    return OptimizeResult(
        success=success,
        message=message,
        status=int(res.status),
        solver_message=str(res.message),
        iterations=int(res.nit),
        evaluations=problem.evaluations,
        gradient_evaluations=problem.gradient_evaluations,
        time_s=elapsed,
        initial=initial_state,
        optimized=chosen,
        objective_initial=omega0,
        objective_optimized=omega_chosen,
        method=opts.method,
    )
