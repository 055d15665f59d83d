"""The stack repair: move the internal plates until every leg is within its limits.

Used by the initial condition when no arm pose gives a valid stack, and by ``solve`` for its
fallback starts. Units: metres and radians.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from ..constraints import leg_limit_margins
from ..exceptions import PoseError
from ..kinematics import PlateArrays, leg_state
from ..model.assembler import AssemblerModel
from ..statics.derivatives import leg_derivatives

__all__ = ["perturbed_plates", "repair_stack"]


def _leg_hinge(am: AssemblerModel, pa: PlateArrays, margin: float) -> np.ndarray:
    """Amounts by which every leg breaks a kinematic constraint, each bound tightened by
    ``margin`` (the negated :func:`~assembler_pin.constraints.leg_limit_margins`, clipped at
    0): [m] for stroke and rise, cosine for the deflection. Zero where valid."""
    legs = leg_state(am, pa)
    return np.maximum(
        -leg_limit_margins(am.config.leg, legs.lengths, np.cos(legs.deflection), legs.rise, margin), 0.0
    ).ravel()


def _hinge_jacobian(am: AssemblerModel, pa: PlateArrays, x: np.ndarray, margin: float) -> np.ndarray:
    """Analytic Jacobian of :func:`_leg_hinge` w.r.t. the local twists ``x`` of plates
    1..n-1 (plate k = ``start_k·exp6(x_k)``): the world-twist derivatives of
    :func:`~assembler_pin.statics.derivatives.leg_derivatives`, times ``Ad(T_k)·Jexp6(x_k)`` per plate
    (a local change δ of x_k moves plate k by the world twist ``Ad(T_k)·Jexp6(x_k)·δ``).
    Rows past their bound have the bound's derivative, the others zero."""
    n = am.n
    ld = leg_derivatives(am, pa)
    rows = np.stack(
        [ld.d_lengths, -ld.d_lengths, ld.d_cos_deflection[:, :, 0], ld.d_cos_deflection[:, :, 1], ld.d_rise]
    )  # (5, n, 6, 6n): derivatives of the margins
    margins = leg_limit_margins(am.config.leg, ld.lengths, ld.cos_deflection, ld.rise, margin)
    d_hinge = np.where((margins < 0)[..., None], -rows, 0.0).reshape(30 * n, n, 6)[:, : n - 1]
    chain = np.array([pa.se3(k).action @ pin.Jexp6(x[6 * (k - 1) : 6 * k]) for k in range(1, n)])  # (n-1, 6, 6)
    return np.einsum("rka,kab->rkb", d_hinge, chain).reshape(30 * n, 6 * (n - 1))


def repair_stack(
    am: AssemblerModel, start: list[pin.SE3], margin: float = 1e-6, max_nfev: int = 100
) -> tuple[PlateArrays, float]:
    """Move plates 1..n-1 from ``start`` until every leg of the stack is valid.

    Plates 0 and n stay where ``start`` has them (the base and the goal). Plate k becomes
    ``start_k·exp6(x_k)``; ``scipy.optimize.least_squares`` (``trf``, analytic Jacobian
    :func:`_hinge_jacobian`) drives the leg constraints' violation (:func:`_leg_hinge`,
    ``margin`` [m or rad] inside every bound) to zero from x = 0, so the plates move little.

    Returns:
        (the plates reached, the largest remaining violation [m or rad]; 0 means valid, inf
        where the legs are not defined on the way: two joint centres of a leg met).
    """
    n = len(start) - 1
    rot0 = np.array([m.rotation for m in start])
    pos0 = np.array([m.translation for m in start])
    if n < 2:  # nothing to move
        pa = PlateArrays(rot0, pos0)
        try:
            return pa, float(_leg_hinge(am, pa, 0.0).max())
        except PoseError:
            return pa, math.inf

    def plates(x: np.ndarray) -> PlateArrays:
        rot, pos = rot0.copy(), pos0.copy()
        for k in range(1, n):
            m = start[k] * pin.exp6(x[6 * (k - 1) : 6 * k])
            rot[k], pos[k] = m.rotation, m.translation
        return PlateArrays(rot, pos)

    from scipy.optimize import least_squares  # on first use: fast start-up

    try:
        res = least_squares(
            lambda x: _leg_hinge(am, plates(x), margin),
            np.zeros(6 * (n - 1)),
            jac=lambda x: _hinge_jacobian(am, plates(x), x, margin),
            method="trf",
            ftol=1e-15,
            xtol=1e-15,
            gtol=1e-15,
            max_nfev=max_nfev,
        )
        pa = plates(res.x)
        return pa, float(_leg_hinge(am, pa, 0.0).max())
    except PoseError:  # a trial point with a leg of zero length: no repair from this start
        return PlateArrays(rot0, pos0), math.inf


def perturbed_plates(
    plates: list[pin.SE3],
    count: int,
    seed: int = 0,
    twist: tuple[float, float] = (0.05, 0.3),
    rng: np.random.Generator | None = None,
) -> list[list[pin.SE3]]:
    """``count`` copies of ``plates`` with plates 1..n-1 moved by random twists of up to
    ``twist`` per axis (translation [m], rotation [rad]; default ±5 cm, ±0.3 rad), drawn from
    ``rng`` when given, else from a generator seeded by ``seed`` (reproducible)."""
    rng = np.random.default_rng(seed) if rng is None else rng
    dp, dr = twist
    out = []
    for _ in range(count):
        moved = [m.copy() for m in plates]
        for k in range(1, len(plates) - 1):
            moved[k] = moved[k] * pin.exp6(np.concatenate([rng.uniform(-dp, dp, 3), rng.uniform(-dr, dr, 3)]))
        out.append(moved)
    return out
