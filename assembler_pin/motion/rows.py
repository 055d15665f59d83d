"""A trajectory's rows against the model: what each commanded set of leg lengths does.

* :func:`evaluate_rows` — stack FK, statics, the forces with the motion's own part
  (:mod:`assembler_pin.dynamics`) and every constraint margin at each row of a timed plan
  (how :func:`~assembler_pin.motion.timing.time_parametrize` fills a trajectory).
* :func:`check_trajectory` — hold every row of a trajectory (e.g. one read from a file) to
  the model: stroke, speeds and accelerations within the config's limits, and the EE
  written in the row equal to stack FK of its lengths.
* :func:`trajectory_states` — the stack at chosen rows, rebuilt from the lengths.

Every FK here starts from a pose on SE(3) (:func:`~assembler_pin.motion.guess.on_se3`), so
chaining thousands of rows does not drift.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..common.progress import ProgressCallback
from ..config.options import GoalTolerance
from ..constraints import leg_limit_margins
from ..dynamics import inverse_dynamics_from_lengths
from ..exceptions import TrajectoryError
from ..kinematics import PlateArrays, se3_to_taa, stack_forward_kinematics, taa_to_se3
from ..model.assembler import AssemblerModel
from ..state import StackState, evaluate_state
from .guess import on_se3
from .trajfile import MARGIN_KINDS, Trajectory

__all__ = ["check_trajectory", "evaluate_rows", "trajectory_states"]


def evaluate_rows(
    am: AssemblerModel,
    plan,
    times: np.ndarray,
    lengths: np.ndarray,
    u: np.ndarray,
    meta: dict,
    strict: bool = True,
    progress: ProgressCallback | None = None,
    rates: np.ndarray | None = None,
    accels: np.ndarray | None = None,
) -> Trajectory:
    """Stack FK, statics, the forces with the motion's own part and every constraint margin
    at each row.

    Args:
        plan: the :class:`~assembler_pin.motion.planner.PlanResult` the rows follow.
        times: (T,) [s]; lengths: (T, n, 6) [m]; u: (T,) path parameter of each row.
        strict: raise when FK fails at a row; otherwise mark it infeasible (NaN pose).
        rates, accels: (T, n, 6) the legs' length rates [m/s] and accelerations [m/s²] of the
            time law at each row (default: at rest, the dynamic forces are the statics).
    """
    tol: GoalTolerance = plan.path_tolerance
    T = len(times)
    ee, force, feasible = np.full((T, 6), np.nan), np.full(T, np.nan), np.zeros(T, dtype=bool)
    dynamic = np.full((T, am.n, 6), np.nan)
    margins = {k: np.full(T, np.nan) for k in MARGIN_KINDS}
    base = plan.states[0].plates.se3(0)
    knots = plan.parameters
    guess = None
    for k in range(T):
        if progress is not None and k % 50 == 0:
            progress(k, T, "checking output samples")
        near = plan.states[int(np.clip(np.searchsorted(knots, u[k]), 0, len(knots) - 1))].plates
        fk = stack_forward_kinematics(am, lengths[k], base=base, guess=on_se3(near if guess is None else guess))
        if not fk.success and guess is not None:  # after a fast stretch the nearest sample is the better guess
            fk = stack_forward_kinematics(am, lengths[k], base=base, guess=on_se3(near))
        if not fk.success:
            if strict:
                raise TrajectoryError(f"stack FK failed at t = {times[k]:.3f} s: {fk.message}")
            continue
        guess = fk.plates
        target = plan.path.at(u[k])
        state = evaluate_state(am, fk.plates, goal=target, tolerance=tol)
        if rates is not None and accels is not None and (np.any(rates[k]) or np.any(accels[k])):
            dynamic[k] = inverse_dynamics_from_lengths(am, fk.plates, rates[k], accels[k]).forces
        else:
            dynamic[k] = state.forces
        _row_margins(am, state, target, tol, margins, k, dynamic[k])
        ee[k], force[k] = se3_to_taa(fk.plates.se3(am.n)), state.max_abs_force
        feasible[k] = state.feasible and margins["force_dynamic"][k] >= 0
    if progress is not None:
        progress(T, T, "checked output samples")
    return Trajectory(times, lengths, ee, force, margins, feasible, am.n, meta, dynamic)


def _row_margins(
    am: AssemblerModel,
    state: StackState,
    target: pin.SE3,
    tol: GoalTolerance,
    margins: dict,
    k: int,
    dynamic: np.ndarray,
) -> None:
    """Fill row ``k`` of every margin kind from the row's state and its forces with the
    motion's part (see :class:`Trajectory`)."""
    leg = am.config.leg
    rows = leg_limit_margins(leg, state.legs.lengths, np.cos(state.legs.deflection), state.legs.rise, 0.0)
    pose = state.plates.se3(am.n)
    margins["stroke"][k] = rows[:2].min()
    margins["deflection"][k] = leg.max_deflection - state.legs.deflection.max()  # [rad], not the cosine rows
    margins["rise"][k] = rows[4].min()
    margins["force"][k] = min(leg.max_tension - state.forces.max(), leg.max_compression + state.forces.min())
    margins["force_dynamic"][k] = min(leg.max_tension - dynamic.max(), leg.max_compression + dynamic.min())
    margins["path_position"][k] = tol.position - np.linalg.norm(pose.translation - target.translation)
    margins["path_rotation"][k] = tol.rotation - np.linalg.norm(pin.log3(target.rotation.T @ pose.rotation))


