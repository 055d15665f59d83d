"""The hexapod standing: the exact elastic equilibrium of the whole structure for commanded leg
lengths, on welded or resting feet (:func:`stand`).

* ``feet="welded"``: each foot plate is held (gripped) where it is; the ground supplies any
  wrench.
* ``feet="resting"``: the feet stand flat on the horizontal floor under them (every foot plate
  level, all at one height). A foot sticks where it stands (no slip is modelled) as long as its
  ground wrench is admissible (:mod:`.feet`); a foot that would pull lifts off and the
  structure is solved again with it hanging from the body, one foot at a time, the most pulling
  first; a foot that would slip or roll on its edge is a violation (its wrench is reported).
  With the feet on the floor, the static stability margin (:func:`.feet.stability_margin`) of
  the machine's centre of mass (:func:`.machine.machine_com`, in the equilibrium configuration)
  below ``min_margin`` is a violation: the machine would tip.

The forces are returned whatever the limits say, with the violations: a leg's force beyond
``leg.max_tension`` / ``leg.max_compression``, a commanded length outside the stroke, a joint
deflected beyond ``leg.max_deflection_deg``, an equilibrium that is unstable or not found.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..collision import Scene, read_scene
from ..common.validation import as_float_array
from ..config.bounds import check_bound
from ..exceptions import HexapodError
from ..kinematics import PlateArrays, leg_state
from ..model.assembler import AssemblerModel
from .clearance import HexapodClearance, machine_clearance
from .feet import foot_violations, stability_margin
from .machine import checked_body, checked_stacks, machine_com
from .structure import StructureEquilibrium, StructureState, solve_structure

__all__ = ["FEET", "HexapodStand", "stand"]

#: The ways the feet meet the ground.
FEET = ("welded", "resting")

#: How level a resting foot must be (|its z axis − world z|) and how far apart in height the
#: feet may be [m].
LEVEL_TOL = 1e-9


@dataclass(frozen=True)
class HexapodStand:
    """The hexapod's equilibrium (:func:`stand`).

    Attributes:
        forces: (k, n, 6) leg forces [N], tension positive.
        foot_wrenches: (k, 6) what the ground applies to each foot plate [N, N·m], world axes,
            moment about that plate's origin (zero for a lifted foot).
        body_displacement: (6,) the body's translation [m] (its centre of mass) and rotation
            vector [rad] from the given poses.
        plates: (k, n+1, 4, 4) every plate's world pose at the equilibrium.
        lengths: (k, n, 6) the commanded (unloaded) leg lengths [m].
        lifted: (k,) the feet that lifted off (resting feet only).
        com: (3,) the whole machine's centre of mass at the equilibrium [m]; mass [kg].
        stability_margin_m: static stability margin [m] (resting feet; NaN when welded).
        feasible: no violation; violations: what is broken, one line each.
        converged, stable: the equilibrium was found, and its tangent stiffness is positive
            definite.
        feet: ``"welded"`` or ``"resting"``.
        body_com: (3,) the body's centre of mass at the equilibrium [m]; body_mass: [kg].
        clearance: the equilibrium's clearance (:mod:`.clearance`), None when not checked.
    """

    forces: np.ndarray
    foot_wrenches: np.ndarray
    body_displacement: np.ndarray
    plates: np.ndarray
    lengths: np.ndarray
    lifted: np.ndarray
    com: np.ndarray
    mass: float
    stability_margin_m: float
    feasible: bool
    violations: tuple[str, ...]
    converged: bool
    stable: bool
    feet: str
    body_com: np.ndarray
    body_mass: float
    clearance: HexapodClearance | None

    def with_violation(self, violation: str) -> HexapodStand:
        """This answer with one more violation (infeasible)."""
        return replace(self, feasible=False, violations=(*self.violations, violation))

    @property
    def max_abs_force(self) -> float:
        """max |F| over every leg of every stack [N]."""
        return float(np.abs(self.forces).max())


def _checked_lengths(am: AssemblerModel, pas: list[PlateArrays], lengths: object) -> np.ndarray:
    own = np.array([leg_state(am, pa).lengths for pa in pas])
    if lengths is None:
        return own
    got = as_float_array(lengths, f"lengths ({len(pas)}, {am.n}, 6) [m]", own.shape, error=HexapodError)
    if not (np.isfinite(got).all() and got.min() > 0 and got.max() <= 10.0 * am.config.leg.max_length):
        raise HexapodError(
            f"lengths must be finite, positive and at most 10 x leg.max_length = {10 * am.config.leg.max_length:g} m"
        )
    return got


def _check_level(am: AssemblerModel, pas: list[PlateArrays], hanging: np.ndarray) -> None:
    """The feet not ``hanging`` flat on one floor, the hanging ones not below it."""
    if hanging.all():
        raise HexapodError("at least one foot must stand on the floor (every foot is given as hanging)")
    down = [pa for pa, h in zip(pas, hanging, strict=True) if not h]
    z = np.array([pa.p[0, 2] for pa in down])
    tilt = max(float(np.abs(pa.R[0][:, 2] - [0.0, 0.0, 1.0]).max()) for pa in down)
    if tilt > LEVEL_TOL or np.ptp(z) > LEVEL_TOL:
        raise HexapodError("resting feet must lie flat (foot plates level) on one horizontal floor (one height)")
    if any(pa.p[0, 2] < z[0] - LEVEL_TOL for pa, h in zip(pas, hanging, strict=True) if h):
        raise HexapodError("a hanging foot must not be below the floor of the standing feet")


def _checked_hanging(k: int, hanging: object) -> np.ndarray:
    if hanging is None:
        return np.zeros(k, bool)
    got = np.asarray(hanging)
    if got.shape != (k,) or got.dtype != bool:
        raise HexapodError(f"hanging must be {k} booleans (one per stack: its foot hangs from the body)")
    return got.copy()


def _limit_violations(am: AssemblerModel, eq: StructureEquilibrium, rest: np.ndarray) -> list[str]:
    leg, out = am.config.leg, []
    F = np.array([t.tension for t in eq.terms.stacks])
    if F.max() > leg.max_tension:
        out.append(f"a leg's tension {F.max():.6g} N > leg.max_tension {leg.max_tension:g} N")
    if -F.min() > leg.max_compression:
        out.append(f"a leg's compression {-F.min():.6g} N > leg.max_compression {leg.max_compression:g} N")
    if rest.min() < leg.min_length or rest.max() > leg.max_length:
        out.append(f"a commanded length is outside the stroke [{leg.min_length:g}, {leg.max_length:g}] m")
    states = zip(eq.state.R, eq.state.p, strict=True)
    bent = max(float(leg_state(am, PlateArrays(R, p)).deflection.max()) for R, p in states)
    if bent > leg.max_deflection:
        limit = leg.max_deflection_deg
        out.append(f"a joint is deflected {np.degrees(bent):.4g} deg > leg.max_deflection_deg {limit:g}")
    if eq.message is not None:
        out.append(eq.message)
    elif not eq.stable:
        out.append("the equilibrium is unstable (the tangent stiffness is not positive definite)")
    return out


def _resting(
    am: AssemblerModel, start: StructureState, rest: np.ndarray, body_mass: float, tol: float, hanging: np.ndarray
):
    """The equilibrium with feet that lift off when they would pull (module doc), the
    ``hanging`` ones free from the start, and the wrenches of the feet."""
    k = rest.shape[0]
    free = hanging.copy()
    floor = start.p[int(np.argmin(hanging)), 0, 2]
    for _ in range(k + 1):
        eq = solve_structure(am, start, rest, body_mass, free)
        w = np.array([t.base_gradient for t in eq.terms.stacks])
        w[free] = 0.0
        pulling = np.where(~free & (w[:, 2] < -tol), w[:, 2], 0.0)
        sunk = free & (eq.state.p[:, 0, 2] < floor - LEVEL_TOL)
        if eq.message is not None or not (pulling.any() or sunk.any()) or free.all():
            return eq, w, free
        if sunk.any():
            free[int(np.argmax(sunk))] = False
        else:
            free[int(np.argmin(pulling))] = True
    return eq, w, free


def _matrices(state: StructureState) -> np.ndarray:
    """(k, n+1, 4, 4) homogeneous poses of every plate of ``state``."""
    out = np.zeros((*state.R.shape[:2], 4, 4))
    out[..., :3, :3], out[..., :3, 3], out[..., 3, 3] = state.R, state.p, 1.0
    return out


def _ground_violations(
    am: AssemblerModel,
    eq: StructureEquilibrium,
    wrenches: np.ndarray,
    lifted: np.ndarray,
    machine: np.ndarray,
    floor: float,
    friction: float,
    min_margin: float,
    tol: float,
    out: list[str],
) -> float:
    """Append to ``out`` what the resting feet break (:mod:`.feet`), a lifted foot below the
    floor at ``floor`` [m], and tipping; return the stability margin [m] of the machine's
    centre of mass ``machine``."""
    plate, depth = am.config.plate, 0.5 * am.config.plate.thickness
    for i in np.flatnonzero(~lifted):
        out += foot_violations(int(i), wrenches[i], eq.state.p[i, 0], friction, plate.radius, depth, tol)
    for i in np.flatnonzero(lifted & (eq.state.p[:, 0, 2] < floor - LEVEL_TOL)):
        out.append(f"foot {i} would both pull on the floor and sink below it: no contact state holds")
    margin = stability_margin(machine[:2], eq.state.p[~lifted, 0, :2], plate.radius)
    if lifted.all():
        out.append("every foot lifts off: nothing holds the machine")
    elif not margin >= min_margin:
        out.append(f"the stability margin {margin:.4g} m < min_margin {min_margin:g} m: the machine tips")
    return margin


def stand(
    am: AssemblerModel,
    stacks: Sequence,
    body_mass: float,
    body_com: npt.ArrayLike,
    lengths: npt.ArrayLike | None = None,
    feet: str = "welded",
    friction: float = 0.5,
    min_margin: float = 0.0,
    scene: Scene | str | None = None,
    check_clearance: bool = True,
    hanging: npt.ArrayLike | None = None,
) -> HexapodStand:
    """The equilibrium of the hexapod (module doc): ``stacks`` (each its n+1 world plate poses,
    the foot first) under a rigid body of ``body_mass`` [kg] centred at ``body_com`` (world, [m])
    fixed to their EE plates, the legs commanded ``lengths`` (k, n, 6) [m] (None: each pose's
    own lengths). The given poses are the start; the body and every plate but the held feet move.
    With ``check_clearance`` (default) the equilibrium's clearance (:mod:`.clearance`, among
    ``scene``'s obstacles and floor: a scene, a scene file or None) below the configuration's
    ``clearance`` is a violation. ``hanging`` (k booleans, None: none) are the feet that hang
    from the body (a stack in its swing): free from the start, on welded or resting feet.

    Raises:
        HexapodError: malformed stacks, body, lengths, ``feet`` not in :data:`FEET`, resting
            feet not level on one floor (or a hanging foot below it, or every foot
            hanging), ``hanging`` not k booleans, ``friction``/``min_margin`` outside their bounds.
        PoseError: a malformed stack's poses.
    """
    pas = checked_stacks(am, stacks)
    mass, com = checked_body(body_mass, body_com)
    if not isinstance(feet, str) or feet not in FEET:
        raise HexapodError(f"feet must be one of {', '.join(FEET)}, got {feet!r:.40}")
    check_bound("hexapod.friction", friction, "friction", HexapodError)
    check_bound("hexapod.min_margin", min_margin, "min_margin", HexapodError)
    rest = _checked_lengths(am, pas, lengths)
    hung = _checked_hanging(len(pas), hanging)
    obstacles = read_scene(scene)
    start = StructureState(np.array([pa.R for pa in pas]), np.array([pa.p for pa in pas]), com)
    g = am.config.gravity
    total, _ = machine_com(am, start.R, start.p, mass, com)
    tol = 1e-9 * (1.0 + total * g)
    if feet == "welded":
        eq = solve_structure(am, start, rest, mass, hung)
        wrenches, lifted = np.array([t.base_gradient for t in eq.terms.stacks]), hung
        wrenches[hung] = 0.0
    else:
        _check_level(am, pas, hung)
        eq, wrenches, lifted = _resting(am, start, rest, mass, tol, hung)
    violations = _limit_violations(am, eq, rest)
    total, machine = machine_com(am, eq.state.R, eq.state.p, mass, eq.state.com)
    margin = float("nan")
    if feet == "resting":
        floor = float(start.p[int(np.argmin(hung)), 0, 2])
        margin = _ground_violations(am, eq, wrenches, lifted, machine, floor, friction, min_margin, tol, violations)
    turn = eq.state.R[0, -1] @ start.R[0, -1].T
    apart = machine_clearance(am, _matrices(eq.state), turn, obstacles) if check_clearance else None
    if apart is not None and not apart.clear:
        violations.append(apart.message)
    return HexapodStand(
        forces=np.array([t.tension for t in eq.terms.stacks]),
        foot_wrenches=wrenches,
        body_displacement=np.concatenate([eq.state.com - com, pin.log3(turn)]),
        plates=_matrices(eq.state),
        lengths=rest,
        lifted=lifted,
        com=machine,
        mass=total,
        stability_margin_m=margin,
        feasible=not violations,
        violations=tuple(violations),
        converged=eq.message is None,
        stable=eq.stable,
        feet=feet,
        body_com=eq.state.com,
        body_mass=mass,
        clearance=apart,
    )
