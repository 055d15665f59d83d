"""Supports of the stack: which plates are held, and the statics of the stack held at both ends.

A support welds plates to the world: ``base`` (plate 0, the package's usual model), ``ee`` (the
EE plate n) or ``both`` (plate 0 and plate n: the inchworm's two feet); ``none`` leaves the
stack a free body, a mechanism. Held at both ends, the 6n leg forces meet only the 6(n−1)
equilibrium equations of the free plates 1..n−1: six internal forces are redundant whatever n
is (one wrench passed from foot to foot through every platform). Two answers:

* :func:`two_point_statics` — the **elastic distribution**: the nonlinear elastic equilibrium
  of the free plates for commanded lengths ``L0`` (default: the pose's own lengths), plates 0
  and n fixed at their poses, the legs springs of ``leg.stiffness`` (:mod:`assembler_pin.compliance.elastic`,
  its Newton solve with the EE held): leg forces ``k (L − L0)`` (tension positive) and the two
  support wrenches.
* :func:`~assembler_pin.supports.choice.chosen_distribution` — the **chosen distribution**: the
  legs are actuated, so small length offsets set the six internal forces; the one minimizing
  max|F| within the force limits, with the offsets that realize it.

Wrenches are ``[f, m]`` the support applies to its plate [N, N·m], world axes, the moment
about that plate's origin.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..common.validation import as_float_array
from ..compliance.elastic import elastic_terms, line_conditions, solve_equilibrium
from ..compliance.loaded import LoadedPose, loaded_pose
from ..config.bounds import check_bound
from ..exceptions import PoseError, SupportError
from ..kinematics import PlateArrays, leg_vectors, plate_arrays, to_se3
from ..model.assembler import AssemblerModel, checked_model
from ..state import StackState, evaluate_state
from ..statics.closed_form import CONDITION_LIMIT
from .turned import turned_model

__all__ = [
    "FAST_STEP",
    "RESIDUAL_TOLERANCE",
    "SUPPORTS",
    "EEHeldStatics",
    "TwoPointStatics",
    "ee_held_statics",
    "ee_loaded_pose",
    "held_plates",
    "two_point_statics",
]

#: The support names: the plates each holds (``n`` the EE plate).
SUPPORTS = ("base", "ee", "both", "none")

#: Largest force or moment left unbalanced at a free plate of an accepted equilibrium [N, N·m]
#: (raised for tall stacks to the floor of double precision: :func:`residual_tolerance`).
RESIDUAL_TOLERANCE = 1e-9

#: Newton step [m] at which the fast solve stops (the residual check decides, see
#: :func:`two_point_statics`).
FAST_STEP = 1e-9


def residual_tolerance(am: AssemblerModel, pa: PlateArrays) -> float:
    """The largest residual accepted at a free plate [N, N·m]: :data:`RESIDUAL_TOLERANCE`, or for
    tall stacks the rounding of the plate positions times the legs' stiffness (16 ε k max|p|),
    the floor no solve in double precision can go below."""
    reach = float(np.abs(pa.p).max())
    return max(RESIDUAL_TOLERANCE, 16.0 * np.finfo(float).eps * float(am.config.leg.stiffness) * reach)


def _residual(terms) -> float:
    """Largest unbalanced force or moment at plates 1..n−1 [N, N·m] (0 with no free plate)."""
    return float(np.abs(terms.gradient[:-1]).max()) if terms.gradient.shape[0] > 1 else 0.0


def held_plates(am: AssemblerModel, support: str) -> tuple[int, ...]:
    """The plates a support holds: ``base`` (0,), ``ee`` (n,), ``both`` (0, n), ``none`` ().

    Raises:
        SupportError: an unknown support name.
    """
    table = {"base": (0,), "ee": (am.n,), "both": (0, am.n), "none": ()}
    if not isinstance(support, str) or support not in table:
        raise SupportError(f"support must be one of {', '.join(SUPPORTS)}; got {support!r}")
    return table[support]


def mechanism_message(support: str) -> str | None:
    """Why a support leaves the stack a mechanism (None when it does not)."""
    if support == "none":
        return "no plate is held: the stack is a free body (six rigid-body motions), a mechanism"
    return None


class SupportAnswer:
    """What the answers of a held stack share (:class:`TwoPointStatics`,
    :class:`~assembler_pin.supports.choice.ChosenDistribution`): the support, plates, forces
    (n, 6) [N, tension positive], commanded lengths [m], the two support wrenches [N, N·m],
    the residual, success and message (attributes of the dataclass using it)."""

    support: str
    plates: PlateArrays
    forces: np.ndarray
    commanded: np.ndarray
    base_wrench: np.ndarray
    ee_wrench: np.ndarray
    residual: float
    success: bool
    message: str

    @property
    def max_abs_force(self) -> float:
        """max |F| [N] (NaN on failure)."""
        return float(np.abs(self.forces).max())

    def _shared_dict(self) -> dict:
        """The JSON-ready keys every held answer writes (NaN kept: write with ``cli.common.dumps``)."""
        wrenches = {"base": self.base_wrench.tolist(), "ee": self.ee_wrench.tolist()}
        return {
            "success": self.success,
            "message": self.message,
            "support": self.support,
            "forces": self.forces.tolist(),
            "max_abs_force": self.max_abs_force,
            "commanded": self.commanded.tolist(),
            "support_wrenches": wrenches,
            "plates": self.plates.as_matrices().tolist(),
            "residual": self.residual,
        }


@dataclass(frozen=True)
class TwoPointStatics(SupportAnswer):
    """The elastic equilibrium of the stack held at plate 0 and plate n (:func:`two_point_statics`).

    Attributes:
        plates: the loaded plate poses (plates 0 and n as given; the last iterate on failure).
        forces: (n, 6) leg forces ``k (L − L0)`` [N], tension positive (NaN on failure).
        lengths: (n, 6) loaded pin-to-pin lengths [m]; commanded: (n, 6) ``L0`` [m].
        base_wrench, ee_wrench: (6,) what the two supports apply to plates 0 and n [N, N·m],
            world axes, moments about those plates' origins.
        residual: largest unbalanced force or moment at a free plate [N, N·m]
            (:func:`residual_tolerance`: 1e-9 up to tall stacks).
        iterations: Newton steps; stable: the free plates' tangent stiffness is positive definite.
        success: converged, stable, residual ≤ :func:`residual_tolerance`, no platform singular;
            message: "converged" or why not.
    """

    plates: PlateArrays
    forces: np.ndarray
    lengths: np.ndarray
    commanded: np.ndarray
    base_wrench: np.ndarray
    ee_wrench: np.ndarray
    residual: float
    iterations: int
    stable: bool
    success: bool
    message: str

    support = "both"

    def __repr__(self) -> str:
        return (
            f"TwoPointStatics(success={self.success}, max|F| {self.max_abs_force:.3f} N, base force "
            f"{np.round(self.base_wrench[:3], 3).tolist()} N, EE force {np.round(self.ee_wrench[:3], 3).tolist()} N, "
            f"residual {self.residual:.2g}, {self.iterations} steps, message={self.message!r})"
        )

    def to_dict(self) -> dict:
        """JSON-ready lists (NaN for a failed one: write it with ``cli.common.dumps``)."""
        return self._shared_dict() | {
            "lengths": self.lengths.tolist(),
            "iterations": self.iterations,
            "stable": self.stable,
            "units": "N (tension positive), m; wrenches [f, m] on the held plate, world axes, N and N m",
        }


def checked_lengths(am: AssemblerModel, lengths: npt.ArrayLike, what: str = "commanded leg lengths") -> np.ndarray:
    """(n, 6) lengths [m], finite and > 0.

    Raises:
        PoseError: malformed, not finite or not positive.
    """
    arr = as_float_array(lengths, what, (am.n, 6))
    if not np.all(np.isfinite(arr)) or not arr.min() > 0:
        raise PoseError(f"{what} must be finite and > 0 [m]")
    return arr


def _failed(pa: PlateArrays, rest: np.ndarray, its: int, residual: float, message: str) -> TwoPointStatics:
    nan, nan6 = np.full(rest.shape, np.nan), np.full(6, np.nan)
    return TwoPointStatics(pa, nan, nan, rest, nan6, nan6, residual, its, False, False, message)


def _equilibrium(am: AssemblerModel, pa: PlateArrays, rest: np.ndarray, max_iterations: int, tolerance: float):
    """Newton on plates 1..n−1 to :data:`FAST_STEP`, polished to 1e-12 m when the residual is
    above ``tolerance``: (the solve's end, its terms or None on failure, the Newton steps)."""
    k = float(am.config.leg.stiffness)
    eq = solve_equilibrium(
        am,
        pa.R,
        pa.p,
        rest,
        k,
        tol=FAST_STEP,
        max_iterations=max_iterations,
        condition_limit=CONDITION_LIMIT,
        hold_ee=True,
    )
    its = eq.iterations
    if eq.message is None and its == 0 and k * eq.step <= 1e-3 * tolerance:
        return eq, eq.terms, its  # already balanced: the step left moves no force by 1e-3 × tolerance
    end = None if eq.message else elastic_terms(am, eq.R, eq.p, rest, k, hessian=False)
    if end is not None and not _residual(end) <= tolerance:  # polish: Newton to the last digits
        eq = solve_equilibrium(am, eq.R, eq.p, rest, k, max_iterations=max_iterations, hold_ee=True)
        its += eq.iterations
        end = None if eq.message else elastic_terms(am, eq.R, eq.p, rest, k, hessian=False)
    return eq, end, its


def _problem(end, eq, residual: float, tolerance: float) -> str | None:
    """Why a converged two-point equilibrium is not accepted (None when it is)."""
    cond = line_conditions(end.lines)[1]
    if not cond.max() <= CONDITION_LIMIT:
        return f"the loaded pose puts platform {int(np.argmax(cond))} at a singular configuration"
    if not eq.stable:
        return "the equilibrium held at both ends is not stable (the free plates buckle)"
    if not residual <= tolerance:
        return f"the equilibrium leaves {residual:.3g} N unbalanced at a free plate (> {tolerance:.3g})"
    return None


def two_point_statics(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    lengths: npt.ArrayLike | None = None,
    max_iterations: int = 30,
) -> TwoPointStatics:
    """The elastic distribution: plates 0 and n welded at their poses in ``plates``, the legs
    commanded to ``lengths`` (n, 6) [m] (default: the pose's own), gravity and the payload on.

    Newton's method on plates 1..n−1 (:func:`~assembler_pin.compliance.elastic.solve_equilibrium` with the
    EE held) from ``plates``, stopped at a step of :data:`FAST_STEP` (Newton converges
    quadratically: the error left is far below it); the forces, support wrenches and residual
    are evaluated at its end, and a residual above the tolerance is polished by more steps to
    ``1e-12`` m before it is reported.

    Returns:
        A :class:`TwoPointStatics`; ``success`` false (NaN forces) for a singular pose (leg-line
        condition number above :data:`~assembler_pin.statics.closed_form.CONDITION_LIMIT`), no convergence,
        an unstable equilibrium or a residual above :func:`residual_tolerance`.

    Raises:
        PoseError: malformed plates or lengths. SupportError: ``max_iterations`` not an
            integer within ``elastic.max_iterations``. ArgumentError: ``am`` not a model.
    """
    am = checked_model(am)
    check_bound("elastic.max_iterations", max_iterations, "max_iterations", SupportError)
    pa = plate_arrays(am, plates)
    rest = leg_vectors(am, pa)[3] if lengths is None else checked_lengths(am, lengths)
    tolerance = residual_tolerance(am, pa)
    eq, end, its = _equilibrium(am, pa, rest, max_iterations, tolerance)
    loaded = PlateArrays(eq.R, eq.p)
    if end is None:
        assert eq.message is not None  # no terms are computed after a failed solve
        return _failed(loaded, rest, its, math.inf, eq.message)
    residual = _residual(end)
    message = _problem(end, eq, residual, tolerance)
    if message is not None:
        return _failed(loaded, rest, its, residual, message)
    base, top = end.base_gradient.copy(), end.gradient[-1].copy()
    return TwoPointStatics(loaded, end.tension, end.lengths, rest, base, top, residual, its, True, True, "converged")


@dataclass(frozen=True)
class EEHeldStatics:
    """The stack held at its EE plate alone (support ``ee``), from the turned model
    (:mod:`assembler_pin.supports.turned`) held at its base.

    Attributes:
        state: the turned model's :class:`~assembler_pin.state.StackState` of the pose (its
            plates and legs in the turned order).
        forces: (n, 6) leg forces [N], tension positive, in the original's order.
        ee_wrench: (6,) what the EE support applies to plate n [N, N·m], world axes, moment
            about plate n's origin (the payload's weight included).
        violations: every broken limit, named for the original's platforms and legs.
    """

    state: StackState
    forces: np.ndarray
    ee_wrench: np.ndarray
    violations: list

    @property
    def feasible(self) -> bool:
        return not self.violations

    @property
    def max_abs_force(self) -> float:
        """max |F| [N]."""
        return float(np.abs(self.forces).max())

    def to_dict(self) -> dict:
        """JSON-ready: ``support``, ``forces`` (original order), ``max_abs_force``, ``feasible``,
        ``violations``, ``support_wrenches`` (``ee`` only) and the plates."""
        return {
            "support": "ee",
            "forces": self.forces.tolist(),
            "max_abs_force": self.max_abs_force,
            "feasible": self.feasible,
            "violations": [v.to_dict() for v in self.violations],
            "support_wrenches": {"ee": self.ee_wrench.tolist()},
            "singular": bool(self.state.statics.singular),
        }


def _payload_wrench(am: AssemblerModel, pa: PlateArrays) -> np.ndarray:
    """What a support of plate n applies to carry the payload: [f, m] about plate n's origin."""
    pay = am.config.payload
    f = np.array([0.0, 0.0, pay.mass * am.config.gravity])
    r = pa.R[-1] @ np.array([0.0, 0.0, pay.offset])
    return np.concatenate([f, np.cross(r, f)])


def ee_held_statics(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> EEHeldStatics:
    """The leg forces and limits of the stack held at plate n alone, plate 0 free: the turned
    model's base-held statics of the same physical pose (:mod:`assembler_pin.supports.turned`).

    Raises:
        PoseError: malformed plates.
    """
    pa = plate_arrays(am, plates)
    tm = turned_model(am)
    state = evaluate_state(tm.model, tm.plates(pa))
    forces = tm.original_legs(state.forces)
    wrench = state.statics.base_wrench + _payload_wrench(am, pa)
    return EEHeldStatics(state, forces, wrench, [tm.original_violation(v) for v in state.violations])


def ee_loaded_pose(am: AssemblerModel, lengths: npt.ArrayLike, ee: pin.SE3) -> LoadedPose:
    """The elastic equilibrium of commanded ``lengths`` (n, 6) [m] (original order) with plate n
    welded at the world pose ``ee`` and plate 0 free: the turned model's
    :func:`~assembler_pin.compliance.loaded.loaded_pose`, its plates, forces and lengths given back
    in the original's order.

    Raises:
        PoseError: malformed lengths or pose.
    """
    tm = turned_model(am)
    rest = checked_lengths(am, lengths)
    got = loaded_pose(tm.model, tm.turned_legs(rest), base=to_se3(ee, "EE pose") * tm.flip)
    back = tm.original_legs
    return dataclasses.replace(
        got,
        plates=tm.original_plates(got.plates),
        rigid=tm.original_plates(got.rigid),
        forces=back(got.forces),
        lengths=back(got.lengths),
        commanded=rest,
    )
