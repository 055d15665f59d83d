"""The hexapod walks on a flat floor (:func:`walk`): the body moves along a straight path to a
goal ``(x, y, yaw)`` while the stacks step in groups, every sample checked by :func:`.stand.stand`.

The walk is a sequence of cycles (the steps), as many as make every foot's travel in each (the
chord of its arc when the body turns) at most ``step`` [m]; cycle ``c`` takes the body from
``B(c/m)`` to ``B((c+1)/m)`` with ``B(s) = (Rz(s yaw), s (x, y, 0))`` (the body turns about the
vertical through the centre of the feet's circle, carried along). In a cycle each group of
stacks (``tripod``: the even and the odd stacks; ``wave``: one stack at a time) in turn

1. **unloads**: the commands go from the distribution where the group stands to the one where
   it hangs, linearly, so its feet's share of the load goes to zero through the commanded
   lengths and no leg force jumps at lift-off;
2. **swings**: its feet lift (by ``lift`` [m], ``sin²`` in height), move (a smooth ``s(u)`` of
   zero speed at both ends along the floor's screw) and land on their footholds ``B((c+1)/m) F``
   (``F`` each foot's start pose), the stacks hanging from the body;
3. **loads**: the commands go back to the distribution where it stands;

then the body moves to ``B((c+1)/m)`` on every foot. A stack's plates between its foot ``P₀``
and its EE plate ``Pₙ`` (fixed to the body) are its home poses with the deformation
``D = log6(Hₙ⁻¹ P₀⁻¹ Pₙ)`` shared evenly: plate ``j`` at ``P₀ Hⱼ exp6(j D / n)`` (``H`` the home
poses relative to plate 0).

The forces are :func:`.share.distribution`'s (a hanging stack carries its own weight, the
standing feet are point supports, the smallest ``Σ F²``). The commanded lengths
are the planned poses' own minus ``F / k``: the structure stands at the planned poses with those
forces. Every sample is re-solved by :func:`.stand.stand` (the hanging feet free): its forces are
the sample's, and a sample whose equilibrium leaves the plan by more than :data:`PLAN_TOL`, or
breaks a limit (stroke, force, deflection, a foot pulling, slipping or rolling, the stability
margin below ``min_margin``) stops the walk with ``success`` false and which step, phase and
limit. Time runs at the legs' ``max_speed``: each sample after the last by the largest change of
a commanded length over ``leg.max_speed`` (accelerations are not planned).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..common.validation import as_float_array
from ..config.bounds import BOUNDS, check_bound
from ..exceptions import HexapodError
from ..kinematics import PlateArrays, leg_state
from ..model.assembler import AssemblerModel, checked_model
from .machine import configured_hexapod
from .share import distribution
from .stand import FEET, stand

__all__ = ["GAITS", "MAX_CYCLES", "PLAN_TOL", "HexapodWalk", "WalkSample", "walk"]

#: The gaits: how the stacks are grouped to step.
GAITS = ("tripod", "wave")
#: Most cycles (steps) of one walk.
MAX_CYCLES = 100
#: Longest step [m]; most samples per phase; highest lift [m].
MAX_STEP_M, MAX_SAMPLES, MAX_LIFT_M = 2.0, 50, 1.0
#: How far [m] a sample's equilibrium may leave the planned plates.
PLAN_TOL = 1e-6


@dataclass(frozen=True)
class WalkSample:
    """One sample of a walk.

    Attributes:
        t: time [s]; step: the cycle, from 1; phase: ``unload``, ``swing``, ``load`` or ``body``.
        body_pose: (6,) the body's centre of mass [m] and its rotation vector from the start [rad].
        feet: (k, 4, 4) every foot plate's world pose; stance: (k,) the feet on the ground.
        lengths: (k, n, 6) commanded lengths [m]; forces: (k, n, 6) the equilibrium's [N].
        plates: (k, n+1, 4, 4) every plate's pose at the equilibrium (planned, when none);
        foot_wrenches: (k, 6) the ground's on each foot [N, N·m] (moment about the foot's origin).
        stability_margin_m: [m] (NaN with welded feet); max_abs_force: [N].
        violations: what the sample breaks (empty when feasible).
    """

    t: float
    step: int
    phase: str
    body_pose: np.ndarray
    feet: np.ndarray
    stance: np.ndarray
    lengths: np.ndarray
    forces: np.ndarray
    plates: np.ndarray
    foot_wrenches: np.ndarray
    stability_margin_m: float
    max_abs_force: float
    violations: tuple[str, ...]


@dataclass(frozen=True)
class HexapodWalk:
    """A walk (:func:`walk`): ``success``, ``reason`` (None on success, else which step, which
    phase and which limit), the samples up to and including the first that fails, the cycles
    planned, the gait and the feet."""

    success: bool
    reason: str | None
    samples: list[WalkSample]
    cycles: int
    gait: str
    feet: str


def _groups(gait: str, k: int) -> list[np.ndarray]:
    if gait == "tripod":
        return [np.arange(k) % 2 == g for g in (0, 1) if (np.arange(k) % 2 == g).any()]
    return [np.arange(k) == i for i in range(k)]


def _plates(rel: list[pin.SE3], foot: pin.SE3, ee: pin.SE3) -> PlateArrays:
    """A stack's plates from its foot to its EE plate (module doc)."""
    n = len(rel) - 1
    D = pin.log6(rel[-1].inverse() * foot.inverse() * ee).vector
    return PlateArrays.from_se3([foot, *[foot * rel[j] * pin.exp6(D * j / n) for j in range(1, n)], ee])


