"""The solvers' options: one light module, the single source of their defaults.

:class:`OptimizeOptions` (the internal-pose optimizer), :class:`HelperArmOptions` (the helper
arm's initial condition) and :class:`GoalTolerance` import no numerical library, so the
command line can show their defaults without loading Pinocchio.
"""

from __future__ import annotations

import logging
import numbers
from dataclasses import dataclass, field
from typing import TypeVar

from ..exceptions import OptionsError, short_repr
from .bounds import check_bound
from .choices import OBJECTIVES, OPTIMIZE_METHODS
from .numbers import finite_float

logger = logging.getLogger(__name__)

__all__ = [
    "AUTO_IPOPT_PLATFORMS",
    "DEFAULT_GOAL_TOLERANCE",
    "GEOMETRIC_MARGIN",
    "METHODS",
    "SMOOTH_METHODS",
    "GoalTolerance",
    "HelperArmOptions",
    "OptimizeOptions",
    "casadi_missing",
    "checked_options",
    "resolved_method",
]


@dataclass(frozen=True)
class GoalTolerance:
    """How close the end effector must be to its goal.

    Attributes:
        position: largest distance between EE and goal origins [m].
        rotation: largest angle of the rotation between EE and goal [rad].
    """

    position: float = 1e-6
    rotation: float = 1e-6

    def __post_init__(self) -> None:
        for name in ("position", "rotation"):
            check_bound(f"goal_tolerance.{name}", getattr(self, name), f"GoalTolerance.{name}")


_OptionsT = TypeVar("_OptionsT")


def checked_options(value: object, cls: type[_OptionsT], what: str) -> _OptionsT:
    """``value`` when it is a ``cls`` instance, ``cls()`` when it is None, else OptionsError.

    Args:
        what: the argument's name, for the message (e.g. ``"options"``).
    """
    if value is None:
        return cls()
    if not isinstance(value, cls):
        raise OptionsError(f"{what} must be a {cls.__name__} (or None for the defaults), got {type(value).__name__}")
    return value


DEFAULT_GOAL_TOLERANCE = GoalTolerance()


#: The optimizer's methods (:data:`~assembler_pin.choices.OPTIMIZE_METHODS`): ``slsqp``
#: (smooth epigraph form, scipy's SLSQP), ``paper`` (the paper's literal form), ``ipopt``
#: (the smooth form by IPOPT on the sparse Jacobian, through CasADi), ``auto`` (by the
#: stack's size, :data:`AUTO_IPOPT_PLATFORMS`).
METHODS = OPTIMIZE_METHODS

#: The methods of the smooth epigraph form (analytic gradients): the sag objectives, the
#: sag limit and a motion term need one of them.
SMOOTH_METHODS = ("slsqp", "ipopt", "auto")

#: ``method="auto"`` runs IPOPT from this many platforms up (SLSQP below, and wherever
#: CasADi is not installed): measured, SLSQP is faster up to 8 platforms, IPOPT from 12.
AUTO_IPOPT_PLATFORMS = 12

#: How far inside the stroke and deflection limits the optimizer's rows keep a point [m, and
#: cosine units]. SLSQP satisfies its rows only to ~1e-8; with a smaller margin its optimum can
#: sit just outside a limit, be rejected by the strict final check and cost the whole solve.
GEOMETRIC_MARGIN = 1e-7


