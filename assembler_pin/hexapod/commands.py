"""Commands that give the chosen forces, and how precisely they must be driven.

* :func:`force_optimal_commands` — the force-optimal distribution of the body's load among the
  stacks (:func:`~assembler_pin.walk.macro_statics`: min max|F| within the force limits and the
  stroke, a linear program), and the commanded lengths that realize it exactly: at the given
  poses every leg's spring carries its chosen force when commanded ``L − F / k`` (``L`` its
  length there), so the structure stands at those poses with those forces.
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

from ..exceptions import HexapodError
from ..kinematics import leg_state
from ..model.assembler import AssemblerModel, checked_model
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
    am: AssemblerModel, stacks: Sequence, body_mass: float, body_com: npt.ArrayLike
) -> HexapodCommands:
    """The chosen distribution (module doc) for the stacks welded at their feet, carrying the
    body of ``body_mass`` [kg] at ``body_com`` (world, [m]), and its commanded lengths.

    Raises:
        HexapodError: malformed stacks or body.
    """
    pas = checked_stacks(am, stacks)
    mass, com = checked_body(body_mass, body_com)
    chosen = macro_statics(am, pas, mass, com)
    own = np.array([leg_state(am, pa).lengths for pa in pas])
    return HexapodCommands(
        chosen.forces, own + chosen.length_offsets, chosen.length_offsets, chosen.success, chosen.message
    )


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
