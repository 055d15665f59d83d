"""Independent re-checks of what an answer claims.

A state called feasible is held to the design's kinematics recomputed from the node angles
(:func:`checks.kinematic_problems`, which shares nothing with the package's geometry) and
to the force limits with forces from the core statics; a solve called successful must have
a finite goal its EE meets; every row of a trajectory file is held to a fresh stack FK and
statics of its own lengths; a map cell called reachable to a finite max|F| within the
limits. A broken claim is ``[wrong-answer]``; an exit status that disagrees with
``success`` is ``[exit-status]``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin

import assembler_pin as ap

from .harness import fail

#: A trajectory row's EE against FK of its own lengths [m, rad], its max|F| against statics [N].
ROW_EE_TOL = 1e-8
ROW_FORCE_TOL = 1e-6


def strict_json(text: str, what: str) -> object:
    """The one JSON document of an answer's stdout (NaN/Infinity tokens are a defect)."""

    def constant(token: str) -> None:
        fail("wrong-answer", f"{what}: non-strict JSON token {token} in the answer")

    try:
        return json.loads(text, parse_constant=constant)
    except json.JSONDecodeError as exc:
        fail("wrong-answer", f"{what}: stdout is not one JSON document: {exc}: {text[:200]}")
    return None


def exit_agrees(code: int, success: object, what: str) -> None:
    """0 = answered and successful, 1 = answered, not possible."""
    if success is True and code != 0:
        fail("exit-status", f"{what}: success true but exit {code}")
    if success is False and code != 1:
        fail("exit-status", f"{what}: success false but exit {code} (the rule: 1 = answered, not possible)")


def _plates(doc_plates, what: str):
    try:
        matrices = np.array(doc_plates, dtype=float)
    except (TypeError, ValueError):
        fail("wrong-answer", f"{what}: plates of a feasible state are not numbers")
    if matrices.ndim != 3 or matrices.shape[1:] != (4, 4) or not np.all(np.isfinite(matrices)):
        fail("wrong-answer", f"{what}: plates of a feasible state are not finite 4x4 matrices")
    return ap.PlateArrays(matrices[:, :3, :3], matrices[:, :3, 3])


def check_state_doc(am, doc: dict, what: str, goal: pin.SE3 | None = None, ee_tol: float = 1e-6) -> None:
    """A state's JSON (``StackState.to_dict``): when it says feasible, every limit holds."""
    from checks import kinematic_problems

    if not isinstance(doc, dict) or doc.get("feasible") is not True:
        return
    pa = _plates(doc.get("plates"), what)
    if len(pa.R) != am.n + 1:
        fail("wrong-answer", f"{what}: a feasible state with {len(pa.R)} plates for {am.n} platforms")
    R = pa.R
    if np.abs(np.matmul(R.transpose(0, 2, 1), R) - np.eye(3)).max() > 1e-6 or np.any(np.linalg.det(R) <= 0):
        fail("wrong-answer", f"{what}: a feasible state whose plates are not rotations")
    problems = kinematic_problems(am.config, pa, goal, tol=ee_tol)
    if problems:
        fail("wrong-answer", f"{what}: called feasible, but {'; '.join(problems)}")
    forces = ap.solve_statics(am, pa).forces
    leg = am.config.leg
    if not np.all(np.isfinite(forces)):
        fail("wrong-answer", f"{what}: called feasible with non-finite statics")
    if forces.max() > leg.max_tension * (1 + 1e-9) or forces.min() < -leg.max_compression * (1 + 1e-9):
        fail("wrong-answer", f"{what}: called feasible with max|F| {np.abs(forces).max():.4g} N over the limits")
    told = np.array(doc.get("forces"), dtype=float)
    if told.shape != forces.shape or not np.allclose(told, forces, atol=1e-6, rtol=0):
        fail("wrong-answer", f"{what}: its forces differ from the statics of its plates")


def goal_of(doc_goal) -> pin.SE3 | None:
    """The goal of a solve answer (TAA or 4x4), None when it is not finite."""
    try:
        arr = np.array(doc_goal, dtype=float)
    except (TypeError, ValueError):
        return None
    if not np.all(np.isfinite(arr)):
        return None
    if arr.shape == (6,):
        return pin.SE3(pin.exp3(arr[3:]), arr[:3])
    if arr.shape == (4, 4):
        return pin.SE3(arr)
    return None


def check_solve_doc(am, doc: dict, code: int, what: str, ee_tol: float = 1e-6) -> None:
    """``solve --json``: success needs a finite goal and an optimized (or initial) state
    that is feasible at it; exit status agrees with success."""
    if not isinstance(doc, dict) or "success" not in doc:
        fail("wrong-answer", f"{what}: the solve answer has no success field")
    exit_agrees(code, doc["success"], what)
    goal = goal_of(doc.get("goal"))
    for key in ("initial", "optimized"):
        if isinstance(doc.get(key), dict):
            check_state_doc(am, doc[key], f"{what} ({key})", goal, ee_tol)
    if doc["success"] is not True:
        return
    if goal is None:
        fail("wrong-answer", f"{what}: success for a goal that is not finite: {doc.get('goal')}")
    final = doc.get("optimized") if isinstance(doc.get("optimized"), dict) else doc.get("initial")
    if not isinstance(final, dict) or final.get("feasible") is not True:
        fail("wrong-answer", f"{what}: success without a feasible state")
    capacity = doc.get("capacity")
    if isinstance(capacity, dict) and capacity.get("success") is True:
        kg = capacity.get("capacity_kg")
        if not (isinstance(kg, (int, float)) and math.isfinite(kg) and kg >= 0):
            fail("wrong-answer", f"{what}: a successful capacity of {kg!r} kg")