def _checked(to: npt.ArrayLike, gait: object, step: object, feet: object, samples: object, lift: object):
    goal = as_float_array(to, "to (three numbers x [m], y [m], yaw [rad])", (3,), error=HexapodError)
    high = BOUNDS["pose.translation"].high
    if not (np.isfinite(goal).all() and np.abs(goal[:2]).max() <= high and abs(goal[2]) <= math.pi):
        raise HexapodError(f"to: x, y within ±{high:g} m and yaw within ±pi rad, got {goal.tolist()}")
    if not isinstance(gait, str) or gait not in GAITS:
        raise HexapodError(f"gait must be one of {', '.join(GAITS)}, got {gait!r:.40}")
    if not isinstance(feet, str) or feet not in FEET:
        raise HexapodError(f"feet must be one of {', '.join(FEET)}, got {feet!r:.40}")
    for name, value, low, top in (("step", step, 0.0, MAX_STEP_M), ("lift", lift, 0.0, MAX_LIFT_M)):
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
        if not (ok and (low < value if name == "step" else low <= value) and value <= top):  # type: ignore[operator]
            kind = "(0" if name == "step" else "[0"
            raise HexapodError(f"{name} must be a number in {kind}, {top:g}] m, got {value!r:.40}")
    if isinstance(samples, bool) or not isinstance(samples, int) or not 1 <= samples <= MAX_SAMPLES:
        raise HexapodError(f"samples must be an integer in [1, {MAX_SAMPLES}], got {samples!r:.40}")
    return goal


def _body(goal: np.ndarray, s: float) -> pin.SE3:
    return pin.SE3(pin.exp3(np.array([0.0, 0.0, s * goal[2]])), s * np.array([goal[0], goal[1], 0.0]))


def _swing(a: pin.SE3, b: pin.SE3, u: float, lift: float) -> pin.SE3:
    """The swinging foot at ``u`` in [0, 1] from ``a`` to ``b`` (module doc)."""
    s = u - math.sin(2.0 * math.pi * u) / (2.0 * math.pi)
    out = a * pin.exp6(pin.log6(a.inverse() * b).vector * s)
    return pin.SE3(out.rotation, out.translation + np.array([0.0, 0.0, lift * math.sin(math.pi * u) ** 2]))


def _cycles(start: list[pin.SE3], goal: np.ndarray, step: float) -> int:
    """The fewest cycles that keep every foot's travel in every cycle within ``step`` [m] (the
    chord of a turning foot's arc: counted cycle by cycle), or ``MAX_CYCLES + 1``."""
    feet = np.array([f.translation for f in start])
    end = _body(goal, 1.0)
    m = max(1, math.ceil(max(float(np.linalg.norm(end.act(f) - f)) for f in feet) / step - 1e-12))
    while m <= MAX_CYCLES:
        at = np.array([[_body(goal, c / m).act(f) for f in feet] for c in range(m + 1)])
        if float(np.linalg.norm(np.diff(at, axis=0), axis=-1).max()) <= step + 1e-12:  # round-off
            return m
        m += 1
    return m


def _plan(k: int, gait: str, cycles: int, samples: int):
    """Each sample's (cycle, phase, s0, s1, group, u): the body between ``s0`` and ``s1`` at
    ``u`` in the body phase, the group's feet at ``u`` of their phase."""
    out: list[tuple[int, str, float, float, np.ndarray | None, float]] = []
    for c in range(cycles):
        s0, s1 = c / cycles, (c + 1) / cycles
        for group in _groups(gait, k):
            for phase in ("unload", "swing", "load"):
                out += [(c, phase, s0, s1, group, (j + 1) / samples) for j in range(samples)]
        out += [(c, "body", s0, s1, None, (j + 1) / samples) for j in range(samples)]
    return out


def _se3(pa: PlateArrays, j: int) -> pin.SE3:
    return pin.SE3(pa.R[j].copy(), pa.p[j].copy())


