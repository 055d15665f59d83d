"""A walk's trajectory file (``hexapod walk --out FILE``): one JSON object, written atomically
(:func:`write_walk`) and read back strictly (:func:`read_walk`); docs/formats.md.

::

    {"format": "assembler-pin hexapod walk", "version": 1,
     "stacks": k, "platforms": n, "gait": "tripod", "feet": "resting",
     "success": true, "reason": null,
     "samples": [{"t": s, "step": 1, "phase": "unload", "body_pose": [x, y, z, rx, ry, rz],
                  "feet": k 4x4 poses, "stance": k booleans, "lengths": k x n x 6 [m],
                  "forces": k x n x 6 [N] or null, "stability_margin_m": m or null,
                  "max_abs_force": N or null, "violations": [strings]}, ...]}

Anything else is refused in one line (:class:`~assembler_pin.exceptions.HexapodError`): a
missing or unknown key, another format or version, a boolean for a number, NaN, an integer no
float holds exactly, a shape that is not k and n's, a foot pose that is not a rigid transform,
time running back, a step or phase out of range, more samples than a walk can have, a file
over the ``trajectory.bytes`` row of the limits table.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..common.files import read_text_bounded, strict_json, write_atomic
from ..exceptions import HexapodError
from .gait import GAITS, MAX_CYCLES, MAX_SAMPLES, HexapodWalk
from .machine import MAX_STACKS
from .stand import FEET

__all__ = ["FORMAT", "MAX_FILE_SAMPLES", "PHASES", "VERSION", "WalkFile", "read_walk", "walk_to_dict", "write_walk"]

FORMAT, VERSION = "assembler-pin hexapod walk", 1
#: A sample's phases.
PHASES = ("unload", "swing", "load", "body")
#: Most samples a file may hold: the longest walk of the most stacks, one at a time.
MAX_FILE_SAMPLES = 1 + MAX_CYCLES * (3 * MAX_STACKS + 1) * MAX_SAMPLES
#: How far a foot pose's rotation may be from orthonormal.
_ROTATION_TOL = 1e-9
_TOP = ("format", "version", "stacks", "platforms", "gait", "feet", "success", "reason", "samples")
_SAMPLE = (
    "t",
    "step",
    "phase",
    "body_pose",
    "feet",
    "stance",
    "lengths",
    "forces",
    "stability_margin_m",
    "max_abs_force",
    "violations",
)


@dataclass(frozen=True)
class WalkFile:
    """A walk file read: its header and, over m samples, ``t`` (m,) [s], ``step`` (m,),
    ``phase`` (m,), ``body_pose`` (m, 6), ``feet`` (m, k, 4, 4), ``stance`` (m, k),
    ``lengths`` and ``forces`` (m, k, n, 6) (NaN where null), ``stability_margin_m`` and
    ``max_abs_force`` (m,) (NaN where null), ``violations`` per sample."""

    stacks: int
    platforms: int
    gait: str
    feet: str
    success: bool
    reason: str | None
    t: np.ndarray
    step: np.ndarray
    phase: tuple[str, ...]
    body_pose: np.ndarray
    feet_poses: np.ndarray
    stance: np.ndarray
    lengths: np.ndarray
    forces: np.ndarray
    stability_margin_m: np.ndarray
    max_abs_force: np.ndarray
    violations: tuple[tuple[str, ...], ...]


def _number(x: float) -> float | None:
    return None if math.isnan(x) else float(x)


def walk_to_dict(result: HexapodWalk) -> dict:
    """The file's object (module doc) of ``result``."""
    first = result.samples[0]
    samples = [
        {
            "t": s.t,
            "step": s.step,
            "phase": s.phase,
            "body_pose": s.body_pose.tolist(),
            "feet": s.feet.tolist(),
            "stance": s.stance.tolist(),
            "lengths": s.lengths.tolist(),
            "forces": None if np.isnan(s.forces).any() else s.forces.tolist(),
            "stability_margin_m": _number(s.stability_margin_m),
            "max_abs_force": _number(s.max_abs_force),
            "violations": list(s.violations),
        }
        for s in result.samples
    ]
    k, n = first.lengths.shape[:2]
    head = {"format": FORMAT, "version": VERSION, "stacks": k, "platforms": n, "gait": result.gait}
    return {**head, "feet": result.feet, "success": result.success, "reason": result.reason, "samples": samples}


def write_walk(path: str | Path, result: HexapodWalk) -> Path:
    """Write ``result`` to ``path`` atomically (module doc); returns the path."""
    return write_atomic(path, json.dumps(walk_to_dict(result), allow_nan=False))


def _fail(where: str, what: str) -> HexapodError:
    return HexapodError(f"walk file: {where}: {what}"[:200])


def _keys(obj: object, keys: tuple[str, ...], where: str) -> dict:
    if not isinstance(obj, dict):
        raise _fail(where, "must be an object")
    if set(obj) != set(keys):
        extra, missing = sorted(set(obj) - set(keys)), sorted(set(keys) - set(obj))
        raise _fail(where, f"unknown keys {extra}" if extra else f"missing keys {missing}")
    return obj


def _exact(v: int) -> bool:
    try:
        return float(v) == v
    except OverflowError:
        return False