def _start_guess(am: AssemblerModel, base: pin.SE3) -> PlateArrays:
    """The home pose carried onto ``base``: a far, neutral FK start."""
    home = evaluate_state(am, am.home).plates
    shift = base * home.se3(0).inverse()
    return PlateArrays.from_se3([shift * home.se3(k) for k in range(am.n + 1)])


def _base(am: AssemblerModel, traj: Trajectory) -> pin.SE3:
    return pin.SE3(np.asarray(traj.meta["base"], dtype=float)) if "base" in traj.meta else am.home[0]


def _check_forces(am: AssemblerModel, traj: Trajectory) -> None:
    """Every row's leg forces (with the motion's part, where the file has them) within the
    model's tension and compression limits, and its max|F| column no larger than the
    largest of them allows (the columns are not taken on trust)."""
    if traj.dynamic_forces is None:
        return
    leg = am.config.leg
    F = traj.dynamic_forces
    over = (F > leg.max_tension * (1 + 1e-9)) | (F < -leg.max_compression * (1 + 1e-9))
    if over.any():
        k = int(np.argmax(over.any(axis=(1, 2))))
        raise TrajectoryError(
            f"at t = {traj.times[k]:.3f} s a leg force is outside the limits "
            f"[-{leg.max_compression:g}, {leg.max_tension:g}] N"
        )


