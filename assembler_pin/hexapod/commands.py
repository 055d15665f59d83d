"""Commands that give the chosen forces, and how precisely they must be driven.

* :func:`force_optimal_commands` — the force-optimal distribution of the body's load among the
  stacks (:func:`~assembler_pin.walk.macro_statics`: min max|F| within the force limits and the
  stroke, a linear program), and the commanded lengths that realize it exactly: at the given
  poses every leg's spring carries its chosen force when commanded ``L − F / k`` (``L`` its
  length there), so the structure stands at those poses with those forces.
  With ``smallest=True`` the distribution is then, among those of that smallest max|F|, the
  one of the smallest ``Σ F²`` (a convex quadratic program, SLSQP from the linear program's
  answer): unique, and the smallest length offsets ``−F / k`` in the least-squares sense.
  With ``smallest=True`` the distribution is then, among those of that smallest max|F|, the
  one of the smallest ``Σ F²`` (a convex quadratic program, SLSQP from the linear program's
  answer): unique, and the smallest length offsets ``−F / k`` in the least-squares sense.
* :func:`length_sensitivity` — ``∂F/∂L_cmd`` (6nk, 6nk) [N/m] at an equilibrium: with ``H`` the
  whole structure's tangent stiffness and ``A`` the legs' length Jacobian over its unknowns
  (:func:`.structure.leg_jacobian`), ``∂F/∂L_cmd = k (k A H⁻¹ Aᵀ − I)`` (the spring's own
  ``−k``, and what the structure's motion gives back).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.linalg import cho_factor, cho_solve
from scipy.optimize import minimize

from ..common.linalg import skew
from ..exceptions import HexapodError
from ..kinematics import leg_state
from ..model.assembler import AssemblerModel, checked_model
from ..supports.choice import force_bounds, held_equilibrium
from ..walk.macro import macro_statics
from .machine import checked_body, checked_stacks
from .stand import HexapodStand
from .structure import StructureState, leg_jacobian, structure_terms

__all__ = ["HexapodCommands", "force_optimal_commands", "length_sensitivity"]


@dataclass(frozen=True)
class HexapodCommands:
    """The force-optimal distribution and its commands (:func:`force_optimal_commands`).

    Attributes:
        forces: (k, n, 6) the chosen leg forces [N], tension positive (NaN on failure).
        lengths: (k, n, 6) the commanded lengths that realize them [m].
        offsets: (k, n, 6) those lengths minus the poses' own [m].
        success: a distribution within every limit was found; message: what, or why not.
    """

    forces: np.ndarray
    lengths: np.ndarray
    offsets: np.ndarray
    success: bool
    message: str

    @property
    def max_abs_force(self) -> float:
        return float(np.abs(self.forces).max())


def force_optimal_commands(
    am: AssemblerModel, stacks: Sequence, body_mass: float, body_com: npt.ArrayLike, smallest: bool = False
) -> HexapodCommands:
    """The chosen distribution (module doc) for the stacks welded at their feet, carrying the
    body of ``body_mass`` [kg] at ``body_com`` (world, [m]), and its commanded lengths; with
    ``smallest`` the one of the smallest ``Σ F²`` among those of the smallest max|F|.

    Raises:
        HexapodError: malformed stacks or body.
    """
    pas = checked_stacks(am, stacks)
    mass, com = checked_body(body_mass, body_com)
    chosen = macro_statics(am, pas, mass, com)
    own = np.array([leg_state(am, pa).lengths for pa in pas])
    forces, message = chosen.forces, chosen.message
    if chosen.success and smallest:
        forces, message = _smallest(am, pas, mass, com, chosen.body_wrenches, chosen.max_abs_force)
    offsets = -forces / float(am.config.leg.stiffness)
    return HexapodCommands(forces, own + offsets, offsets, chosen.success, message)


def _program(am: AssemblerModel, pas: list):
    """Every stack's leg forces affine in the wrench on its EE plate, ``F = F0 + N u`` (stacked,
    u (6k,)), the force bounds, and the (6, 6k) map of the wrenches to their sum about the
    world origin."""
    P, N, lo, hi, B = [], [], [], [], []
    for pa in pas:
        eq = held_equilibrium(am, pa, "both")
        assert not isinstance(eq, str), "the linear program solved it"
        P.append(eq.particular.ravel())
        N.append(eq.null.reshape(-1, 6))
        bounds = force_bounds(am, leg_state(am, pa).lengths)
        lo.append(bounds[0].ravel())
        hi.append(bounds[1].ravel())
        M = np.eye(6)
        M[3:, :3] = skew(pa.p[-1])  # the wrench about the EE origin, about the world origin
        B.append(M)
    k, m = len(pas), len(P[0])
    Nb = np.zeros((k * m, 6 * k))
    for i in range(k):
        Nb[i * m : (i + 1) * m, 6 * i : 6 * i + 6] = N[i]
    return np.concatenate(P), Nb, np.concatenate(lo), np.concatenate(hi), np.hstack(B)


def _smallest(am: AssemblerModel, pas: list, mass: float, com: np.ndarray, u0: np.ndarray, peak: float):
    """The distribution of the smallest ``Σ F²`` with max|F| ≤ ``peak`` (module doc), from the
    linear program's wrenches ``u0`` (k, 6) on the EE plates; (forces (k, n, 6), message)."""
    F0, Nb, lo, hi, balance = _program(am, pas)
    top, bottom = np.minimum(hi, peak * (1 + 1e-9)), np.maximum(lo, -peak * (1 + 1e-9))
    f = np.array([0.0, 0.0, -mass * am.config.gravity])
    G = np.concatenate([f, np.cross(com, f)])
    scale = 1.0 / max(peak * peak * len(F0), 1e-300)  # the objective of order 1
    res = minimize(
        lambda u: scale * float((F0 + Nb @ u) @ (F0 + Nb @ u)),
        u0.ravel(),
        jac=lambda u: 2.0 * scale * Nb.T @ (F0 + Nb @ u),
        constraints=[
            {"type": "ineq", "fun": lambda u: top - F0 - Nb @ u, "jac": lambda u: -Nb},
            {"type": "ineq", "fun": lambda u: F0 + Nb @ u - bottom, "jac": lambda u: Nb},
            {"type": "eq", "fun": lambda u: balance @ u - G, "jac": lambda u: balance},
        ],
        method="SLSQP",
        options={"ftol": 1e-13, "maxiter": 500},
    )
    F, shape = F0 + Nb @ res.x, (len(pas), am.n, 6)
    if not (res.success and np.all(F <= top + 1e-7) and np.all(F >= bottom - 1e-7)):
        why = f"min max|F| (HiGHS); the smallest sum of squares was not found (SLSQP: {res.message})"
        return (F0 + Nb @ u0.ravel()).reshape(shape), why
    return F.reshape(shape), "min max|F| (HiGHS), then the smallest sum of squares among those (SLSQP)"


