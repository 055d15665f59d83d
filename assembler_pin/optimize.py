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
compression limits (for ``slsqp`` also capped by the start's max|F|, so max|F| never increases),
continuous translation (every top joint at least ``rise_margin``
above its bottom joint in the bottom plate's frame), end effector within tolerance.

Along a motion (:mod:`assembler_pin.motion`) a :class:`MotionTerm` adds the paper's
"minimum required movement": ``w3·Σ (L_i - L_i^prev)²`` in the objective and, as
constraints, ``|L_i - L_i^prev| <= max_step`` for every leg (slsqp only).

The result never calls a constraint-violating state a success: the returned state is the
best *feasible* one met (checked again with the Pinocchio statics), the initial one when
nothing better was found, with the reason.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import pinocchio as pin

from .constraints import leg_limit_margins
from .exceptions import OptionsError, SingularConfigurationError, _SingularIterateError
from .gradients import PoseDerivatives, pose_derivatives
from .kinematics import LegState, PlateArrays, checked_goal, leg_state, plate_arrays, plate_deviation
from .messages import binding, describe, one_line
from .model import AssemblerModel, checked_model
from .options import METHODS, OptimizeOptions, checked_options
from .state import StackState, evaluate_state
from .statics import solve_statics
from .threads import one_blas_thread
from .validation import is_number

__all__ = [
    "METHODS",
    "MotionTerm",
    "OptimizeOptions",
    "OptimizeResult",
    "objective_value",
    "optimize_internal_poses",
]

logger = logging.getLogger(__name__)

#: Forces [N] standing in for the statics at a singular trial point: finite (SLSQP cannot
#: handle NaN) and far outside every force limit, so such a step is infeasible.
SINGULAR_FORCE = 1e6


@dataclass(frozen=True)
class MotionTerm:
    """Continuity with the previous sample of a motion.

    Attributes:
        previous_lengths: (n, 6) leg lengths of the previous sample [m].
        max_step: largest change of any leg length from it [m] (> 0).
        w3: weight of Σ ΔL² in the objective [1/m²] (>= 0).
    """

    previous_lengths: np.ndarray
    max_step: float
    w3: float = 0.0

    def __post_init__(self) -> None:
        if not (is_number(self.max_step) and 0 < self.max_step < math.inf):
            raise OptionsError(f"max_step must be a finite number > 0 [m], got {self.max_step!r}")
        if not (is_number(self.w3) and 0 <= self.w3 < math.inf):
            raise OptionsError(f"w3 must be a finite number >= 0 [1/m^2], got {self.w3!r}")
        prev = np.asarray(self.previous_lengths, dtype=float)
        if prev.ndim != 2 or prev.shape[1] != 6 or not np.all(np.isfinite(prev)):
            raise OptionsError(f"previous_lengths must be a finite (n, 6) array [m], got shape {prev.shape}")
        object.__setattr__(self, "previous_lengths", prev)

    def margins(self, lengths: np.ndarray) -> np.ndarray:
        """Rows >= 0 when every leg moved at most ``max_step``: (2·6n,)."""
        step = (lengths - self.previous_lengths).ravel()
        return np.concatenate([self.max_step - step, self.max_step + step])


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

    def __repr__(self) -> str:
        return (
            f"OptimizeResult(success={self.success}, method={self.method!r}, max|F| "
            f"{self.initial.max_abs_force:.3f} → {self.optimized.max_abs_force:.3f} N, "
            f"Ω {self.objective_initial:.3f} → {self.objective_optimized:.3f}, {self.iterations} iterations, "
            f"{1e3 * self.time_s:.1f} ms, "
            f"message={self.message!r})"
        )


def objective_value(am: AssemblerModel, state: StackState, w1: float = 1.0, w2: float = 1.0) -> float:
    """Ω = w1·max|F| + w2·sqrt(Σ λ_k²) of a state (paper eq. 10)."""
    lam = plate_deviation(am, state.plates).angles
    return float(w1 * state.max_abs_force + w2 * np.sqrt(np.sum(lam**2)))


@dataclass(frozen=True)
class _Values:
    """What the constraints and the objective read at one point."""

    plates: PlateArrays
    forces: np.ndarray  # (n, 6) [N], Pinocchio statics
    lengths: np.ndarray
    cos_deflection: np.ndarray  # (n, 6, 2)
    rise: np.ndarray
    plate_angles: np.ndarray  # (n,) [rad]


class _Problem:
    """Maps decision vectors to plate poses and evaluates objective and constraints.

    Values come from the Pinocchio statics and the plain kinematics; derivatives (only
    where the solver asks for them) from :func:`~assembler_pin.gradients.pose_derivatives`.
    """

    def __init__(
        self,
        am: AssemblerModel,
        start: PlateArrays,
        goal: pin.SE3,
        opts: OptimizeOptions,
        start_feasible: bool,
        motion: MotionTerm | None = None,
    ):
        self.am, self.opts, self.goal, self.motion = am, opts, goal, motion
        self.n = am.n
        self.free_ee = opts.ee_tolerance is not None
        self.movable = list(range(1, self.n)) + ([self.n] if self.free_ee else [])
        self.ref = [start.se3(k) for k in range(self.n + 1)]
        self.ref[self.n] = goal
        self.nx_pose = 6 * len(self.movable)
        leg = am.config.leg
        # from a feasible start the smooth method never accepts a larger max|F|: both force
        # limits are capped by it (the paper's literal formulation keeps the plain limits)
        self.start_max_force = float(np.abs(self._forces(start, leg_state(am, start))).max())
        cap = self.start_max_force if opts.method == "slsqp" and start_feasible else np.inf
        self.tension_limit = min(leg.max_tension, cap) - 1e-6
        self.compression_limit = min(leg.max_compression, cap) - 1e-6
        # with equal limits the epigraph variable s carries them: one row s <= limit
        self.symmetric_limits = self.tension_limit == self.compression_limit
        self.best: tuple[float, np.ndarray] | None = None
        self.evaluations = 0
        self.gradient_evaluations = 0
        self._values: tuple[bytes, _Values] | None = None
        self._derivs: tuple[bytes, PoseDerivatives, np.ndarray] | None = None

    # ----------------------------------------------------------- pose maps
    def plates_local(self, x: np.ndarray) -> PlateArrays:
        """Chart of the smooth method: T_k = T_k⁰ exp6(x_k)."""
        poses = list(self.ref)
        for slot, k in enumerate(self.movable):
            poses[k] = self.ref[k] * pin.exp6(x[6 * slot : 6 * slot + 6])
        return PlateArrays.from_se3(poses)

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

    # ----------------------------------------------------------- evaluation
    def values(self, x_pose: np.ndarray) -> _Values:
        """Values at the pose part of x (cached for the last point); tracks the best feasible."""
        key = x_pose.tobytes()
        if self._values is not None and self._values[0] == key:
            return self._values[1]
        pa = self.plates_taa(x_pose) if self.opts.method == "paper" else self.plates_local(x_pose)
        legs = leg_state(self.am, pa)
        v = _Values(
            pa,
            self._forces(pa, legs),
            legs.lengths,
            np.cos(legs.deflection),
            legs.rise,
            plate_deviation(self.am, pa).angles,
        )
        self._values = (key, v)
        self.evaluations += 1
        omega = self.opts.w1 * np.abs(v.forces).max() + self.opts.w2 * np.sqrt(np.sum(v.plate_angles**2))
        omega += self._motion_cost(v)
        feasible = (
            np.all(self._geometric(v) >= 0)
            and np.all(self._force_rows(v.forces) >= 0)
            and np.all(self._ee(v.plates, x_pose) >= 0)
            and np.all(self._motion(v) >= 0)
        )
        if feasible and (self.best is None or omega < self.best[0]):
            self.best = (omega, x_pose.copy())
        return v

    def _forces(self, pa: PlateArrays, legs: LegState) -> np.ndarray:
        """Actuator forces [N]; :data:`SINGULAR_FORCE` where the statics are not defined, so
        that a singular trial point is an infeasible step rather than an exception or NaN."""
        try:
            forces = solve_statics(self.am, pa, legs=legs).forces
        except (np.linalg.LinAlgError, SingularConfigurationError):
            return np.full((self.n, 6), SINGULAR_FORCE)
        return np.where(np.isfinite(forces), forces, SINGULAR_FORCE)

    def derivatives(self, x_pose: np.ndarray) -> tuple[PoseDerivatives, np.ndarray]:
        """Derivatives at x and B = d(world twists of plates 1..n)/d(chart coordinates)."""
        key = x_pose.tobytes()
        if self._derivs is not None and self._derivs[0] == key:
            return self._derivs[1], self._derivs[2]
        pa = self.values(x_pose).plates
        try:
            d = pose_derivatives(self.am, pa)
        except (np.linalg.LinAlgError, SingularConfigurationError) as exc:
            raise _SingularIterateError(str(exc)) from None
        # world twist of plate k per chart coordinate: Ad(T_k) · Jexp6(x_k)
        B = np.zeros((6 * self.n, self.nx_pose))
        for slot, k in enumerate(self.movable):
            B[6 * (k - 1) : 6 * k, 6 * slot : 6 * slot + 6] = pa.se3(k).action @ pin.Jexp6(
                x_pose[6 * slot : 6 * slot + 6]
            )
        self._derivs = (key, d, B)
        self.gradient_evaluations += 1
        return d, B

    # ----------------------------------------------------------- constraint rows (>= 0)
    def _geometric(self, v: _Values) -> np.ndarray:
        """Stroke, deflection and rise rows (:func:`leg_limit_margins`, ``limit_margin`` inside)."""
        margins = leg_limit_margins(
            self.am.config.leg,
            v.lengths,
            v.cos_deflection,
            v.rise,
            self.opts.limit_margin,
            rise_margin=self.opts.rise_margin,
        )
        return margins.ravel()

    def _geometric_jac(self, d: PoseDerivatives, B: np.ndarray) -> np.ndarray:
        """Rows of :meth:`_geometric` differentiated, in its order (see :data:`LEG_LIMIT_ROWS`)."""
        C = 6 * self.n
        dL = d.d_lengths.reshape(-1, C) @ B
        d_cos = d.d_cos_deflection  # (n, 6, 2, C)
        bottom, top = d_cos[:, :, 0].reshape(-1, C) @ B, d_cos[:, :, 1].reshape(-1, C) @ B
        return np.vstack([dL, -dL, bottom, top, d.d_rise.reshape(-1, C) @ B])

    def _force_rows(self, forces: np.ndarray) -> np.ndarray:
        F = forces.ravel()
        return np.concatenate([self.tension_limit - F, F + self.compression_limit])

    def _motion(self, v: _Values) -> np.ndarray:
        return np.zeros(0) if self.motion is None else self.motion.margins(v.lengths)

    def _motion_cost(self, v: _Values) -> float:
        if self.motion is None or self.motion.w3 == 0.0:
            return 0.0
        return float(self.motion.w3 * np.sum((v.lengths - self.motion.previous_lengths) ** 2))

    def _ee(self, pa: PlateArrays, x_pose: np.ndarray) -> np.ndarray:
        if not self.free_ee:
            return np.zeros(0)
        tol = self.opts.ee_tolerance
        assert tol is not None  # free_ee: the EE may move within ee_tolerance
        dp = pa.p[self.n] - self.goal.translation
        if self.opts.method == "paper":
            rot = pin.log3(self.goal.rotation.T @ pa.R[self.n])
        else:
            rot = x_pose[self.nx_pose - 3 : self.nx_pose]
        shrink = 1.0 - 1e-6  # stay strictly inside the tolerance the final check applies
        return np.array([(shrink * tol.position) ** 2 - dp @ dp, (shrink * tol.rotation) ** 2 - rot @ rot])

    def _ee_jac(self, pa: PlateArrays, x_pose: np.ndarray, B: np.ndarray) -> np.ndarray:
        k = self.n
        dp = pa.p[k] - self.goal.translation
        # d p_n / d(world twist) = [I, -[p_n]x]
        jp = np.hstack([np.eye(3), -pin.skew(pa.p[k])]) @ B[6 * (k - 1) : 6 * k]
        ee = np.zeros((2, self.nx_pose))
        ee[0] = -2.0 * dp @ jp
        ee[1, self.nx_pose - 3 :] = -2.0 * x_pose[self.nx_pose - 3 :]
        return ee

    # ----------------------------------------------------------- smooth method (x = [poses, s])
    def smooth_fun(self, x: np.ndarray) -> float:
        v = self.values(x[:-1])
        return float(self.opts.w1 * x[-1] + self.opts.w2 * np.sqrt(np.sum(v.plate_angles**2)) + self._motion_cost(v))

    def smooth_grad(self, x: np.ndarray) -> np.ndarray:
        v = self.values(x[:-1])
        d, B = self.derivatives(x[:-1])
        grad = np.zeros_like(x)
        s = np.sqrt(np.sum(v.plate_angles**2))
        if s > 1e-12:
            grad[:-1] = self.opts.w2 * (0.5 / s) * (d.d_plate_angles_sq.sum(axis=0) @ B)
        if self.motion is not None and self.motion.w3 > 0.0:
            step = (v.lengths - self.motion.previous_lengths).ravel()
            grad[:-1] += 2.0 * self.motion.w3 * step @ (d.d_lengths.reshape(-1, 6 * self.n) @ B)
        grad[-1] = self.opts.w1
        return grad

    def smooth_cons(self, x: np.ndarray) -> np.ndarray:
        v = self.values(x[:-1])
        F, s = v.forces.ravel(), x[-1]
        limits = np.array([self.tension_limit - s]) if self.symmetric_limits else self._force_rows(v.forces)
        return np.concatenate([s - F, s + F, limits, self._geometric(v), self._ee(v.plates, x[:-1]), self._motion(v)])

    def smooth_cons_jac(self, x: np.ndarray) -> np.ndarray:
        v = self.values(x[:-1])
        d, B = self.derivatives(x[:-1])
        dF = d.d_forces.reshape(-1, 6 * self.n) @ B

        def with_s(block: np.ndarray, ds: float) -> np.ndarray:
            return np.hstack([block, np.full((block.shape[0], 1), ds)])

        if self.symmetric_limits:
            limits = np.zeros((1, x.size))
            limits[0, -1] = -1.0
        else:
            limits = with_s(np.vstack([-dF, dF]), 0.0)
        rows = [with_s(-dF, 1.0), with_s(dF, 1.0), limits, with_s(self._geometric_jac(d, B), 0.0)]
        if self.free_ee:
            rows.append(with_s(self._ee_jac(v.plates, x[:-1], B), 0.0))
        if self.motion is not None:
            dL = d.d_lengths.reshape(-1, 6 * self.n) @ B
            rows.append(with_s(np.vstack([-dL, dL]), 0.0))
        return np.vstack(rows)

    # ----------------------------------------------------------- paper method (x = TAA poses)
    def paper_fun(self, x: np.ndarray) -> float:
        v = self.values(x)
        return float(self.opts.w1 * np.abs(v.forces).max() + self.opts.w2 * np.sqrt(np.sum(v.plate_angles**2)))

    def paper_cons(self, x: np.ndarray) -> np.ndarray:
        v = self.values(x)
        return np.concatenate([self._force_rows(v.forces), self._geometric(v), self._ee(v.plates, x)])


@one_blas_thread
def optimize_internal_poses(
    am: AssemblerModel,
    initial: StackState | PlateArrays | list,
    goal: pin.SE3 | None = None,
    options: OptimizeOptions | None = None,
    motion: MotionTerm | None = None,
) -> OptimizeResult:
    """Minimize Ω over the intermediate plate poses, from a starting pose.

    The start need not be valid (the solver may reach a feasible point from outside); the
    result is a success only when the solver converged to a point that meets every
    constraint. A converged point just outside a limit is pulled back inside along the
    segment to the best feasible point met; when that fails the result says so.

    Args:
        initial: the starting pose (a state or plate poses), e.g. the helper-arm initial
            condition; plate n is taken as the goal unless ``goal`` is given.
        goal: the EE goal pose (default: the initial state's plate n).
        options: see :class:`OptimizeOptions`.
        motion: continuity with a previous sample (:class:`MotionTerm`, slsqp only); the
            chosen state then also keeps every leg within ``max_step`` of it.
    """
    checked_model(am)
    opts = checked_options(options, OptimizeOptions, "options")
    if motion is not None and not isinstance(motion, MotionTerm):
        raise OptionsError(f"motion must be a MotionTerm or None, got {type(motion).__name__}")
    if goal is not None:
        goal = checked_goal(goal, "goal")
    if motion is not None:
        if opts.method != "slsqp":
            raise OptionsError("a motion term needs method 'slsqp'")
        if motion.previous_lengths.shape != (am.n, 6):
            raise OptionsError(f"previous_lengths must have shape ({am.n}, 6), got {motion.previous_lengths.shape}")
    start = initial.plates if isinstance(initial, StackState) else plate_arrays(am, initial)
    goal = start.se3(am.n) if goal is None else goal
    check_tol = opts.ee_tolerance or opts.goal_tolerance
    initial_state = evaluate_state(am, start, goal=goal, tolerance=check_tol)
    omega0 = objective_value(am, initial_state, opts.w1, opts.w2)
    problem = _Problem(am, start, goal, opts, initial_state.feasible, motion)
    if problem.nx_pose == 0:
        return _nothing_to_optimize(initial_state, omega0, opts.method)
    t0 = time.perf_counter()
    res, to_plates, x_final, singular = _run_solver(problem, initial_state)
    elapsed = time.perf_counter() - t0

    def state_at(x: np.ndarray) -> StackState:
        pad = np.concatenate([x, [0.0]]) if opts.method == "slsqp" else x
        return evaluate_state(am, to_plates(pad), goal=goal, tolerance=check_tol)

    final_state = state_at(x_final)
    converged = bool(res.success) and not singular

    def acceptable(state: StackState) -> bool:
        return state.feasible and (motion is None or bool(np.all(motion.margins(state.leg_lengths) >= 0)))

    def score(state: StackState) -> float:
        omega = objective_value(am, state, opts.w1, opts.w2)
        if motion is not None:
            omega += motion.w3 * float(np.sum((state.leg_lengths - motion.previous_lengths) ** 2))
        return omega

    if converged and not acceptable(final_state):
        # SLSQP honours its rows to ~1e-8: step back towards the best feasible point met
        x_inside = problem.best[1] if problem.best is not None else np.zeros_like(x_final)
        for t in (1e-4, 1e-3, 1e-2, 1e-1):
            trial = state_at(x_final + t * (x_inside - x_final))
            if acceptable(trial):
                final_state = trial
                break
    candidates = [final_state] + ([state_at(problem.best[1])] if problem.best is not None else [])
    chosen, omega_chosen = initial_state, score(initial_state)
    for state in candidates:
        omega = score(state)
        no_worse = not initial_state.feasible or state.max_abs_force <= initial_state.max_abs_force + 1e-9
        if acceptable(state) and (not acceptable(chosen) or (omega < omega_chosen and no_worse)):
            chosen, omega_chosen = state, omega
    if motion is not None and converged and final_state.feasible and not acceptable(final_state):
        converged, singular = (
            False,
            f"motion step: the converged point moves a leg more than {1e3 * motion.max_step:.3g} mm",
        )
    success, message = _verdict(res, singular, converged, final_state, chosen, initial_state)
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


def _run_solver(
    problem: _Problem, initial_state: StackState
) -> tuple[_SolverResult, Callable[[np.ndarray], PlateArrays], np.ndarray, str]:
    """Run SLSQP in the method's chart; returns (scipy result, chart map, final pose point,
    the reason when it stopped at a singular iterate else "")."""
    opts = problem.opts
    if opts.method == "slsqp":
        x0 = np.zeros(problem.nx_pose + 1)
        x0[-1] = np.abs(initial_state.forces).max() if np.all(np.isfinite(initial_state.forces)) else 0.0
        fun, jac, cons = (
            problem.smooth_fun,
            problem.smooth_grad,
            {"fun": problem.smooth_cons, "jac": problem.smooth_cons_jac},
        )
        to_plates = problem.plates_local
    else:
        x0 = problem.taa_start()
        fun, jac, cons = problem.paper_fun, None, {"fun": problem.paper_cons}
        to_plates = problem.plates_taa
    from scipy.optimize import minimize  # on first use: fast start-up

    try:
        res = minimize(
            fun,
            x0,
            jac=jac,
            method="SLSQP",
            constraints=[{"type": "ineq", **cons}],
            options={"maxiter": opts.max_iterations, "ftol": opts.ftol},
        )
        singular = ""
    except _SingularIterateError as exc:
        singular = f"stopped at a singular iterate: {exc}"
        res = _StoppedEarly(x0, singular)
    x_final = res.x[:-1] if opts.method == "slsqp" else res.x
    return res, to_plates, x_final, singular


class _SolverResult(Protocol):
    """What is read of a solver result: scipy's ``OptimizeResult`` or :class:`_StoppedEarly`."""

    x: np.ndarray
    message: str
    success: bool
    status: int
    nit: int


@dataclass
class _StoppedEarly:
    """Stands in for scipy's result when the solve stopped early (no converged point)."""

    x: np.ndarray
    message: str
    success: bool = False
    status: int = -1
    nit: int = 0


def _verdict(
    res: _SolverResult, singular: str, converged: bool, final: StackState, chosen: StackState, initial: StackState
) -> tuple[bool, str]:
    """(success, message) of an optimization: success only when the solver converged to a
    point that meets every constraint (or was pulled back inside) and that point was kept."""
    stopped = singular or f"the optimizer stopped after {res.nit} iterations (status {res.status})"
    if not converged:
        if not chosen.feasible:
            return False, one_line(f"no feasible state found: {describe(binding(chosen.violations))}")
        if chosen is initial:
            return False, one_line(f"did not converge: {stopped}; the start is returned")
        return False, one_line(f"did not converge: {stopped}; the best feasible state met is returned")
    if not final.feasible:
        kept = "the best feasible state met is returned" if chosen.feasible else "no feasible state found"
        return False, one_line(f"{describe(binding(final.violations))} at the converged point; {kept}")
    return True, "converged"


def _nothing_to_optimize(initial_state: StackState, omega0: float, method: str) -> OptimizeResult:
    """A stack without movable plates (one platform, EE fixed): the start is the optimum."""
    if initial_state.feasible:
        message = "nothing to optimize (no internal plates): the start is the optimum"
    else:
        message = one_line(f"{describe(binding(initial_state.violations))} (nothing to optimize: no internal plates)")
    return OptimizeResult(
        success=initial_state.feasible,
        message=message,
        status=0,
        solver_message="",
        iterations=0,
        evaluations=0,
        gradient_evaluations=0,
        time_s=0.0,
        initial=initial_state,
        optimized=initial_state,
        objective_initial=omega0,
        objective_optimized=omega0,
        method=method,
    )
