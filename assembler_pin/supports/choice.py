"""The chosen distribution of leg forces of a held stack, and the length offsets that realize it.

Equilibrium at a pose. With the leg forces ``T`` (tension positive) the potential's gradient
at plate m (:mod:`assembler_pin.compliance.elastic`, world axes) is ``ĝ_m + Ŵ_{m−1} − Ŵ_m``: ``ĝ_m`` the
weights on it (its gradient with slack legs), ``Ŵ_j = Σ_i T_ji [u, r × u]`` platform j's legs'
wrench, every moment taken about one point (the EE's origin). A free plate needs it zero, a
held plate's is its support's wrench. So:

* held at the base: ``Ŵ_j = −Σ_{m>j} ĝ_m`` (unique); at the EE: ``Ŵ_j = Σ_{m≤j} ĝ_m`` (unique);
* held at both: ``Ŵ_j = −Σ_{m>j} ĝ_m + w`` for any wrench ``w``, which is the EE support's:
  the six internal forces of the two-point support (the equilibrium matrix's null space,
  ``T_j = J_j⁻ᵀ w`` moved to plate j+1, ``J_j`` the platform's leg lines);
* held nowhere: ``Σ ĝ = 0`` is needed, which gravity denies: a mechanism.

:func:`chosen_distribution` picks ``w`` minimizing ``max|T|`` subject to the force limits
(``−max_compression ≤ T ≤ max_tension``) and the stroke (each commanded ``L − T / k`` within
``[min_length, max_length]``: a leg at a stroke end can only pull it further in): a linear
program in ``(w, t)`` solved by HiGHS. The
legs realize it when commanded ``L0 = L − T / k``: the pose is then an exact elastic equilibrium
with these forces (``k (L − L0) = T``), so the offsets are ``−T / k`` [m]; they are applied
through :func:`~assembler_pin.supports.two_point.two_point_statics` (or the base-held
:func:`~assembler_pin.compliance.loaded.loaded_pose`, the EE-held
:func:`~assembler_pin.supports.two_point.ee_loaded_pose`) to check that the forces come back.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from ..compliance.elastic import elastic_terms, line_conditions
from ..compliance.loaded import LoadedPose, loaded_pose, stroke_problem
from ..kinematics import PlateArrays, leg_vectors, plate_arrays
from ..model.assembler import AssemblerModel
from ..statics.closed_form import CONDITION_LIMIT
from .two_point import (
    SupportAnswer,
    TwoPointStatics,
    ee_loaded_pose,
    held_plates,
    mechanism_message,
    residual_tolerance,
    two_point_statics,
)

__all__ = [
    "CHECK_TOLERANCE",
    "ChosenDistribution",
    "HeldEquilibrium",
    "chosen_distribution",
    "force_bounds",
    "held_equilibrium",
]

#: Largest difference [N] between the chosen forces and those its offsets produce when applied.
CHECK_TOLERANCE = 1e-6


@dataclass(frozen=True)
class HeldEquilibrium:
    """The leg forces in equilibrium at a pose for a support, as ``F = particular + null @ w``.

    Attributes:
        particular: (n, 6) forces with the EE's support wrench zero (the base-held statics, or
            the EE-held ones for ``ee``) [N].
        null: (n, 6, k) the internal force patterns: k = 6 with both ends held, else 0 [N per
            unit of the EE support's wrench about the EE origin].
        total: (6,) the weights' wrench about the EE origin (what the supports carry together).
        ee_origin: (3,) the EE plate's origin [m], the moments' point.
    """

    particular: np.ndarray
    null: np.ndarray
    total: np.ndarray
    ee_origin: np.ndarray


def _moved(W: np.ndarray, c: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Wrenches (..., 6) with moments about ``c`` moved to points ``P`` (..., 3)."""
    out = W.copy()
    out[..., 3:] += np.cross(c - P, W[..., :3])
    return out


def held_equilibrium(am: AssemblerModel, pa: PlateArrays, support: str) -> HeldEquilibrium | str:
    """The equilibrium forces of the module docstring, or why there are none (a mechanism, a
    singular platform) as a string."""
    held = held_plates(am, support)
    why = mechanism_message(support)
    if why is not None:
        return why
    slack = elastic_terms(am, pa.R, pa.p, None, float(am.config.leg.stiffness), hessian=False)
    J_inv, cond = line_conditions(slack.lines)
    if not cond.max() <= CONDITION_LIMIT:
        j = int(np.argmax(cond))
        return f"platform {j} is at a singular configuration (condition number {cond[j]:.3g} > {CONDITION_LIMIT:.0g})"
    c = pa.p[-1]
    g_hat = _moved(np.vstack([slack.base_gradient, slack.gradient]), pa.p, c)  # about the EE origin
    if held == (am.n,):
        W = np.cumsum(g_hat[:-1], axis=0)
    else:
        W = -np.cumsum(g_hat[::-1], axis=0)[::-1][1:]  # -Σ_{m>j}
    to_legs = np.swapaxes(J_inv, 1, 2)  # T = J⁻ᵀ W at the top plate's origin
    particular = np.einsum("jab,jb->ja", to_legs, _moved(W, c, pa.p[1:]))
    k = 6 if len(held) == 2 else 0
    unit = np.broadcast_to(np.eye(6)[:k], (am.n, k, 6))
    null = np.einsum("jab,jkb->jak", to_legs, _moved(unit, c, pa.p[1:, None, :]))
    return HeldEquilibrium(particular, null, g_hat.sum(axis=0), c)


def force_bounds(am: AssemblerModel, lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-leg bounds (n, 6) on a chosen force [N]: the force limits, and the stroke (the
    commanded ``L − F / k`` within ``[min_length, max_length]``)."""
    leg = am.config.leg
    k = float(leg.stiffness)
    lo = np.maximum(-leg.max_compression, k * (lengths - leg.max_length))
    hi = np.minimum(leg.max_tension, k * (lengths - leg.min_length))
    return lo, hi


#: HiGHS's dual simplex without presolve: the fastest of its methods on these small programs.
_LP_OPTIONS = {"presolve": False}

#: Pivot and feasibility tolerance of the small simplex, relative to the program's scale.
_SIMPLEX_TOL = 1e-11


def _pivot(T: np.ndarray, basis: np.ndarray, row: int, col: int) -> None:
    T[row] /= T[row, col]
    factors = T[:, col].copy()
    factors[row] = 0.0
    T -= np.outer(factors, T[row])
    basis[row] = col


def _simplex_pivots(T: np.ndarray, basis: np.ndarray, allowed: int, tol: float) -> bool:
    """Simplex pivots on the tableau ``T`` (last row the reduced costs, last column the values)
    over its first ``allowed`` columns until optimal (True) or unbounded (False): Dantzig's
    rule, and Bland's (which cannot cycle) after 10 pivots without progress."""
    stalled, value = 0, T[-1, -1]
    for _ in range(50 * T.shape[1]):
        costs = T[-1, :allowed]
        if stalled < 10:
            col = int(np.argmin(costs))
            if costs[col] >= -tol:
                return True
        else:
            enter = np.flatnonzero(costs < -tol)
            if enter.size == 0:
                return True
            col = int(enter[0])
        a = T[:-1, col]
        rows = np.flatnonzero(a > tol)
        if rows.size == 0:
            return False
        ratios = T[rows, -1] / a[rows]
        ties = rows[ratios <= ratios.min() + tol]
        _pivot(T, basis, int(ties[np.argmin(basis[ties])]), col)
        stalled = stalled + 1 if T[-1, -1] <= value + tol else 0
        value = max(value, T[-1, -1])
    return False


def _small_simplex(A: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray | None:
    """``z`` minimizing ``c·z`` subject to ``A z ≤ b`` (z free, A of full column rank m), by a
    two-phase tableau simplex (:func:`_simplex_pivots`) on the dual ``min b·y, Aᵀy = −c, y ≥ 0``; the
    answer is returned only when it certifies itself (primal feasible, the duality gap closed),
    else None."""
    m, rows = A.shape[1], A.shape[0]
    E, r = A.T.copy(), -c.astype(float)
    flip = r < 0
    E[flip], r[flip] = -E[flip], -r[flip]
    scale = max(1.0, float(np.abs(b).max()))
    T = np.zeros((m + 1, rows + m + 1))
    T[:m, :rows], T[:m, rows : rows + m], T[:m, -1] = E, np.eye(m), r
    T[-1] = -T[:m].sum(axis=0)
    T[-1, rows : rows + m] = 0.0
    basis = np.arange(rows, rows + m)
    if not _simplex_pivots(T, basis, rows, _SIMPLEX_TOL) or T[-1, -1] < -_SIMPLEX_TOL:
        return None  # no dual feasible point: the primal is infeasible or unbounded
    if np.any(basis >= rows):
        return None  # a degenerate artificial left in the basis: leave it to HiGHS
    T[-1] = 0.0
    T[-1, :rows] = b / scale
    T[-1] -= T[-1, basis] @ T[:m]
    if not _simplex_pivots(T, basis, rows, _SIMPLEX_TOL):
        return None
    try:
        z = np.linalg.solve(A[basis], b[basis])
    except np.linalg.LinAlgError:
        return None
    y = np.zeros(rows)
    y[basis] = T[:m, -1]
    gap = abs(float(c @ z) + float(b @ y))
    if not (np.all(A @ z <= b + 1e-9 * scale) and np.all(y >= -1e-12) and gap <= 1e-9 * scale):
        return None
    return z


def _minmax(eq: HeldEquilibrium, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray | None, str]:
    """``w`` minimizing max|F| with ``lo ≤ F ≤ hi``, or None and why not: the small certified
    simplex, HiGHS when it does not certify its answer."""
    Fp = eq.particular.ravel()
    N = eq.null.reshape(Fp.size, -1)
    k = N.shape[1]
    if k == 0:
        return np.zeros(0), "the support is statically determinate: the forces are unique"
    ones = np.ones((Fp.size, 1))
    zeros = np.zeros((Fp.size, 1))
    A = np.block([[N, -ones], [-N, -ones], [N, zeros], [-N, zeros]])
    b = np.concatenate([-Fp, Fp, hi.ravel() - Fp, Fp - lo.ravel()])
    cost = np.zeros(k + 1)
    cost[-1] = 1.0
    z = _small_simplex(A, b, cost)
    if z is not None:
        return z[:k], "minimal max|F| within the force limits and the stroke (simplex, certified)"
    res = linprog(cost, A_ub=A, b_ub=b, bounds=[(None, None)] * k + [(0, None)], method="highs-ds", options=_LP_OPTIONS)
    if res.status != 0 or res.x is None:
        why = f"force limit: no distribution of {k} free force(s) within the limits and the stroke"
        return None, f"{why} (HiGHS status {res.status})"
    return res.x[:k], "minimal max|F| within the force limits and the stroke (HiGHS)"


@dataclass(frozen=True)
class ChosenDistribution(SupportAnswer):
    """The forces chosen by commanding length offsets (:func:`chosen_distribution`).

    Attributes:
        support: ``base``, ``ee`` or ``both``.
        plates: where the forces are chosen (the elastic distribution's loaded plates, or the
            pose itself: see :func:`chosen_distribution`); the pose when it failed.
        forces: (n, 6) leg forces [N], tension positive, at ``plates`` (NaN on failure).
        length_offsets: (n, 6) commanded minus the pose's own lengths, ``−F / k`` [m].
        commanded: (n, 6) the lengths to command [m].
        base_wrench, ee_wrench: (6,) what the supports apply to plates 0 and n [N, N·m], world
            axes, moments about those plates' origins (zero for a plate not held).
        residual: largest unbalanced force or moment at a free plate, from the potential's
            gradient at the pose with the commanded lengths [N, N·m].
        check_error: largest difference [N] between ``forces`` and those of the elastic solve of
            the commanded lengths (NaN when not checked: ``verify`` false).
        within_stroke: every commanded length lies within the legs' stroke.
        success: a distribution within the force limits, in equilibrium, reproduced by its
            offsets and commandable; message: what was done, or why not.
    """

    support: str
    plates: PlateArrays
    forces: np.ndarray
    length_offsets: np.ndarray
    commanded: np.ndarray
    base_wrench: np.ndarray
    ee_wrench: np.ndarray
    residual: float
    check_error: float
    within_stroke: bool
    success: bool
    message: str

    def __repr__(self) -> str:
        return (
            f"ChosenDistribution(support={self.support!r}, success={self.success}, max|F| "
            f"{self.max_abs_force:.3f} N, largest offset {1e6 * float(np.abs(self.length_offsets).max()):.2f} µm, "
            f"check {self.check_error:.2g} N, message={self.message!r})"
        )

    def to_dict(self) -> dict:
        """JSON-ready lists (NaN for a failed one: write it with ``cli.common.dumps``)."""
        return self._shared_dict() | {
            "length_offsets": self.length_offsets.tolist(),
            "check_error": self.check_error,
            "within_stroke": self.within_stroke,
        }


def _failed(support: str, pa: PlateArrays, message: str) -> ChosenDistribution:
    nan, nan6 = np.full((len(pa) - 1, 6), np.nan), np.full(6, np.nan)
    return ChosenDistribution(support, pa, nan, nan, nan, nan6, nan6, math.inf, math.nan, False, False, message)


def _check(
    am: AssemblerModel, pa: PlateArrays, support: str, commanded: np.ndarray, F: np.ndarray
) -> tuple[float, str]:
    """Apply the commanded lengths through the elastic solve of the support (held at both ends:
    Newton started from ``pa``, where the forces were chosen): the largest force difference
    [N] and a note (the EE-only support through the turned model,
    :func:`~assembler_pin.supports.two_point.ee_loaded_pose`)."""
    got: TwoPointStatics | LoadedPose
    if support == "both":
        got = two_point_statics(am, pa, commanded)
    elif support == "ee":
        got = ee_loaded_pose(am, commanded, pa.se3(am.n))
    else:
        got = loaded_pose(am, commanded, base=pa.se3(0))
    if not got.success:
        return math.inf, f"the elastic solve of the commanded lengths failed: {got.message}"
    return float(np.abs(got.forces - F).max()), "offsets checked by the elastic solve"


def _where(am: AssemblerModel, pa: PlateArrays, support: str, loaded: bool) -> PlateArrays | str:
    """The plates the distribution is chosen at: where the elastic solve of the pose's own
    lengths puts them (``loaded``), else the pose itself."""
    if not loaded:
        return pa
    el: TwoPointStatics | LoadedPose
    if support == "both":
        el = two_point_statics(am, pa)
    elif support == "ee":
        el = ee_loaded_pose(am, leg_vectors(am, pa)[3], pa.se3(am.n))
    else:
        el = loaded_pose(am, leg_vectors(am, pa)[3], base=pa.se3(0))
    return el.plates if el.success else f"no elastic equilibrium of the pose's own lengths: {el.message}"


def _verdict(residual: float, tolerance: float, error: float, checked: str) -> str | None:
    if not residual <= tolerance:
        return f"the chosen forces leave {residual:.3g} N unbalanced at a free plate (> {tolerance:.3g})"
    if not (math.isnan(error) or error <= CHECK_TOLERANCE):
        return f"{checked}: the offsets give forces {error:.3g} N from the chosen ones (> {CHECK_TOLERANCE:g} N)"
    return None


def chosen_distribution(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    support: str = "both",
    loaded: bool = True,
    verify: bool = True,
) -> ChosenDistribution:
    """The leg forces minimizing max|F| within the force limits and the stroke for the stack
    held by ``support`` at ``plates``, and the length offsets that realize them (module doc).

    ``loaded`` (default): chosen where the elastic distribution of the pose's own lengths puts
    the plates (:func:`~assembler_pin.supports.two_point.two_point_statics`; the base-held
    :func:`~assembler_pin.compliance.loaded.loaded_pose`; the EE-held
    :func:`~assembler_pin.supports.two_point.ee_loaded_pose`), so the elastic forces are one of the
    candidates and ``max|F|`` is never above theirs; else at ``plates`` exactly. The offsets are
    the commanded lengths minus the pose's own. Held at one end the forces are unique; held at
    both, HiGHS picks the six internal forces. With ``verify`` the commanded lengths are applied
    through the elastic solve and must give the forces back within :data:`CHECK_TOLERANCE`
    (``check_error``; NaN without ``verify``).

    Returns:
        A :class:`ChosenDistribution`; ``success`` false (NaN forces) for a support that leaves
        a mechanism, a singular pose, no distribution within the limits, or a failed check.

    Raises:
        SupportError: an unknown support. PoseError: malformed plates.
    """
    pa = plate_arrays(am, plates)
    held = held_plates(am, support)
    at = _where(am, pa, support, loaded) if mechanism_message(support) is None else pa
    if isinstance(at, str):
        return _failed(support, pa, at)
    eq = held_equilibrium(am, at, support)
    if isinstance(eq, str):
        return _failed(support, pa, eq)
    lengths = leg_vectors(am, at)[3]
    lo, hi = force_bounds(am, lengths)
    w, note = _minmax(eq, lo, hi)
    if w is None:
        return _failed(support, pa, note)
    F = eq.particular + eq.null @ w
    if eq.null.shape[2] == 0 and not np.all((lo <= F) & (F <= hi)):
        return _failed(support, pa, "the forces of this support exceed the force limits (or the stroke)")
    k = float(am.config.leg.stiffness)
    commanded = lengths - F / k
    terms = elastic_terms(am, at.R, at.p, commanded, k, hessian=False)
    grad = np.vstack([terms.base_gradient, terms.gradient])
    free = [m for m in range(am.n + 1) if m not in held]
    residual = float(np.abs(grad[free]).max()) if free else 0.0
    error, checked = _check(am, at, support, commanded, F) if verify else (math.nan, "offsets not checked")
    why = _verdict(residual, residual_tolerance(am, at), error, checked) or stroke_problem(am, commanded)
    walls = (grad[0] if 0 in held else np.zeros(6), grad[-1] if am.n in held else np.zeros(6))
    offsets = commanded - leg_vectors(am, pa)[3]
    within = stroke_problem(am, commanded) is None
    return ChosenDistribution(
        support, at, F, offsets, commanded, *walls, residual, error, within, why is None, why or f"{note}; {checked}"
    )
