"""Every sample of a planned walk checked again, with the support of its phase.

Reach and swing samples: stack FK of the sample's lengths from its held plate (on the model
held at that foot: the package's own, or the turned one for the swing) gives back its plates;
every limit of that model holds; its forces are that support's statics; the held foot does not
move. Transfer samples: the pose's kinematic limits; the forces within the force limits and
the stroke; the commanded lengths applied through the elastic solve held at both ends give the
forces back. Phases follow one another without a jump, and a moving foot ends on its foothold.
Among a scene (``walk.scene``), every sample's clearance is measured again on the stack's own
bodies: at least the configuration's ``clearance`` with the held feet standing, and the moving
foot too when the sample puts it on its foothold's normal within ``walk.lift`` of the
foothold it leaves or lands on (:mod:`assembler_pin.walk.plan`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin

from ..collision.check import clearance
from ..collision.scene import Scene
from ..constraints import Violation
from ..kinematics import PlateArrays, stack_forward_kinematics
from ..model.assembler import AssemblerModel
from ..motion.guess import on_se3
from ..state import evaluate_state
from ..supports.choice import CHECK_TOLERANCE, force_bounds
from ..supports.turned import turned_model
from ..supports.two_point import two_point_statics
from .footholds import plate_target

__all__ = ["SAMPLE_TOLERANCE", "verify_walk"]

#: Largest plate distance [m, or rad] accepted between a sample and the FK of its lengths,
#: between consecutive phases, and between a landed foot and its foothold.
SAMPLE_TOLERANCE = 1e-6

_FORCE_KINDS = {"tension", "compression", "non_finite_force", "singular"}


def _gap(a: PlateArrays, b: PlateArrays, plates: slice | list[int] | None = None) -> float:
    """Largest position [m] or rotation [rad] difference between two sets of plate poses."""
    idx = slice(None) if plates is None else plates
    dp = np.abs(a.p[idx] - b.p[idx]).max()
    dR = np.abs(a.R[idx] - b.R[idx]).max()
    return float(max(dp, dR))


def _moving_sample(am: AssemblerModel, phase, i: int) -> str:
    """Problems of sample ``i`` of a reach or swing ("" when none)."""
    tm = turned_model(am)
    turned = phase.kind == "swing"
    model = tm.model if turned else am
    pa = phase.plates[i]
    mp = tm.plates(pa) if turned else pa
    lengths = tm.turned_legs(phase.lengths[i]) if turned else phase.lengths[i]
    fk = stack_forward_kinematics(model, lengths, base=mp.se3(0), guess=on_se3(mp))
    if not fk.success or _gap(fk.plates, mp) > SAMPLE_TOLERANCE:
        return f"the FK of its lengths does not give its plates back ({fk.message})"
    state = evaluate_state(model, mp)
    if not state.feasible:
        v = state.violations[0]
        return str(tm.original_violation(v) if turned else v)
    forces = tm.original_legs(state.forces) if turned else state.forces
    if np.abs(forces - phase.forces[i]).max() > 1e-9 * max(1.0, np.abs(forces).max()):
        return f"its forces are not the statics of support {phase.support}"
    held = [am.n] if turned else [0]
    if _gap(pa, phase.plates[0], held) > SAMPLE_TOLERANCE:
        return "the held foot moved"
    return ""


def _on_normal(pose: pin.SE3, target: pin.SE3, lift: float) -> bool:
    """True when ``pose`` is ``target`` moved along its own z by at most ``lift`` [m]."""
    rel = target.actInv(pose)
    turn = float(np.linalg.norm(pin.log3(rel.rotation)))
    x, y, z = rel.translation
    return turn <= SAMPLE_TOLERANCE and float(np.hypot(x, y)) <= SAMPLE_TOLERANCE and abs(z) <= lift + SAMPLE_TOLERANCE


def _standing(am: AssemblerModel, walk, k: int, phase, pa: PlateArrays) -> tuple[int, ...]:
    """The plates of sample ``pa`` of phase ``k`` that stand on the floor (module doc)."""
    n = am.n
    if phase.kind == "transfer":
        return (0, n)
    foot, plate, held = ("ee", n, 0) if phase.kind == "reach" else ("base", 0, n)
    ends = [phase.step] + ([phase.step - 2] if phase.step >= 2 else [])
    if any(_on_normal(pa.se3(plate), plate_target(walk.footholds[s], foot), walk.lift) for s in ends):
        return (0, n)
    return (held,)


def _clearance_problem(am: AssemblerModel, walk, k: int, phase, i: int, scene: Scene) -> str:
    pa = phase.plates[i]
    near = clearance(am, pa, dataclasses.replace(scene, standing=_standing(am, walk, k, phase, pa)))
    if near.clear:
        return ""
    return str(Violation("collision", None, None, near.min_distance, near.limit, near.between))


def _transfer_sample(am: AssemblerModel, phase, i: int) -> str:
    pa, F = phase.plates[i], phase.forces[i]
    state = evaluate_state(am, pa)
    kinematic = [v for v in state.violations if v.kind not in _FORCE_KINDS]
    if kinematic:
        return str(kinematic[0])
    lo, hi = force_bounds(am, state.leg_lengths)
    if not np.all((lo <= F) & (F <= hi)):
        return "its forces are beyond the force limits or the stroke"
    el = two_point_statics(am, pa, phase.commanded[i])
    if not el.success or np.abs(el.forces - F).max() > CHECK_TOLERANCE:
        return f"the elastic solve of its commanded lengths does not give its forces ({el.message})"
    return ""


def verify_walk(am: AssemblerModel, walk) -> list[str]:
    """Every problem found in a :class:`~assembler_pin.walk.plan.WalkResult` (module doc),
    each naming its phase and sample; empty when every sample checks."""
    out: list[str] = []
    previous = None
    for k, phase in enumerate(walk.phases):
        where = f"phase {k} ({phase.kind} to foothold {phase.step})"
        if previous is not None and phase.plates and _gap(previous, phase.plates[0]) > SAMPLE_TOLERANCE:
            out.append(f"{where}: it does not start where phase {k - 1} ended")
        check = _transfer_sample if phase.kind == "transfer" else _moving_sample
        for i in range(len(phase.plates)):
            problem = check(am, phase, i)
            if not problem and walk.scene is not None:
                problem = _clearance_problem(am, walk, k, phase, i, walk.scene)
            if problem:
                out.append(f"{where}, sample {i}: {problem}")
        if phase.complete and phase.kind != "transfer":
            foot = "ee" if phase.kind == "reach" else "base"
            plate = am.n if foot == "ee" else 0
            target = plate_target(walk.footholds[phase.step], foot)
            landed = phase.plates[-1].se3(plate)
            if float(np.abs(pin.log6(target.actInv(landed)).vector).max()) > SAMPLE_TOLERANCE:
                out.append(f"{where}: the {foot} foot does not end on foothold {phase.step}")
        previous = phase.plates[-1] if phase.plates else previous
    return out
