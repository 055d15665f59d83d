"""A world goal reached by the stack on its carrier (:func:`solve_on_carrier`): the carrier's
joints join the search, and the result says whether the stack or the carrier binds."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..common.messages import binding, describe
from ..common.progress import ProgressCallback, checked_progress
from ..common.threads import one_blas_thread
from ..config.bounds import check_bound
from ..config.options import DEFAULT_GOAL_TOLERANCE, GoalTolerance, HelperArmOptions, OptimizeOptions
from ..exceptions import OptionsError
from ..kinematics import to_se3
from ..model.assembler import AssemblerModel
from ..optimize import optimize_internal_poses
from ..optimize.objective import objective_value
from ..solver.pipeline import solve
from .polish import joint_polish
from .robot import Carrier
from .statics import CarrierStatics, carrier_statics

__all__ = ["W_CARRIER", "CarrierSolveResult", "carrier_objective", "solve_on_carrier"]

W_CARRIER = 200.0
"""Weight of the carrier term of Ω_c [N]: a joint at its effort limit costs as much as a leg
at the default force limit."""


@dataclass
class CarrierSolveResult:
    """A world goal reached by the stack on its carrier (:func:`solve_on_carrier`).

    Attributes:
        success: the stack reaches the goal with every constraint holding and no carrier
            joint over its effort limit.
        message: what happened, or why not.
        goal: the EE goal in the world.
        statics: the chosen pose's :class:`CarrierStatics` (None when no pose was found).
        moved_carrier: whether the carrier's joints were searched.
        candidates: every carrier placement tried: ``(t, q, Ω_c or nan, note)`` with ``t``
            the blend from the goal seen from the start placement (0) to the home EE pose (1);
            the joint optimization's answer last, with ``t`` nan (its JSON row says
            ``"stage": "joint_optimization"``, the others ``"placement"``).
        time_s: wall time [s].
    """

    success: bool
    message: str
    goal: pin.SE3
    statics: CarrierStatics | None
    moved_carrier: bool
    candidates: list[tuple[float, np.ndarray, float, str]] = field(default_factory=list)
    time_s: float = 0.0

    @property
    def binding(self) -> str | None:
        return None if self.statics is None else self.statics.binding

    def to_dict(self) -> dict:
        out = {
            "success": self.success,
            "message": self.message,
            "moved_carrier": self.moved_carrier,
            "goal": self.goal.homogeneous.tolist(),
            "time_s": self.time_s,
            "candidates": [_candidate_dict(*c) for c in self.candidates],
        }
        if self.statics is not None:
            out |= self.statics.to_dict()
            out["state"] = self.statics.state.to_dict()
        return out

    def __repr__(self) -> str:
        detail = repr(self.statics) if self.statics is not None else "no pose"
        return (
            f"CarrierSolveResult(success={self.success}, moved_carrier={self.moved_carrier}, {detail}, "
            f"{self.time_s:.2f} s, message={self.message!r})"
        )


@dataclass(frozen=True)
class _Search:
    """What :func:`solve_on_carrier` solves with: the model, the carrier, the world goal and
    the settings, read once."""

    am: AssemblerModel
    carrier: Carrier
    goal: pin.SE3
    options: OptimizeOptions
    helper: HelperArmOptions | None
    optimize: bool
    w_carrier: float

    @property
    def tolerance(self) -> GoalTolerance:
        """How close plate n must be to the goal: the EE tolerance when the EE may move."""
        return self.options.ee_tolerance or DEFAULT_GOAL_TOLERANCE

    def score(self, statics: CarrierStatics | None) -> float:
        return math.nan if statics is None else carrier_objective(self.am, statics, self.w_carrier, self.options)

    def rank(self, statics: CarrierStatics) -> tuple[bool, float]:
        """Within limits first, then the lower Ω_c."""
        return (not statics.within_limits, self.score(statics))


def _candidate_dict(t: float, q: np.ndarray, score: float, note: str) -> dict:
    """One row of ``candidates`` in JSON: ``stage`` says a placement (with its blend ``t``)
    or the joint optimization (``t`` null)."""
    stage = "joint_optimization" if math.isnan(t) else "placement"
    t_value = None if math.isnan(t) else t
    score_value = None if math.isnan(score) else score
    return {"stage": stage, "t": t_value, "q": q.tolist(), "score": score_value, "note": note}


def _stack_on(s: _Search, q: np.ndarray) -> tuple[CarrierStatics | None, str]:
    """The stack for the world goal with the carrier held at ``q``: the helper arm and (with
    ``s.optimize``) the force optimization for the goal seen from the base, then optimized
    again under the world's gravity; without ``s.optimize`` the helper arm's pose as it is."""
    am = s.am
    base = s.carrier.base_pose(q)
    first = solve(am, base.actInv(s.goal), optimize=s.optimize, options=s.options, helper_options=s.helper)
    start = first.best  # with gravity along the base's −z
    if start is None:
        return None, f"the stack cannot reach the goal from this placement: {first.message}"
    world = [base * start.plates.se3(k) for k in range(am.n + 1)]
    why = "helper-arm pose (not optimized)"
    if s.optimize:
        result = optimize_internal_poses(am, world, s.goal, s.options)  # again, under the world's gravity
        if not result.success:
            return None, f"no valid stack pose under the mounted gravity: {result.message}"
        world = result.optimized.plates.as_se3()
        why = "converged" if result.optimal else f"valid, {result.message}"
    rel = [pin.SE3.Identity()] + [base.actInv(world[k]) for k in range(1, am.n + 1)]
    return carrier_statics(am, s.carrier, q, rel, goal=s.goal, tolerance=s.tolerance), why


def _checked_settings(
    options: OptimizeOptions | None,
    helper_options: HelperArmOptions | None,
    blends: int,
    max_iterations: int | None,
    w_carrier: float,
) -> tuple[OptimizeOptions, int]:
    """(options, joint-optimization iteration limit), or an :class:`OptionsError`."""
    if options is not None and not isinstance(options, OptimizeOptions):
        raise OptionsError(f"options must be an OptimizeOptions, got {type(options).__name__}")
    if helper_options is not None and not isinstance(helper_options, HelperArmOptions):
        raise OptionsError(f"helper_options must be a HelperArmOptions, got {type(helper_options).__name__}")
    check_bound("carrier.blends", blends, "blends")
    if isinstance(w_carrier, bool) or not isinstance(w_carrier, (int, float)) or not 0 <= w_carrier < math.inf:
        raise OptionsError(f"w_carrier must be a finite number >= 0 [N], got {w_carrier!r}")
    opts = options or OptimizeOptions()
    limit = opts.max_iterations if max_iterations is None else max_iterations
    check_bound("optimize.max_iterations", limit, "max_iterations")
    return opts, int(limit)


@one_blas_thread
def solve_on_carrier(
    am: AssemblerModel,
    carrier: Carrier,
    goal: pin.SE3 | npt.ArrayLike,
    q0: npt.ArrayLike | None = None,
    move_carrier: bool = True,
    blends: int = 5,
    polish: bool = True,
    w_carrier: float = W_CARRIER,
    max_iterations: int | None = None,
    options: OptimizeOptions | None = None,
    helper_options: HelperArmOptions | None = None,
    optimize: bool = True,
    progress: ProgressCallback | None = None,
) -> CarrierSolveResult:
    """Reach a world EE goal with the stack on its carrier.

    With ``move_carrier=False`` the carrier stays at ``q0`` and the stack is solved for the
    goal seen from its base (helper arm and optimizer, then optimized again under the
    world's gravity).

    With ``move_carrier=True`` the carrier's joints join the search: the goal seen from the
    base is blended from where ``q0`` puts it (t = 0) to the stack's home EE pose (t = 1) in
    ``blends`` steps; for each, the carrier's joint-limited IK places the base so, and the
    stack is solved there; the candidate within every limit with the lowest Ω_c wins. From
    it (``polish``), one SLSQP over the carrier's joints (within their limits) and the
    internal plates together minimizes Ω_c = w1·max|F| + w2·sqrt(Σλ²) +
    ``w_carrier``·max|τ|/τ_max (:func:`carrier_objective`), every leg limit and force limit
    holding and no joint over its effort limit, with forward-difference gradients. Its
    answer is kept only when SLSQP converged, a fresh :func:`carrier_statics` of it holds
    every limit and its Ω_c is lower; otherwise the placement is kept and the message says why.

    Args:
        q0: the carrier's configuration (default: the spec's upright one) [rad].
        blends: placements tried between the start and the home EE pose (2..100).
        polish: run the joint optimization after the placement search.
        w_carrier: weight of the carrier's torque term in Ω_c [N].
        max_iterations: iteration limit of the joint optimization (default
            ``options.max_iterations``).
        options: the stack optimizer's settings (method, w1, w2, EE tolerance, iteration
            limit, ftol); w1, w2 and ftol are the joint optimization's too (which is always
            SLSQP, with the EE at the goal). Default :class:`OptimizeOptions`.
        helper_options: the helper arm's settings (the initial condition at each placement).
        optimize: False: the helper arm's pose at each placement under the world's gravity,
            with neither force nor joint optimization.
        progress: called ``(done, total, note)`` after each placement and the joint optimization.
    """
    t0 = time.perf_counter()
    progress = checked_progress(progress)
    goal = to_se3(goal, "goal")
    opts, limit = _checked_settings(options, helper_options, blends, max_iterations, w_carrier)
    q0 = carrier.upright_q if q0 is None else carrier.check_q(q0, "q0")
    s = _Search(am, carrier, goal, opts, helper_options, bool(optimize), float(w_carrier))
    if not move_carrier:
        return _held(s, q0, t0)
    return _moved(s, q0, blends, polish, limit, progress, t0)


def _held(s: _Search, q0: np.ndarray, t0: float) -> CarrierSolveResult:
    """:func:`solve_on_carrier` with the carrier held at ``q0``."""
    statics, why = _stack_on(s, q0)
    msg = why if statics is None else _verdict(statics)
    ok = statics is not None and statics.within_limits
    return CarrierSolveResult(
        ok, msg, s.goal, statics, False, [(0.0, q0, s.score(statics), msg)], time.perf_counter() - t0
    )


def _moved(
    s: _Search, q0: np.ndarray, blends: int, polish: bool, limit: int, progress: ProgressCallback | None, t0: float
) -> CarrierSolveResult:
    """:func:`solve_on_carrier` with the carrier's joints searched: the placements, then
    (``polish``) the joint optimization from the best."""
    best, candidates = _placements(s, q0, blends, progress)
    if best is None:
        message = f"unreachable: no carrier placement gave a valid stack pose ({len(candidates)} placements tried)"
        return CarrierSolveResult(False, message, s.goal, None, True, candidates, time.perf_counter() - t0)
    note = ""
    if polish and s.optimize and best.within_limits:
        best, note = _polish(s, best, limit, candidates)
    if progress is not None:
        progress(len(candidates), len(candidates), "done")
    message = _verdict(best) + note
    return CarrierSolveResult(best.within_limits, message, s.goal, best, True, candidates, time.perf_counter() - t0)


def _placements(
    s: _Search, q0: np.ndarray, blends: int, progress: ProgressCallback | None
) -> tuple[CarrierStatics | None, list[tuple[float, np.ndarray, float, str]]]:
    """The placement search of :func:`solve_on_carrier`: (best statics or None, candidates)."""
    start_rel = s.carrier.base_pose(q0).actInv(s.goal)
    home_ee = s.am.home[-1]
    candidates: list[tuple[float, np.ndarray, float, str]] = []
    best: CarrierStatics | None = None
    blend_values = np.linspace(0.0, 1.0, max(2, int(blends)))
    total = len(blend_values) + (1 if s.optimize else 0)
    for k, t in enumerate(blend_values):
        rel = pin.SE3.Interpolate(start_rel, home_ee, float(t))
        ik = s.carrier.ik(s.goal * rel.inverse(), q0)
        if not ik.success:
            candidates.append((float(t), ik.q, math.nan, f"carrier IK failed (error {ik.error:.2e})"))
        else:
            statics, why = _stack_on(s, ik.q)
            candidates.append((float(t), ik.q, s.score(statics), why if statics is None else _verdict(statics)))
            if statics is not None and (best is None or s.rank(statics) < s.rank(best)):
                best = statics
        if progress is not None:
            progress(k + 1, total, f"placement t = {t:.2f}")
    return best, candidates


def _polish(
    s: _Search, best: CarrierStatics, max_iterations: int, candidates: list[tuple[float, np.ndarray, float, str]]
) -> tuple[CarrierStatics, str]:
    """The joint optimization from the best placement: (the state kept, a note for the
    message, empty when the polished point is kept); its candidate row is appended."""
    polished, q, why = joint_polish(s.am, s.carrier, s.goal, best, s.w_carrier, s.options, max_iterations, s.tolerance)
    better = polished is not None and s.score(polished) < s.score(best)
    if polished is None:
        candidates.append((math.nan, q, math.nan, f"joint optimization: {why}; kept the best placement"))
        return best, f" (the joint optimization was not kept: {why})"
    note = f"joint optimization: {why}{'' if better else ' (no lower Ω_c: kept the placement)'}"
    candidates.append((math.nan, polished.q, s.score(polished), note))
    return (polished, "") if better else (best, "")


def carrier_objective(
    am: AssemblerModel, statics: CarrierStatics, w_carrier: float = W_CARRIER, options: OptimizeOptions | None = None
) -> float:
    """Ω_c = w1·max|F| + w2·sqrt(Σλ²) + w_carrier·max|τ|/τ_max of a mounted state (the paper's
    eq. 10 with the weights of ``options``, default :class:`OptimizeOptions`, plus the
    carrier's torque term) [w1 in 1/N, w2 in 1/rad, w_carrier in N]."""
    o = options or OptimizeOptions()
    return objective_value(am, statics.state, o.w1, o.w2) + w_carrier * statics.carrier_ratio


def _verdict(statics: CarrierStatics) -> str:
    if statics.within_limits:
        share = max(statics.stack_ratio, statics.carrier_ratio)
        return f"reached; {statics.binding} binds at {100 * share:.0f} % of its limit"
    if not statics.state.feasible:
        return f"the stack violates its limits: {describe(binding(statics.state.violations))}"
    k = int(np.argmax(statics.torque_ratio))
    return (
        f"torque limit: carrier joint {k} at {100 * statics.torque_ratio[k]:.0f} % of its effort limit "
        f"({statics.torques[k]:.1f} N·m)"
    )