@dataclass(frozen=True)
class OptimizeOptions:
    """Settings of :func:`optimize_internal_poses`.

    Attributes:
        method: ``"slsqp"`` (smooth epigraph form, analytic gradients, scipy's SLSQP),
            ``"ipopt"`` (the same form by IPOPT on the sparse constraint Jacobian,
            through CasADi), ``"auto"`` (IPOPT from :data:`AUTO_IPOPT_PLATFORMS` platforms up
            when CasADi is installed, SLSQP otherwise) or ``"paper"``.
        w1: weight of max|F| [1/N]; w2: weight of the plate-deviation term [1/rad].
        ee_tolerance: allow the EE plate to move this far from the goal (position [m],
            rotation [rad]); None keeps it exactly at the goal.
        max_iterations: solver iteration limit.
        ftol: solver's convergence tolerance on the objective.
        rise_margin: smallest rise of a top joint above its bottom joint [m].
        limit_margin: how far inside the stroke [m] and the deflection limit [rad] the
            optimizer keeps the legs (default :data:`GEOMETRIC_MARGIN`; a motion plan keeps
            more, so that the legs stay inside between its samples).
        goal_tolerance: tolerance the final state is checked against when the EE is fixed.
        objective: what is minimized (:data:`~assembler_pin.config.choices.OBJECTIVES`,
            :mod:`assembler_pin.optimize.objective`): ``"force"`` Ω (paper eq. 10), ``"sag"`` the EE's
            sag under its own load, ``"weighted"`` Ω plus ``sag_weight`` times the normalized
            sag; ``"sag"`` and ``"weighted"`` need a smooth method (:data:`SMOOTH_METHODS`).
        sag_weight: the weight w of the sag in the weighted objective (bounds key
            ``optimize.sag_weight``, no unit).
        max_sag: largest EE sag [m] of the answer (bounds key ``optimize.max_sag``), None for
            no limit; needs a smooth method.
    """

    method: str = "auto"
    w1: float = 1.0
    w2: float = 1.0
    ee_tolerance: GoalTolerance | None = None
    max_iterations: int = 200
    ftol: float = 1e-7
    rise_margin: float = 1e-3
    limit_margin: float = GEOMETRIC_MARGIN
    goal_tolerance: GoalTolerance = field(default_factory=lambda: GoalTolerance(1e-9, 1e-9))
    objective: str = "force"
    sag_weight: float = 1.0
    max_sag: float | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.method, str) or self.method not in METHODS:
            raise OptionsError(f"method must be one of {', '.join(METHODS)}, got {short_repr(self.method)}")
        if self.method == "ipopt":
            _check_casadi()
        self._check_sag_options()
        for name, positive in (
            ("w1", False),
            ("w2", False),
            ("ftol", True),
            ("rise_margin", False),
            ("limit_margin", True),
        ):
            value = getattr(self, name)
            x = finite_float(value)  # None for an integer too large for a float, as for NaN
            if x is None or not (x > 0 if positive else x >= 0):
                sign = ">" if positive else ">="
                raise OptionsError(f"{name} must be a finite number {sign} 0, got {short_repr(value)}")
        if self.w1 + self.w2 == 0:
            raise OptionsError("weights w1, w2 must not both be 0")
        if not (
            isinstance(self.max_iterations, numbers.Integral)
            and not isinstance(self.max_iterations, bool)
            and self.max_iterations >= 1
        ):
            raise OptionsError(f"max_iterations must be an integer >= 1, got {short_repr(self.max_iterations)}")
        check_bound("optimize.max_iterations", self.max_iterations, "max_iterations")
        for name in ("ee_tolerance", "goal_tolerance"):
            tol = getattr(self, name)
            if tol is None and name == "ee_tolerance":
                continue
            if not isinstance(tol, GoalTolerance) or not all(
                (finite_float(v) or 0.0) > 0 for v in (tol.position, tol.rotation)
            ):
                shown = short_repr(tol)
                raise OptionsError(f"{name} must be a GoalTolerance of two finite numbers > 0 (m, rad), got {shown}")

    def _check_sag_options(self) -> None:
        """``objective`` one of :data:`~assembler_pin.config.choices.OBJECTIVES`, ``sag_weight`` and
        ``max_sag`` within their bounds rows, and the sag needing the smooth method."""
        if not isinstance(self.objective, str) or self.objective not in OBJECTIVES:
            raise OptionsError(f"objective must be one of {', '.join(OBJECTIVES)}, got {short_repr(self.objective)}")
        check_bound("optimize.sag_weight", self.sag_weight, "sag_weight")
        if self.max_sag is not None:
            check_bound("optimize.max_sag", self.max_sag, "max_sag [m]")
        if self.method not in SMOOTH_METHODS and (self.objective != "force" or self.max_sag is not None):
            raise OptionsError(
                f"objective {self.objective!r} and max_sag need method 'slsqp' (or 'ipopt', 'auto': "
                "the analytic gradients), "
                f"got method {self.method!r}"
            )