def check_trajectory(
    am: AssemblerModel,
    traj: Trajectory,
    tolerance: float = 1e-6,
    keep: np.ndarray | None = None,
    progress: ProgressCallback | None = None,
) -> dict[int, PlateArrays]:
    """Hold every row of ``traj`` to the model (see the module docstring).

    Args:
        tolerance: largest distance [m] and angle [rad] between a row's EE and stack FK of
            its lengths.
        keep: row indices whose FK plates to return (default none).

    Returns:
        row index → world plate poses from stack FK, for the rows in ``keep``.

    Raises:
        TrajectoryError: naming the first row that fails and how.
    """
    if traj.platforms != am.n:
        raise TrajectoryError(f"the trajectory is for {traj.platforms} platforms, the model has {am.n}")
    leg = am.config.leg
    L = traj.lengths
    out = (L < leg.min_length - 1e-9) | (L > leg.max_length + 1e-9)
    if out.any():
        k = int(np.argmax(out.any(axis=(1, 2))))
        raise TrajectoryError(
            f"at t = {traj.times[k]:.3f} s a leg length is outside the stroke "
            f"[{leg.min_length:g}, {leg.max_length:g}] m"
        )
    _check_rates(am, traj)
    _check_forces(am, traj)
    wanted = set() if keep is None else {int(k) for k in keep}
    base = _base(am, traj)
    start = _start_guess(am, base)
    guess, kept = start, {}
    for k in range(len(traj.times)):
        if progress is not None and k % 200 == 0:
            progress(k, len(traj.times), "checking rows against stack FK")
        fk = stack_forward_kinematics(am, L[k], base=base, guess=on_se3(guess))
        if not fk.success and guess is not start:
            fk = stack_forward_kinematics(am, L[k], base=base, guess=start)
        if not fk.success:
            raise TrajectoryError(f"stack FK failed at t = {traj.times[k]:.3f} s: {fk.message}")
        written = taa_to_se3(traj.ee[k], what=f"the EE at t = {traj.times[k]:.3f} s")
        pose = fk.plates.se3(am.n)
        gap = max(
            float(np.linalg.norm(pose.translation - written.translation)),
            float(np.linalg.norm(pin.log3(written.rotation.T @ pose.rotation))),
        )
        if not gap <= tolerance:
            raise TrajectoryError(
                f"at t = {traj.times[k]:.3f} s the lengths put the EE {gap:.2e} from the pose "
                f"written in the file (> {tolerance:g})"
            )
        guess = fk.plates
        if k in wanted:
            kept[k] = fk.plates
    return kept


def _check_rates(am: AssemblerModel, traj: Trajectory, rtol: float = 1e-6) -> None:
    """Leg speeds and accelerations (finite differences) within the config's limits."""
    leg = am.config.leg
    if len(traj.times) > 1 and np.abs(traj.speeds()).max() > leg.max_speed * (1 + rtol):
        raise TrajectoryError(
            f"its legs move at up to {np.abs(traj.speeds()).max():.4g} m/s, over leg.max_speed {leg.max_speed:g} m/s"
        )
    if len(traj.times) > 2 and np.abs(traj.accelerations()).max() > leg.max_acceleration * (1 + rtol):
        raise TrajectoryError(
            f"its legs accelerate at up to {np.abs(traj.accelerations()).max():.4g} m/s², over "
            f"leg.max_acceleration {leg.max_acceleration:g} m/s²"
        )


def trajectory_states(
    am: AssemblerModel,
    traj: Trajectory,
    frames: int | None = None,
    tolerance: float = 1e-6,
    progress: ProgressCallback | None = None,
) -> tuple[np.ndarray, list[StackState]]:
    """The stack at evenly spaced rows, rebuilt from its leg lengths by stack FK, after
    :func:`check_trajectory` has held every row to the model; each chosen row's max|F| must
    also equal the model's statics (to 1e-6 N + 1e-9 relative).

    Args:
        frames: how many evenly spaced rows (default: all).
        tolerance: largest EE mismatch with the file [m, rad].

    Returns:
        (times [s], states) of the chosen rows.

    Raises:
        TrajectoryError: see :func:`check_trajectory`, or forces that disagree.
    """
    count = len(traj.times) if frames is None else max(2, min(int(frames), len(traj.times)))
    picks = np.unique(np.round(np.linspace(0, len(traj.times) - 1, count)).astype(int))
    kept = check_trajectory(am, traj, tolerance, keep=picks, progress=progress)
    states = [evaluate_state(am, kept[int(k)]) for k in picks]
    for k, st in zip(picks, states, strict=True):
        if not abs(st.max_abs_force - traj.max_abs_force[k]) <= 1e-6 + 1e-9 * st.max_abs_force:
            raise TrajectoryError(
                f"at t = {traj.times[k]:.3f} s the file's max|F| is {traj.max_abs_force[k]:.6g} N, "
                f"this model's statics give {st.max_abs_force:.6g} N (planned with another "
                "config?)"
            )
    return traj.times[picks], states
