"""Constraint evaluation of a state: every constraint class of the paper (§IV-A).

* leg length limits ``min_length <= L <= max_length``;
* joint deflection ``θ <= max_deflection`` at both ends of every leg;
* force limits ``-max_compression <= F <= max_tension`` (tension positive);
* end effector at the goal within a position [m] and rotation [rad] tolerance;
* continuous translation: each top joint above its bottom joint in the bottom plate's
  frame;
* and, beyond the paper, a near-singular platform (its forces are not defined).

:func:`evaluate_constraints` returns a list of :class:`Violation` — empty when feasible.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import pinocchio as pin

from .common.labels import leg_label, platform_label
from .config.options import DEFAULT_GOAL_TOLERANCE, GoalTolerance
from .config.schema import AssemblerConfig, LegConfig
from .exceptions import OptionsError, PoseError
from .kinematics import LegState, PlateArrays
from .statics.closed_form import CONDITION_LIMIT
from .statics.result import StaticsResult

__all__ = [
    "LEG_LIMIT_ROWS",
    "STROKE_END_TOLERANCE",
    "Violation",
    "at_stroke_end",
    "evaluate_constraints",
    "leg_limit_margins",
]


#: A leg within this distance of an end of its stroke is "at a stroke end": that limit binds
#: (the optimizer holds its legs ``limit_margin``, 1e-7 m, inside the stroke) [m]. The one
#: definition for the results table, the figures and the pages.
STROKE_END_TOLERANCE = 1e-6


def at_stroke_end(lengths: np.ndarray, min_length: float, max_length: float) -> np.ndarray:
    """Mask of the legs whose length [m] is within :data:`STROKE_END_TOLERANCE` of either end
    of the stroke ``[min_length, max_length]``."""
    L = np.asarray(lengths, dtype=float)
    return (L <= min_length + STROKE_END_TOLERANCE) | (L >= max_length - STROKE_END_TOLERANCE)


@dataclass(frozen=True)
class Violation:
    """One violated constraint.

    Attributes:
        kind: ``min_length``, ``max_length``, ``deflection_bottom``, ``deflection_top``,
            ``tension``, ``compression``, ``continuous_translation``, ``ee_position``,
            ``ee_rotation``, ``singular``, ``non_finite_force`` (a force that overflowed:
            never feasible) or ``collision`` (two bodies closer than the clearance allowed).
        platform: platform index j (``None`` for end-effector constraints).
        leg: leg index i within the platform (``None`` when not about one leg).
        value: the offending value, in the constraint's unit ([m], [rad], [N], or the
            condition number for ``singular``).
        limit: the bound it crosses, same unit.
        between: for ``collision``, the names of the two bodies (``value`` is their distance
            [m], ``limit`` the clearance allowed [m]); None otherwise.
    """

    kind: str
    platform: int | None
    leg: int | None
    value: float
    limit: float
    between: tuple[str, str] | None = None

    @property
    def amount(self) -> float:
        """How far past the bound, in the constraint's unit (>= 0)."""
        return abs(self.value - self.limit)

    def to_dict(self) -> dict:
        doc = asdict(self)
        if self.between is None:
            del doc["between"]
        else:
            doc["between"] = list(self.between)
        return doc

    def __str__(self) -> str:
        """``max_length at SP1 leg 2: 0.36 (limit 0.35)`` — 0-based, as :mod:`~assembler_pin.common.labels`."""
        if self.between is not None:  # a collision: a distance [m] between two bodies
            a, b = self.between
            return f"{self.kind} between {a} and {b}: {self.value:.6g} m (limit {self.limit:.6g} m)"
        if self.platform is None:
            where = "end effector"
        elif self.leg is None:
            where = platform_label(self.platform)
        else:
            where = leg_label(self.platform, self.leg)
        return f"{self.kind} at {where}: {self.value:.6g} (limit {self.limit:.6g})"


#: The rows of :func:`leg_limit_margins`, in order.
LEG_LIMIT_ROWS = ("min_length", "max_length", "deflection_bottom", "deflection_top", "continuous_translation")