def check_trajectory_file(am, path: Path, what: str, claimed_valid: bool) -> None:
    """Every row of a written trajectory file against a fresh FK and statics of its own
    lengths; when the answer (or the row) claims validity, every limit holds there."""
    from checks import kinematic_problems

    traj = ap.read_trajectory(path)
    if not np.all(np.isfinite(traj.times)) or np.any(np.diff(traj.times) <= 0):
        fail("wrong-answer", f"{what}: written times are not finite and increasing")
    guess = None
    leg = am.config.leg
    for k in range(len(traj.times)):
        fk = ap.stack_forward_kinematics(am, traj.lengths[k], guess=guess)
        if not fk.success:
            fail("wrong-answer", f"{what}: row {k}: the lengths have no FK solution")
        pa = fk.plates
        guess = pa
        ee = pa.se3(am.n)
        written = traj.ee[k]
        dp = float(np.linalg.norm(ee.translation - written[:3]))
        dr = float(np.linalg.norm(pin.log3(ee.rotation.T @ pin.exp3(written[3:]))))
        if dp > ROW_EE_TOL or dr > ROW_EE_TOL:
            fail(
                "wrong-answer",
                f"{what}: row {k} of {len(traj.times)}: written EE {dp:.3g} m / {dr:.3g} rad "
                "from FK of the row's own lengths",
            )
        forces = ap.solve_statics(am, pa).forces
        if abs(float(np.abs(forces).max()) - float(traj.max_abs_force[k])) > ROW_FORCE_TOL:
            fail(
                "wrong-answer",
                f"{what}: row {k}: written max|F| {traj.max_abs_force[k]:.9g} N, statics of its "
                f"lengths {np.abs(forces).max():.9g} N",
            )
        if claimed_valid or bool(traj.feasible[k]):
            problems = kinematic_problems(am.config, pa, tol=1e-9)
            over = forces.max() > leg.max_tension or forces.min() < -leg.max_compression
            if problems or over:
                fail("wrong-answer", f"{what}: row {k} written as valid but {'; '.join(problems) or 'forces over'}")
    if claimed_valid and len(traj.times) > 1:
        v = np.abs(traj.speeds()).max()
        if v > leg.max_speed * (1 + 1e-6):
            fail("wrong-answer", f"{what}: leg speed {v:.4g} m/s over the limit {leg.max_speed:g} in a valid plan")


def check_plan_doc(am, doc: dict, code: int, what: str, out: Path | None) -> None:
    """``plan --json`` (and its ``--out`` file)."""
    if not isinstance(doc, dict) or "success" not in doc:
        fail("wrong-answer", f"{what}: the plan answer has no success field")
    exit_agrees(code, doc["success"], what)
    if out is not None and out.exists():
        check_trajectory_file(am, out, what, claimed_valid=True)
    elif out is not None and doc["success"] is True:
        fail("wrong-answer", f"{what}: success but no trajectory file written")


def check_map_dir(out: Path, what: str, limit: float) -> dict:
    """Every cell of a map directory: reachable cells have a finite max|F| within the force
    limit and a finite capacity. Returns {cell id: reachable}."""
    import pyarrow.parquet as pq

    cells: dict = {}
    for part in sorted(out.glob("*.parquet")):
        table = pq.read_table(part).to_pylist()
        for row in table:
            if row.get("reachable"):
                f = row.get("max_abs_force")
                if f is None or not math.isfinite(f) or f > limit * (1 + 1e-9):
                    fail("wrong-answer", f"{what}: cell {row.get('cell')} reachable with max|F| {f!r}")
            cells[(row.get("config"), row.get("cell"))] = bool(row.get("reachable"))
    return cells


def check_fk_result(am, fk, what: str, lengths: float | None = None) -> None:
    """A successful stack FK: finite plates with proper rotations, each platform's legs
    (recomputed from the design anchors) of the lengths it was given."""
    from checks import sp_legs

    pa = fk.plates
    R = np.asarray(pa.R, dtype=float)
    if not (np.all(np.isfinite(R)) and np.all(np.isfinite(pa.p))):
        fail("wrong-answer", f"{what}: FK success with non-finite plates")
    if np.abs(np.matmul(R.transpose(0, 2, 1), R) - np.eye(3)).max() > 1e-9 or np.any(np.linalg.det(R) <= 0):
        fail("wrong-answer", f"{what}: FK success with plates that are not rotations")
    if lengths is None:
        return
    for j in range(am.n):
        L = sp_legs(am.config, j, R[j], pa.p[j], R[j + 1], pa.p[j + 1])[0]
        if np.abs(L - lengths).max() > 1e-9:
            fail("wrong-answer", f"{what}: FK success, but platform {j}'s legs are not the given lengths")