#: What a user without CasADi is told.
IPOPT_INSTALL_HINT = "method 'ipopt' needs CasADi (IPOPT), a dependency of assembler_pin: pip install 'casadi>=3.6,<4'"


def casadi_missing() -> bool:
    """CasADi cannot be imported here (checked without importing it: CasADi is heavy)."""
    import importlib.util
    import sys

    if "casadi" in sys.modules:
        return sys.modules["casadi"] is None
    return importlib.util.find_spec("casadi") is None


def _check_casadi() -> None:
    """OptionsError saying how to install CasADi when it cannot be imported."""
    if casadi_missing():
        raise OptionsError(IPOPT_INSTALL_HINT)


def resolved_method(method: str, platforms: int) -> str:
    """The method that runs: ``"auto"`` is ``"ipopt"`` from :data:`AUTO_IPOPT_PLATFORMS`
    platforms up when CasADi is installed, else ``"slsqp"``; any other method itself."""
    if method != "auto":
        return method
    if platforms < AUTO_IPOPT_PLATFORMS:
        return "slsqp"
    if casadi_missing():
        global _told_missing
        if not _told_missing:
            logger.warning(
                "method auto: CasADi is not installed, so SLSQP runs at %d platforms (%s)",
                platforms,
                IPOPT_INSTALL_HINT,
            )
            _told_missing = True
        return "slsqp"
    return "ipopt"


_told_missing = False


@dataclass
class HelperArmOptions:
    """Options of :func:`initial_condition`.

    Attributes:
        d_step: step s of the link-length scan [m] (see :func:`initial_condition`).
        max_attempts: recursion limit: the most arm solves (scan values of d) tried.
        tolerance: EE goal tolerance of the returned state [m, rad].
        regularization: weight w of the pull of the joints toward 0 [m/rad].
        constraint_weight: weight of the stack's leg constraints in the arm IK
            (:meth:`HelperArm.ik`).
        arm_tolerance: the arm counts as reaching the goal within this error [m, rad].
        restarts: extra deterministic starts of the arm IK per d.
        free_link_length: let the arm IK move d continuously over the whole
            :func:`height_range`, starting at each scan value (False: d fixed at the scan
            values, the paper's scan exactly).
        repair_starts: after a scan without success, how many of the arm's closest poses
            (fewest goal error plus leg violation) are repaired on the stack itself
            (0: no repair).
        perturbed_starts: how many randomly perturbed copies of the even screw pose are
            repaired too, after the even pose itself (seeded).
    """

    d_step: float = 0.01
    max_attempts: int = 15
    tolerance: GoalTolerance = field(default_factory=lambda: GoalTolerance(1e-9, 1e-9))
    regularization: float = 0.05
    constraint_weight: float = 10.0
    arm_tolerance: float = 1e-10
    restarts: int = 0
    free_link_length: bool = True
    repair_starts: int = 2
    perturbed_starts: int = 8

    def __post_init__(self) -> None:
        for name in ("d_step", "regularization", "constraint_weight", "arm_tolerance"):
            value = getattr(self, name)
            x = finite_float(value)
            if x is None or not x >= 0:
                raise OptionsError(f"{name} must be a finite number >= 0, got {short_repr(value)}")
        if not self.d_step > 0:
            raise OptionsError(f"d_step must be a positive number of metres, got {short_repr(self.d_step)}")
        for name, low in (("max_attempts", 1), ("restarts", 0), ("repair_starts", 0), ("perturbed_starts", 0)):
            value = getattr(self, name)
            if not (isinstance(value, numbers.Integral) and not isinstance(value, bool) and int(value) >= low):
                raise OptionsError(f"{name} must be an integer >= {low}, got {short_repr(value)}")
        if not isinstance(self.tolerance, GoalTolerance):
            raise OptionsError(f"tolerance must be a GoalTolerance, got {short_repr(self.tolerance)}")
        if not isinstance(self.free_link_length, bool):
            raise OptionsError(f"free_link_length must be True or False, got {short_repr(self.free_link_length)}")
        check_bound("helper.max_attempts", self.max_attempts, "max_attempts")
        check_bound("helper.d_step", self.d_step, "d_step")