class _Walker:
    """The state of a walk being planned: the start, the feet where they stand, the clock."""

    def __init__(self, am: AssemblerModel, feet: str, lift: float, min_margin: float, clearance: bool):
        self.lift, self.friction = lift, am.config.hexapod.friction
        self.am, self.feet, self.min_margin, self.clearance = am, feet, min_margin, clearance
        stacks, self.body_mass, self.body_com = configured_hexapod(am)
        self.start = [_se3(pa, 0) for pa in stacks]
        self.ee = [_se3(pa, am.n) for pa in stacks]
        self.rel = [am.home[0].inverse() * m for m in am.home]
        self.planted = list(self.start)
        self.t, self.last = 0.0, None

    def sample(self, goal: np.ndarray, cycle: int, phase: str, s0: float, s1: float, group, u: float) -> WalkSample:
        am, k = self.am, len(self.start)
        body = _body(goal, s0 + (s1 - s0) * u if phase == "body" else s0)
        hanging = group.copy() if phase == "swing" else np.zeros(k, bool)
        feet = list(self.planted)
        for i in np.flatnonzero(group) if group is not None else ():
            target = _body(goal, s1) * self.start[i]
            if phase == "swing":
                feet[i] = _swing(self.planted[i], target, u, self.lift)
            elif phase == "load":
                feet[i] = self.planted[i] = target
        pas = [_plates(self.rel, f, body * e) for f, e in zip(feet, self.ee, strict=True)]
        com = body.act(self.body_com)
        forces, why = distribution(am, pas, self.body_mass, com, hanging)
        if why is None and phase in ("unload", "load"):
            hung, why = distribution(am, pas, self.body_mass, com, group)
            share = u if phase == "unload" else 1.0 - u
            forces = (1.0 - share) * forces + share * hung
        own = np.array([leg_state(am, pa).lengths for pa in pas])
        lengths = own - np.nan_to_num(forces) / float(am.config.leg.stiffness)
        if self.last is not None:
            self.t += float(np.abs(lengths - self.last).max()) / am.config.leg.max_speed
        self.last = lengths
        pose = np.concatenate([com, pin.log3(body.rotation)])
        matrices = np.array([f.homogeneous for f in feet])
        if why is not None:
            nan = float("nan")
            planned = np.zeros((k, am.n + 1, 4, 4))
            planned[..., :3, :3], planned[..., :3, 3], planned[..., 3, 3] = (
                [pa.R for pa in pas],
                [pa.p for pa in pas],
                1,
            )
            wrenches = np.full((k, 6), np.nan)
            stance = ~hanging
            return WalkSample(
                self.t, cycle + 1, phase, pose, matrices, stance, lengths, forces, planned, wrenches, nan, nan, (why,)
            )
        got = stand(
            am,
            pas,
            self.body_mass,
            com,
            lengths,
            self.feet,
            self.friction,
            self.min_margin,
            None,
            self.clearance,
            hanging,
        )
        violations = list(got.violations)
        moved = float(np.abs(got.plates[..., :3, 3] - np.array([pa.p for pa in pas])).max())
        if moved > PLAN_TOL:
            violations.append(f"the equilibrium leaves the planned plates by {moved:.3g} m > {PLAN_TOL:g} m")
        return WalkSample(
            self.t,
            cycle + 1,
            phase,
            pose,
            matrices,
            ~got.lifted,
            lengths,
            got.forces,
            got.plates,
            got.foot_wrenches,
            got.stability_margin_m,
            got.max_abs_force,
            tuple(violations),
        )


def walk(
    am: AssemblerModel,
    to: npt.ArrayLike,
    gait: str = "tripod",
    step: float = 0.1,
    feet: str = "resting",
    samples: int = 4,
    lift: float = 0.03,
    min_margin: float | None = None,
    check_clearance: bool = False,
) -> HexapodWalk:
    """The walk of the configured hexapod (:func:`.machine.configured_hexapod`) from where it
    stands to the body's displacement ``to = (x [m], y [m], yaw [rad])`` (module doc): ``gait``
    one of :data:`GAITS`, each foot's travel per cycle at most ``step`` [m] (in (0, 2]), feet
    ``resting`` or ``welded``, ``samples`` per phase (1..50), swing feet lifted ``lift`` [m]
    (in [0, 1]), the margin at least ``min_margin`` [m] (None: ``hexapod.min_margin``) and, with
    ``check_clearance``, every sample's clearance checked (:mod:`.clearance`).

    Raises:
        HexapodError: an argument outside what the module doc allows, or a walk of more than
            :data:`MAX_CYCLES` cycles.
    """
    checked_model(am)
    goal = _checked(to, gait, step, feet, samples, lift)
    hc = am.config.hexapod
    if min_margin is not None:
        check_bound("hexapod.min_margin", min_margin, "min_margin", HexapodError)
    walker = _Walker(am, feet, float(lift), hc.min_margin if min_margin is None else min_margin, check_clearance)
    cycles = _cycles(walker.start, goal, float(step))
    if cycles > MAX_CYCLES:
        raise HexapodError(f"the walk needs {cycles} steps > {MAX_CYCLES}: take longer steps or a nearer goal")
    plan = _plan(len(walker.start), gait, cycles, samples)
    out = [walker.sample(goal, 0, "unload", 0.0, 1.0 / cycles, plan[0][4], 0.0)]
    for cycle, phase, s0, s1, group, u in plan:
        if out[-1].violations:
            break
        out.append(walker.sample(goal, cycle, phase, s0, s1, group, u))
    bad = out[-1].violations
    reason = None if not bad else f"step {out[-1].step} ({out[-1].phase}, t = {out[-1].t:.4g} s): {bad[0]}"
    return HexapodWalk(not bad, reason, out, cycles, gait, feet)
