"""Footholds of a walk: checked, generated on a level floor, or read from a strict JSON file.

A footholds file::

    {"footholds": [[x, y, z, rx, ry, rz], ...],   # or 4x4 matrices; metres, radians
     "degrees": false,                              # optional: the rotation vectors in degrees
     "floor_z": 0.0}                                # optional: a level floor they all lie on

Each foothold is a world frame on the surface, its z the outward normal, its x along the step
onto it (:mod:`assembler_pin.walk.plan`). Anything else (unknown keys, NaN, booleans, a
matrix that is not a proper pose, too many footholds, overlapping or off-floor ones) is
refused in one line (:class:`~assembler_pin.exceptions.WalkError`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import cast

import numpy as np
import pinocchio as pin

from ..common.files import read_text_bounded, strict_json
from ..config.bounds import check_bound
from ..config.numbers import finite_float
from ..exceptions import AssemblerError, WalkError
from ..kinematics import taa_to_se3, to_se3
from ..model.assembler import AssemblerModel

__all__ = [
    "TURN_OVER",
    "FootholdFile",
    "checked_footholds",
    "floor_footholds",
    "parse_footholds",
    "plate_target",
    "read_footholds",
]


@dataclass(frozen=True)
class FootholdFile:
    """A footholds file read: the world frames, and the floor's height [m] when declared."""

    footholds: tuple[pin.SE3, ...]
    floor_z: float | None


def checked_footholds(am: AssemblerModel, footholds: object, floor_z: float | None = None) -> tuple[pin.SE3, ...]:
    """The footholds as world frames: 2..100 proper poses, consecutive ones (one foot's and the
    other's) at least a plate's diameter (2 ``node_radius``) apart, on the floor when one is given.

    Raises:
        WalkError: a malformed list, a pose that is not one, overlapping feet, off the floor.
    """
    if isinstance(footholds, (str, bytes, dict)) or not hasattr(footholds, "__len__"):
        raise WalkError(f"footholds must be a list of world poses (pin.SE3 or 4x4), got {type(footholds).__name__}")
    items = cast(Sequence[object], footholds)
    check_bound("walk.footholds", len(items), "the number of footholds", error=WalkError)
    out = []
    for k, f in enumerate(items):
        try:
            out.append(to_se3(f, f"foothold {k}"))
        except AssemblerError as exc:  # a PoseError: one line naming the foothold
            raise WalkError(f"foothold {k} is not a world pose (4x4, proper rotation): {exc}") from None
    span = 2.0 * am.config.plate.node_radius
    for k in range(len(out) - 1):
        d = float(np.linalg.norm(out[k + 1].translation - out[k].translation))
        if d < span:
            raise WalkError(
                f"footholds {k} and {k + 1} overlap: their centres are {d:.4g} m apart, the two feet need "
                f"at least {span:.4g} m (2 x plate.node_radius)"
            )
    if floor_z is not None:
        for k, f in enumerate(out):
            if abs(f.translation[2] - floor_z) > 1e-6 or f.rotation[2, 2] < 1.0 - 1e-9:
                raise WalkError(
                    f"foothold {k} is not on the floor z = {floor_z:g} m (its origin at z = {f.translation[2]:.6g} m, "
                    "its z axis must point straight up)"
                )
    return tuple(out)


def floor_footholds(step: float, count: int, floor_z: float = 0.0) -> tuple[pin.SE3, ...]:
    """``count`` footholds ``step`` [m] apart along world +x on the floor z = ``floor_z``, the
    first at the origin, every frame level (identity rotation).

    Raises:
        WalkError: step or count outside their rows of the limits table.
    """
    check_bound("walk.floor_step", step, "--floor STEP", error=WalkError)
    check_bound("walk.footholds", count, "--floor COUNT", error=WalkError)
    return tuple(pin.SE3(np.eye(3), np.array([k * float(step), 0.0, float(floor_z)])) for k in range(int(count)))


def _is_number(x: object) -> bool:
    """A JSON number a float holds finitely (:func:`~assembler_pin.config.numbers.finite_float`)."""
    return isinstance(x, (int, float)) and finite_float(x) is not None


def _foothold(k: int, row: object, degrees: bool) -> pin.SE3:
    """One entry: six numbers (translation, rotation vector) or a 4x4 matrix."""
    if isinstance(row, list) and len(row) == 6 and all(_is_number(x) for x in row):
        try:
            return taa_to_se3(row, degrees=degrees, what=f"foothold {k}")
        except AssemblerError as exc:
            raise WalkError(str(exc)) from None
    if isinstance(row, list) and len(row) == 4 and all(isinstance(r, list) and len(r) == 4 for r in row):
        if all(_is_number(x) for r in row for x in r):
            try:
                return to_se3(np.array(row, dtype=float), f"foothold {k}")
            except AssemblerError as exc:
                raise WalkError(str(exc)) from None
    raise WalkError(f"foothold {k} must be six finite numbers [x, y, z, rx, ry, rz] or a 4x4 matrix of them")


def parse_footholds(text: str) -> FootholdFile:
    """A :class:`FootholdFile` from the JSON text of a footholds file (module doc).

    Raises:
        WalkError: anything but the format, in one line.
    """
    doc = strict_json(text, WalkError)
    if not isinstance(doc, dict) or "footholds" not in doc:
        raise WalkError('expected a JSON object {"footholds": [[x, y, z, rx, ry, rz], ...]}')
    unknown = sorted(set(doc) - {"footholds", "degrees", "floor_z"})
    if unknown:
        raise WalkError(f"unknown keys {json.dumps(unknown[:5])[:80]} (allowed: footholds, degrees, floor_z)")
    rows, degrees, floor_z = doc["footholds"], doc.get("degrees", False), doc.get("floor_z")
    if type(degrees) is not bool:
        raise WalkError(f'"degrees" must be true or false, got {json.dumps(degrees)[:40]}')
    if floor_z is not None and not (_is_number(floor_z) and abs(floor_z) <= 1e3):
        raise WalkError(f'"floor_z" must be a number in [-1000, 1000] m, got {json.dumps(floor_z)[:40]}')
    if not isinstance(rows, list):
        raise WalkError('"footholds" must be a list of footholds')
    check_bound("walk.footholds", len(rows), "the number of footholds", error=WalkError)
    feet = tuple(_foothold(k, row, degrees) for k, row in enumerate(rows))
    return FootholdFile(feet, None if floor_z is None else float(floor_z))


def read_footholds(path: str | Path) -> FootholdFile:
    """Read a footholds file (module doc), at most the ``walk.file_bytes`` row of the limits table (1 MiB).

    Raises:
        WalkError: unreadable, empty, too large, not UTF-8, or not the format (one line).
    """
    return parse_footholds(read_text_bounded(path, "walk.file_bytes", "footholds file", WalkError))


#: Turns a foothold frame into the pose of the EE plate standing on it (its +z into the
#: surface): a half turn about the foothold's y, the stack arriving along its x.
TURN_OVER = pin.SE3(pin.exp3(np.array([0.0, math.pi, 0.0])), np.zeros(3))


def plate_target(foothold: pin.SE3, foot: str) -> pin.SE3:
    """The world pose of a foot's plate standing on ``foothold``: the base plate is the
    foothold frame, the EE plate the frame turned over about its y (``foothold · Ry(π)``)."""
    return foothold if foot == "base" else foothold * TURN_OVER