def _array(value: object, shape: tuple[int, ...], where: str, nullable: bool = False) -> np.ndarray:
    if value is None and nullable:
        return np.full(shape, np.nan)

    def numbers(v: object, depth: int) -> bool:
        if depth == len(shape):
            # an integer too long for a float would be read as another number
            return isinstance(v, float) or (isinstance(v, int) and not isinstance(v, bool) and _exact(v))
        return isinstance(v, list) and len(v) == shape[depth] and all(numbers(x, depth + 1) for x in v)

    if not numbers(value, 0):
        raise _fail(where, f"must be numbers of shape {list(shape)}" + (" or null" if nullable else ""))
    out = np.array(value, dtype=float)
    if not np.isfinite(out).all():
        raise _fail(where, "must be finite")
    return out


def _choice(value: object, allowed: tuple[str, ...], where: str) -> str:
    if not isinstance(value, str) or value not in allowed:
        raise _fail(where, f"must be one of {', '.join(allowed)}")
    return value


def _count(value: object, low: int, high: int, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise _fail(where, f"must be an integer in [{low}, {high}]")
    return value


def _nullable_number(value: object, where: str) -> float:
    if value is None:
        return math.nan
    return float(_array(value, (), where))


def _sample(obj: object, k: int, n: int, where: str) -> dict:
    s = _keys(obj, _SAMPLE, where)
    feet = _array(s["feet"], (k, 4, 4), f"{where}.feet")
    R = feet[:, :3, :3]
    rigid = np.abs(np.einsum("kab,kac->kbc", R, R) - np.eye(3)).max() <= _ROTATION_TOL
    if not (rigid and (np.linalg.det(R) > 0).all() and np.array_equal(feet[:, 3], np.tile([0, 0, 0, 1.0], (k, 1)))):
        raise _fail(f"{where}.feet", "must be rigid transforms (a rotation, a translation, last row 0 0 0 1)")
    stance = s["stance"]
    if not (isinstance(stance, list) and len(stance) == k and all(isinstance(b, bool) for b in stance)):
        raise _fail(f"{where}.stance", f"must be {k} booleans")
    violations = s["violations"]
    if not (isinstance(violations, list) and all(isinstance(v, str) for v in violations)):
        raise _fail(f"{where}.violations", "must be a list of strings")
    return {
        "t": float(_array(s["t"], (), f"{where}.t")),
        "step": _count(s["step"], 1, MAX_CYCLES, f"{where}.step"),
        "phase": _choice(s["phase"], PHASES, f"{where}.phase"),
        "body_pose": _array(s["body_pose"], (6,), f"{where}.body_pose"),
        "feet": feet,
        "stance": np.array(stance, bool),
        "lengths": _array(s["lengths"], (k, n, 6), f"{where}.lengths"),
        "forces": _array(s["forces"], (k, n, 6), f"{where}.forces", nullable=True),
        "stability_margin_m": _nullable_number(s["stability_margin_m"], f"{where}.stability_margin_m"),
        "max_abs_force": _nullable_number(s["max_abs_force"], f"{where}.max_abs_force"),
        "violations": tuple(violations),
    }


def read_walk(path: str | Path) -> WalkFile:
    """Read a walk file (module doc).

    Raises:
        HexapodError: unreadable, too large, or not the format (one line).
    """
    top = _keys(
        strict_json(read_text_bounded(path, "trajectory.bytes", "walk file", HexapodError), HexapodError), _TOP, "top"
    )
    if top["format"] != FORMAT or isinstance(top["version"], bool) or top["version"] != VERSION:
        raise _fail("top", f"format must be {FORMAT!r} and version {VERSION}")
    k = _count(top["stacks"], 1, MAX_STACKS, "stacks")
    n = _count(top["platforms"], 1, 16, "platforms")
    gait, feet = _choice(top["gait"], GAITS, "gait"), _choice(top["feet"], FEET, "feet")
    if not isinstance(top["success"], bool) or not (top["reason"] is None or isinstance(top["reason"], str)):
        raise _fail("top", "success must be a boolean and reason a string or null")
    if top["success"] == (top["reason"] is not None):
        raise _fail("top", "a reason is given exactly when the walk did not succeed")
    raw = top["samples"]
    if not isinstance(raw, list) or not 1 <= len(raw) <= MAX_FILE_SAMPLES:
        raise _fail("samples", f"must be a list of 1..{MAX_FILE_SAMPLES} samples")
    rows = [_sample(s, k, n, f"samples[{j}]") for j, s in enumerate(raw)]
    t = np.array([r["t"] for r in rows])
    if (np.diff(t) < 0).any() or t[0] < 0:
        raise _fail("samples", "time must start at or after 0 and never run back")
    stack = {key: np.array([r[key] for r in rows]) for key in _SAMPLE if key not in ("phase", "violations")}
    return WalkFile(
        k,
        n,
        gait,
        feet,
        top["success"],
        top["reason"],
        t,
        stack["step"],
        tuple(r["phase"] for r in rows),
        stack["body_pose"],
        stack["feet"],
        stack["stance"],
        stack["lengths"],
        stack["forces"],
        stack["stability_margin_m"],
        stack["max_abs_force"],
        tuple(r["violations"] for r in rows),
    )