def leg_limit_margins(
    leg: LegConfig,
    lengths: np.ndarray,
    cos_deflection: np.ndarray,
    rise: np.ndarray,
    margin: float = 0.0,
    rise_margin: float | None = None,
) -> np.ndarray:
    """The one rule of a leg's kinematic limits, as signed margins (positive: inside).

    Used by :func:`evaluate_constraints`, the optimizer's constraint rows, the helper arm's
    joint limits and IK penalty, and the stack repair, each with its own margin.

    Args:
        leg: the limits.
        lengths: (...) pin-to-pin lengths [m].
        cos_deflection: (..., 2) cosine of the deflection at the bottom and top joint.
        rise: (...) height of the top joint above the bottom joint in the bottom plate's
            frame [m].
        margin: how far inside the stroke [m] and the deflection limit [rad] to keep.
        rise_margin: smallest rise [m] (default ``margin``).

    Returns:
        (5, ...) margins, rows :data:`LEG_LIMIT_ROWS`: ``L - (min_length + margin)``,
        ``(max_length - margin) - L`` [m]; ``cos θ - cos(max_deflection - margin)`` at the
        bottom and top joint (cosine form: smooth at θ = 0) [1]; ``rise - rise_margin`` [m].
    """
    cos_limit = math.cos(leg.max_deflection - margin)
    out = np.empty((5, *np.shape(lengths)))  # the three inputs share one shape
    np.subtract(lengths, leg.min_length + margin, out=out[0])
    np.subtract(leg.max_length - margin, lengths, out=out[1])
    np.subtract(cos_deflection[..., 0], cos_limit, out=out[2])
    np.subtract(cos_deflection[..., 1], cos_limit, out=out[3])
    np.subtract(rise, margin if rise_margin is None else rise_margin, out=out[4])
    return out


def _per_leg(kind: str, mask: np.ndarray, values: np.ndarray, limit: float) -> list[Violation]:
    return [
        Violation(kind, int(j), int(i), float(values[j, i]), float(limit))
        for j, i in zip(*np.nonzero(mask), strict=True)
    ]


def evaluate_constraints(
    cfg: AssemblerConfig,
    legs: LegState,
    statics: StaticsResult | None,
    plates: PlateArrays | None = None,
    goal: pin.SE3 | None = None,
    tolerance: GoalTolerance = DEFAULT_GOAL_TOLERANCE,
) -> list[Violation]:
    """All violated constraints of a state (empty list: feasible).

    Args:
        cfg: limits come from here.
        legs: leg state of the pose (:func:`~assembler_pin.kinematics.leg_state`).
        statics: its statics, or None to skip the force and singularity checks.
        plates, goal: with a goal, the EE plate (plates[n]) is checked against it.
        tolerance: EE goal tolerance.
    """
    leg = cfg.leg
    out: list[Violation] = []
    L, defl = legs.lengths, legs.deflection
    m = leg_limit_margins(leg, L, np.cos(defl), legs.rise)
    if not (m[:4].min() >= 0 and m[4].min() > 0):  # the lists only where a leg is out (NaN: out)
        out += _per_leg("min_length", m[0] < 0, L, leg.min_length)
        out += _per_leg("max_length", m[1] < 0, L, leg.max_length)
        out += _per_leg("deflection_bottom", m[2] < 0, defl[..., 0], leg.max_deflection)
        out += _per_leg("deflection_top", m[3] < 0, defl[..., 1], leg.max_deflection)
        out += _per_leg("continuous_translation", m[4] <= 0, legs.rise, 0.0)  # strictly above
    if statics is not None:
        F = statics.forces
        if not (F.max() <= leg.max_tension and F.min() >= -leg.max_compression):  # NaN: not within
            out += _per_leg("non_finite_force", ~np.isfinite(F), F, float("inf"))
            out += _per_leg("tension", F > leg.max_tension, F, leg.max_tension)
            out += _per_leg("compression", F < -leg.max_compression, F, -leg.max_compression)
        for j in np.nonzero(~(statics.condition <= CONDITION_LIMIT))[0]:
            out.append(Violation("singular", int(j), None, float(statics.condition[j]), CONDITION_LIMIT))
    if goal is not None:
        if not isinstance(tolerance, GoalTolerance):
            raise OptionsError(f"tolerance must be a GoalTolerance, got {type(tolerance).__name__}")
        if plates is None:
            raise PoseError("evaluate_constraints: a goal needs the plate poses")
        ee = plates.se3(len(plates) - 1)
        dist = math.hypot(*(ee.translation - goal.translation))  # no overflow warning for huge goals
        angle = float(np.linalg.norm(pin.log3(goal.rotation.T @ ee.rotation)))
        # "not <=": a NaN distance or tolerance is a violation, never a pass
        if not dist <= tolerance.position:
            out.append(Violation("ee_position", None, None, dist, tolerance.position))
        if not angle <= tolerance.rotation:
            out.append(Violation("ee_rotation", None, None, angle, tolerance.rotation))
    return out
