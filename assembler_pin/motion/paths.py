"""End-effector paths: waypoints joined on SE(3), sampled at a given spacing.

Two interpolations between consecutive waypoints A and B (world frame):

* ``"screw"`` (default): the geodesic of SE(3), ``A · exp6(t · log6(A⁻¹ B))`` — the EE
  turns and translates along one screw motion (its origin moves on a helix when it turns).
* ``"linear"``: the origin on the straight segment from A to B, the orientation by slerp,
  ``R_A · exp3(t · log3(R_Aᵀ R_B))`` — what "move in a straight line" usually means.

Waypoint files: JSON ``{"waypoints": [[x, y, z, rx, ry, rz], ...], "times": [...],
"degrees": false}`` (``times`` and ``degrees`` optional) or CSV rows ``x,y,z,rx,ry,rz[,t]``
with an optional header line; rotations are rotation vectors [rad] (TAA, as ``solve --goal``;
degrees with ``"degrees": true``). Times, when given, are honoured: the EE arrives at each
waypoint at its time, at rest (:mod:`.timing`), and times too short for the legs' limits are
refused.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..common.files import read_text_bounded, strict_json
from ..config.bounds import BOUNDS, check_bound
from ..config.choices import PATH_KINDS
from ..config.numbers import finite_float
from ..exceptions import AssemblerError, PathError, short_repr
from ..kinematics import taa_to_se3, to_se3

__all__ = ["EEPath", "interpolate_pose", "read_waypoints"]


def interpolate_pose(a: pin.SE3, b: pin.SE3, t: float, kind: str = "screw") -> pin.SE3:
    """The pose at fraction ``t`` ∈ [0, 1] from ``a`` to ``b`` (see module docstring)."""
    if kind == "screw":
        return a * pin.exp6(t * pin.log6(a.actInv(b)))
    if kind == "linear":
        rotation = a.rotation @ pin.exp3(t * pin.log3(a.rotation.T @ b.rotation))
        return pin.SE3(rotation, (1.0 - t) * a.translation + t * b.translation)
    raise PathError(f"path kind must be one of {', '.join(PATH_KINDS)}, got {short_repr(kind, 40)}")


@dataclass(frozen=True)
class EEPath:
    """A piecewise path of the EE through waypoints.

    Attributes:
        waypoints: world poses of the EE (≥ 2).
        kind: interpolation between consecutive waypoints (:data:`PATH_KINDS`).
        times: optional arrival time of each waypoint [s], increasing from 0: the time law
            then arrives at each waypoint at its time, at rest (:mod:`.timing`).
    """

    waypoints: tuple[pin.SE3, ...]
    kind: str = "screw"
    times: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        if self.kind not in PATH_KINDS:
            raise PathError(f"path kind must be one of {', '.join(PATH_KINDS)}, got {short_repr(self.kind, 40)}")
        if len(self.waypoints) < 2:
            raise PathError(f"a path needs at least 2 waypoints, got {len(self.waypoints)}")
        for k, w in enumerate(self.waypoints):
            if not isinstance(w, pin.SE3):
                raise PathError(f"waypoint {k} must be a pin.SE3, got {type(w).__name__} (EEPath.between takes 4x4)")
            to_se3(w, f"waypoint {k}")  # finite, a proper rotation
        if self.times is not None:
            if any(isinstance(x, bool) or not isinstance(x, (int, float, np.number)) for x in self.times):
                raise PathError("times must be numbers [s] (no booleans or strings)")
            t = np.asarray(self.times, dtype=float)
            if t.shape != (len(self.waypoints),) or not np.all(np.isfinite(t)) or t[0] != 0 or np.any(np.diff(t) <= 0):
                raise PathError("times must give one finite time per waypoint, starting at 0 and increasing")

    @classmethod
    def between(cls, start: pin.SE3 | np.ndarray, goal: pin.SE3 | np.ndarray, kind: str = "screw") -> EEPath:
        """The path from ``start`` to ``goal`` (poses or 4×4)."""
        return cls((to_se3(start, "start"), to_se3(goal, "goal")), kind)

    @property
    def segments(self) -> int:
        return len(self.waypoints) - 1

    def at(self, u: float) -> pin.SE3:
        """The pose at path parameter ``u`` ∈ [0, segments] (segment ``floor(u)``)."""
        u = float(np.clip(u, 0.0, self.segments))
        k = min(math.floor(u), self.segments - 1)
        return interpolate_pose(self.waypoints[k], self.waypoints[k + 1], u - k, self.kind)

    def parameters(self, position_step: float, rotation_step: float) -> np.ndarray:
        """Path parameters of samples no farther apart than ``position_step`` [m] and
        ``rotation_step`` [rad] (each segment split evenly), from 0 to ``segments``."""
        counts = []
        for k in range(self.segments):
            a, b = self.waypoints[k], self.waypoints[k + 1]
            # the screw path's origin travels at most the chord plus the arc of the turn
            mid = [interpolate_pose(a, b, t, self.kind).translation for t in np.linspace(0, 1, 9)]
            length = float(np.sum(np.linalg.norm(np.diff(mid, axis=0), axis=1)))
            angle = float(np.linalg.norm(pin.log3(a.rotation.T @ b.rotation)))
            counts.append(max(1.0, math.ceil(max(length / position_step, angle / rotation_step) - 1e-9)))
        limit = BOUNDS["plan.path_samples"].high
        if not sum(counts) <= limit:  # checked before allocating
            raise PathError(
                f"the path needs {sum(counts):.4g} samples at {position_step:g} m / {rotation_step:g} rad "
                f"steps, over the {limit:,.0f} one plan may hold (plan.path_samples): shorten the path"
            )
        out = [np.zeros(1)] + [k + np.arange(1, int(m) + 1) / m for k, m in enumerate(counts)]
        return np.concatenate(out)


def read_waypoints(path: str | Path, kind: str = "screw") -> EEPath:
    """An :class:`EEPath` from a JSON or CSV waypoint file (see module docstring), read
    strictly: JSON keys only ``waypoints``, ``times`` and ``degrees`` (a real true/false),
    no duplicate keys, every value a number (no strings, booleans, NaN or infinity); CSV
    rows all of 6 numbers or all of 7 (the 7th the time), an optional header
    ``x,y,z,rx,ry,rz[,t]`` and ``#`` comment lines. Times, when given, are honoured by the
    time law (one per waypoint, from 0, increasing; see :mod:`.timing`).

    Raises:
        PathError: one line naming the file and what is wrong.
    """
    text = read_text_bounded(path, "waypoints.bytes", "waypoint file", PathError)
    path = Path(path)
    try:
        rows, times, degrees = _json_waypoints(text) if path.suffix.lower() == ".json" else _csv_waypoints(text)
        check_bound("waypoints.count", len(rows), "the number of waypoints", PathError)
        poses = tuple(taa_to_se3(r, degrees=degrees, what=f"waypoint {i}") for i, r in enumerate(rows))
        if times is not None:
            check_bound("plan.duration", times[-1], "the last waypoint time", PathError)
        return EEPath(poses, kind, times)
    except AssemblerError as exc:
        raise PathError(f"waypoint file '{path}': {exc}") from None


def _numbers(row: object, width: int) -> bool:
    """``row`` is a list of ``width`` JSON numbers, no integer too large for a float (an
    infinite float is refused with its name where the pose is read)."""
    if type(row) is not list or len(row) != width:
        return False
    return all(type(x) is float or (type(x) is int and finite_float(x) is not None) for x in row)


def _json_waypoints(text: str) -> tuple[list, tuple[float, ...] | None, bool]:
    """(rows, times or None, degrees) of a JSON waypoint file."""
    doc = strict_json(text, PathError)
    if not isinstance(doc, dict) or "waypoints" not in doc:
        raise PathError('expected a JSON object {"waypoints": [[x, y, z, rx, ry, rz], ...]}')
    unknown = sorted(set(doc) - {"waypoints", "times", "degrees"})
    if unknown:
        raise PathError(f"unknown keys {unknown[:5]} (allowed: waypoints, times, degrees)"[:160])
    rows, times, degrees = doc["waypoints"], doc.get("times"), doc.get("degrees", False)
    if type(degrees) is not bool:
        raise PathError(f'"degrees" must be true or false, got {json.dumps(degrees)[:40]}')
    if not isinstance(rows, list):
        raise PathError('"waypoints" must be a list of [x, y, z, rx, ry, rz] rows')
    check_bound("waypoints.count", len(rows), "the number of waypoints", PathError)
    for i, r in enumerate(rows):
        if not _numbers(r, 6):
            raise PathError(f"waypoint {i} must be a list of 6 numbers x, y, z, rx, ry, rz")
    if times is not None and not _numbers(times, len(rows)):
        raise PathError(f'"times" must be a list of {len(rows)} numbers [s], one per waypoint')
    return rows, None if times is None else tuple(float(t) for t in times), degrees


_HEADERS = ("x,y,z,rx,ry,rz", "x,y,z,rx,ry,rz,t")


def _csv_waypoints(text: str) -> tuple[list, tuple[float, ...] | None, bool]:
    """(rows, times or None, degrees False) of a CSV waypoint file."""
    lines = [ln.strip() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln and not ln.startswith("#")]
    if lines and lines[0].replace(" ", "").lower() in _HEADERS:
        lines = lines[1:]
    elif lines and not _is_number(lines[0].split(",")[0]):
        raise PathError(f"the header must be one of {' or '.join(_HEADERS)}")
    if len(lines) > BOUNDS["waypoints.count"].high:
        check_bound("waypoints.count", len(lines), "the number of waypoints", PathError)
    rows = [ln.split(",") for ln in lines]
    widths = {len(r) for r in rows}
    if not widths <= {6, 7} or len(widths) > 1:
        raise PathError("every CSV row must hold 6 numbers x,y,z,rx,ry,rz, or every row 7 (then t [s])")
    try:
        values = [[float(x) for x in r] for r in rows]
    except ValueError as exc:
        raise PathError(f"every CSV value must be a number: {str(exc)[:80]}") from None
    if widths == {7}:
        return [r[:6] for r in values], tuple(r[6] for r in values), False
    return values, None, False


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
