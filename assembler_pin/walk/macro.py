"""The macro-configuration: several stacks, each standing on its base plate, their EE plates
joined to one rigid body (six Assemblers as the legs of a hexapod).

With ``k`` stacks the body's six equations meet ``6k`` unknown wrenches (what the body applies
to each stack's EE plate): ``6(k − 1)`` are redundant, like the two-point support's six. Each
stack's leg forces are affine in the wrench ``u`` on its EE plate (world axes, moment about
that plate's origin): ``F = P + N u`` (:func:`~assembler_pin.supports.choice.held_equilibrium`
of the stack held at both ends: ``P`` the base-held forces, ``N`` the internal force patterns).
The body in equilibrium under its weight needs ``Σ_i u_i = G`` (moments about one point), ``G``
the body's weight wrench ``[0, 0, −m g]`` at its centre of mass.

* :func:`macro_statics` — the **chosen distribution**: the wrenches minimizing max|F| over
  every leg of every stack within the force limits and the stroke (a linear program, HiGHS),
  with the length offsets ``−F / k`` that realize it.
* :func:`macro_capacity` — the largest body mass any distribution carries within the limits
  (a linear program in the mass and the wrenches).

**The tool payload.** Each stack is modelled by ``am``, payload included: every stack carries
its configured tool payload (``payload.mass`` at ``payload.com`` on its EE plate: 5 kg at
0.2 m with the default configuration) besides its share of the body, so a 0 kg body gives
each stack its loaded ``statics --home`` forces. For the body alone, model the stacks
without a payload: ``AssemblerModel.from_config(cfg.replace(payload=PayloadConfig(mass=0.0)))``.

The elastic distribution of the macro-configuration (the stacks' compliance sharing the
body's load for given commanded lengths, on welded or resting feet) is
:func:`assembler_pin.hexapod.stand`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.optimize import linprog

from ..common.validation import as_float_array
from ..config.bounds import BOUNDS, check_bound
from ..exceptions import WalkError
from ..kinematics import PlateArrays, leg_vectors, plate_arrays
from ..model.assembler import AssemblerModel, checked_model
from ..supports.choice import force_bounds, held_equilibrium

__all__ = ["MacroStatics", "macro_capacity", "macro_statics"]


@dataclass(frozen=True)
class MacroStatics:
    """The chosen distribution of a macro-configuration (:func:`macro_statics`).

    Attributes:
        forces: (k, n, 6) leg forces of every stack [N], tension positive (NaN on failure).
        length_offsets: (k, n, 6) commanded minus the poses' own lengths, ``−F / k`` [m].
        body_wrenches: (k, 6) what the body applies to each stack's EE plate [N, N·m], world
            axes, moment about that plate's origin.
        success: a distribution within the limits was found; message: what, or why not.
    """

    forces: np.ndarray
    length_offsets: np.ndarray
    body_wrenches: np.ndarray
    success: bool
    message: str

    @property
    def max_abs_force(self) -> float:
        """max |F| over every leg [N] (NaN on failure)."""
        return float(np.abs(self.forces).max())


def _stacks(am: AssemblerModel, stacks: Sequence) -> list[PlateArrays]:
    checked_model(am)
    if isinstance(stacks, (str, bytes)) or not hasattr(stacks, "__len__") or not 1 <= len(stacks) <= 16:
        raise WalkError("stacks must be a list of 1..16 plate poses (each n+1 world poses)")
    return [plate_arrays(am, s) for s in stacks]


def _body_com(body_com: object) -> np.ndarray:
    """``body_com`` as three finite numbers [m] within the ``pose.translation`` bound."""
    com = as_float_array(body_com, "body_com (three numbers x, y, z [m])", (3,), error=WalkError)
    if not np.all(np.isfinite(com)):
        raise WalkError(f"body_com must be three finite numbers [m], got {com.tolist()}")
    high = BOUNDS["pose.translation"].high
    if not np.abs(com).max() <= high:
        raise WalkError(f"body_com: every coordinate within ±{high:g} m (pose.translation), got {com.tolist()}")
    return com


def _moved_to(point: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """(6, 6) map of a wrench about ``origin`` to the same wrench about ``point``."""
    M = np.eye(6)
    r = origin - point  # m_point = m_origin + (origin − point) × f
    M[3:, :3] = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
    return M


def _program(am: AssemblerModel, stacks: list[PlateArrays]):
    """Per stack ``P`` (6n,), ``N`` (6n, 6), bounds, and the (6, 6k) body balance about the
    world origin; or the reason there is none."""
    P, N, lo, hi, balance = [], [], [], [], []
    for i, pa in enumerate(stacks):
        eq = held_equilibrium(am, pa, "both")
        if isinstance(eq, str):
            return f"stack {i}: {eq}"
        P.append(eq.particular.ravel())
        N.append(eq.null.reshape(-1, 6))
        bounds = force_bounds(am, leg_vectors(am, pa)[3])
        lo.append(bounds[0].ravel())
        hi.append(bounds[1].ravel())
        # held_equilibrium's wrench is about the EE origin already: the body balance about 0
        balance.append(_moved_to(np.zeros(3), pa.p[-1]))
    return P, N, np.concatenate(lo), np.concatenate(hi), np.hstack(balance)


def _weight_wrench(mass: float, com: np.ndarray, gravity: float) -> np.ndarray:
    f = np.array([0.0, 0.0, -mass * gravity])
    return np.concatenate([f, np.cross(com, f)])


def macro_statics(am: AssemblerModel, stacks: Sequence, body_mass: float, body_com: npt.ArrayLike) -> MacroStatics:
    """The chosen distribution (module doc) of the stacks ``stacks`` (each its n+1 world plate
    poses, its plate 0 held) carrying a body of ``body_mass`` [kg] centred at ``body_com`` (world,
    [m]) on their EE plates. Each stack also carries its configured tool payload (module doc):
    with ``body_mass`` 0 the forces are those of the stacks under their own payloads.

    Raises:
        WalkError: malformed stacks, a mass outside ``macro.body_mass`` or a centre of mass
            that is not three finite numbers within ``pose.translation``.
        ArgumentError: ``am`` is not a model.
    """
    pas = _stacks(am, stacks)
    check_bound("macro.body_mass", body_mass, "body_mass", WalkError)
    com = _body_com(body_com)
    k, n6 = len(pas), 6 * am.n
    nan = np.full((k, am.n, 6), np.nan)
    prog = _program(am, pas)
    if isinstance(prog, str):
        return MacroStatics(nan, nan, np.full((k, 6), np.nan), False, prog)
    P, N, lo, hi, balance = prog
    Fp, big = np.concatenate(P), np.zeros((k * n6, 6 * k))
    for i in range(k):
        big[i * n6 : (i + 1) * n6, 6 * i : 6 * i + 6] = N[i]
    ones, zeros = np.ones((k * n6, 1)), np.zeros((k * n6, 1))
    A = np.block([[big, -ones], [-big, -ones], [big, zeros], [-big, zeros]])
    b = np.concatenate([-Fp, Fp, hi - Fp, Fp - lo])
    G = _weight_wrench(body_mass, com, am.config.gravity)
    A_eq, cost = np.hstack([balance, np.zeros((6, 1))]), np.r_[np.zeros(6 * k), 1.0]
    res = linprog(cost, A_ub=A, b_ub=b, A_eq=A_eq, b_eq=G, bounds=[(None, None)] * 6 * k + [(0, None)], method="highs")
    if res.status != 0 or res.x is None:
        why = f"no distribution carries the body within the force limits and the stroke (HiGHS: {res.message})"
        return MacroStatics(nan, nan, np.full((k, 6), np.nan), False, why)
    u = res.x[:-1].reshape(k, 6)
    F = (Fp + big @ res.x[:-1]).reshape(k, am.n, 6)
    offsets = -F / float(am.config.leg.stiffness)
    return MacroStatics(F, offsets, u, True, "minimal max|F| over every stack within the limits (HiGHS)")


def macro_capacity(am: AssemblerModel, stacks: Sequence, body_com: npt.ArrayLike) -> tuple[float, str]:
    """The largest body mass [kg] (centred at ``body_com``, world [m]) that some distribution
    carries within every leg's force limits and stroke, and a note; 0 with the reason when the
    stacks cannot even carry themselves. The stacks' configured tool payloads are carried too
    (module doc): the body's mass is on top of them.

    Raises:
        WalkError: malformed stacks or centre of mass.
    """
    pas = _stacks(am, stacks)
    com = _body_com(body_com)
    prog = _program(am, pas)
    if isinstance(prog, str):
        return 0.0, prog
    P, N, lo, hi, balance = prog
    k, n6 = len(pas), 6 * am.n
    Fp, big = np.concatenate(P), np.zeros((k * n6, 6 * k))
    for i in range(k):
        big[i * n6 : (i + 1) * n6, 6 * i : 6 * i + 6] = N[i]
    unit = _weight_wrench(1.0, com, am.config.gravity)
    A = np.block([[big, np.zeros((k * n6, 1))], [-big, np.zeros((k * n6, 1))]])
    b = np.concatenate([hi - Fp, Fp - lo])
    A_eq = np.hstack([balance, -unit[:, None]])
    cost = np.r_[np.zeros(6 * k), -1.0]
    res = linprog(
        cost, A_ub=A, b_ub=b, A_eq=A_eq, b_eq=np.zeros(6), bounds=[(None, None)] * 6 * k + [(0, 1e6)], method="highs"
    )
    if res.status != 0 or res.x is None:
        return 0.0, f"the stacks cannot carry even themselves within the limits (HiGHS: {res.message})"
    return float(res.x[-1]), "largest body mass within every leg's limits (HiGHS)"