def length_sensitivity(am: AssemblerModel, result: HexapodStand) -> np.ndarray:
    """``∂F/∂L_cmd`` (6nk, 6nk) [N/m] at the equilibrium of ``result`` (module doc): row ``a``,
    column ``b`` is the change of leg ``a``'s force per metre of leg ``b``'s command, legs in
    the order of ``result.forces.ravel()``. The feet stay as in ``result`` (held, or lifted).

    Raises:
        HexapodError: ``result`` is not a :class:`~assembler_pin.hexapod.stand.HexapodStand`
            of this model.
    """
    checked_model(am)
    if not isinstance(result, HexapodStand) or result.forces.shape[1] != am.n:
        raise HexapodError("length_sensitivity needs a HexapodStand of this model (from stand(am, ...))")
    state = StructureState(result.plates[..., :3, :3].copy(), result.plates[..., :3, 3].copy(), result.body_com.copy())
    terms = structure_terms(am, state, result.lengths, result.body_mass, result.lifted)
    A = leg_jacobian(am, state, result.lifted)
    k = float(am.config.leg.stiffness)
    try:
        HA = cho_solve(cho_factor(terms.hessian), A.T)
    except np.linalg.LinAlgError:
        HA = np.linalg.solve(terms.hessian, A.T)
    return k * (k * A @ HA - np.eye(A.shape[0]))
