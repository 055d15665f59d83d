"""How a walking hexapod shares its load among its stacks (:func:`distribution`).

A hanging stack (its foot in the air) carries its own weight: its legs' forces are the unique
ones of the stack held at its EE plate
(:func:`~assembler_pin.supports.choice.held_equilibrium`, support ``ee``).

A standing stack's foot is pushed by the floor with a vertical force ``f_i`` at its origin and
nothing else (no friction force, no moment: a point support at the foot's centre, so a resting
foot's wrench is always within its friction cone and its centre of pressure at its centre).
The whole machine (the body, every stack) then balances when ``Σ f_i = W`` and
``Σ f_i (x_i, y_i) = W (x_c, y_c)`` (``W`` its weight, ``c`` its centre of mass, :func:`.machine.
machine_com`); the body applies to a standing stack's EE plate what the floor and the stack's
weight leave, and the stack's legs carry it (support ``both``: ``F = F₀ + N u``). Among the
``f`` that balance, the one of the smallest ``Σ F²`` over the standing stacks' legs: a least
squares problem with three equality constraints, solved exactly (its KKT system), unique when
the standing feet are not all on one line, and smooth in the poses: a walk's forces change
continuously. Whether the floor pushes (``f_i ≥ 0``) and the legs are within their limits is
for :func:`.stand.stand` to check.
"""

from __future__ import annotations

import numpy as np

from ..kinematics import PlateArrays
from ..model.assembler import AssemblerModel
from ..supports.choice import held_equilibrium
from .machine import machine_com

__all__ = ["distribution"]


def _moved(wrench: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``wrench`` (force, moment about ``a``) with its moment about ``b``."""
    return np.concatenate([wrench[:3], wrench[3:] + np.cross(a - b, wrench[:3])])


def _standing(am: AssemblerModel, pa: PlateArrays, g: float):
    """A standing stack's forces ``F = A + B f`` (6n,), (6n,) in its foot's force ``f`` [N]."""
    held = held_equilibrium(am, pa, "both")
    if isinstance(held, str):
        return held
    mass, com = machine_com(am, pa.R[None], pa.p[None], 0.0, np.zeros(3))
    foot, ee = pa.p[0], pa.p[-1]
    own = _moved(np.array([0, 0, mass * g, *np.cross(com - foot, [0, 0, mass * g])]), foot, ee)
    per_newton = _moved(np.array([0.0, 0.0, -1.0, 0.0, 0.0, 0.0]), foot, ee)
    N = held.null.reshape(-1, 6)
    return held.particular.ravel() + N @ own, N @ per_newton


def distribution(
    am: AssemblerModel, pas: list[PlateArrays], body_mass: float, body_com: np.ndarray, hanging: np.ndarray
) -> tuple[np.ndarray, str | None]:
    """The leg forces (k, n, 6) [N] (module doc) of the stacks ``pas`` under a body of
    ``body_mass`` [kg] at ``body_com`` [m], the ``hanging`` (k,) stacks in the air; and None, or
    NaN and why there is none."""
    k, g = len(pas), am.config.gravity
    forces = np.full((k, am.n, 6), np.nan)
    R, p = np.array([pa.R for pa in pas]), np.array([pa.p for pa in pas])
    total, com = machine_com(am, R, p, body_mass, np.asarray(body_com, float))
    for i in np.flatnonzero(hanging):
        held = held_equilibrium(am, pas[i], "ee")
        if isinstance(held, str):
            return forces, f"stack {i} cannot hang: {held}"
        forces[i] = held.particular
    standing = np.flatnonzero(~hanging)
    parts = [_standing(am, pas[i], g) for i in standing]
    for i, part in zip(standing, parts, strict=True):
        if isinstance(part, str):
            return forces, f"stack {i} cannot stand: {part}"
    m = len(standing)
    A = np.concatenate([a for a, _ in parts])
    B = np.zeros((len(A), m))
    for j, (_, b) in enumerate(parts):
        B[j * len(b) : (j + 1) * len(b), j] = b
    E = np.vstack([np.ones(m), p[standing, 0, 0], p[standing, 0, 1]])
    d = total * g * np.array([1.0, com[0], com[1]])
    kkt = np.block([[B.T @ B, E.T], [E, np.zeros((3, 3))]])
    rhs = np.concatenate([-B.T @ A, d])
    solution, *_ = np.linalg.lstsq(kkt, rhs, rcond=None)
    f = solution[:m]
    if not np.allclose(E @ f, d, rtol=1e-9, atol=1e-9 * total * g):
        return forces, "the standing feet cannot carry the machine (a single foot, or feet on one line)"
    forces[standing] = (A + B @ f).reshape(m, am.n, 6)
    return forces, None
