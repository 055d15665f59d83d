"""End-effector paths: waypoints joined on SE(3), sampled at a given spacing.

Two interpolations between consecutive waypoints A and B (world frame):

* ``"screw"`` (default): the geodesic of SE(3), ``A · exp6(t · log6(A⁻¹ B))`` — the EE
  turns and translates along one screw motion (its origin moves on a helix when it turns).
* ``"linear"``: the origin on the straight segment from A to B, the orientation by slerp,
  ``R_A · exp3(t · log3(R_Aᵀ R_B))`` — what "move in a straight line" usually means.

Waypoint files: JSON ``{"waypoints": [[x, y, z, rx, ry, rz], ...], "times": [...],
"degrees": false}`` (``times`` optional) or CSV rows ``x,y,z,rx,ry,rz[,t]`` with an optional
header line; rotations are rotation vectors [rad] (TAA, as ``solve --goal``).
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..choices import PATH_KINDS
from ..exceptions import PathError
from ..kinematics import taa_to_se3, to_se3

__all__ = ["PATH_KINDS", "EEPath", "PathError", "interpolate_pose", "read_waypoints"]



def interpolate_pose(a: pin.SE3, b: pin.SE3, t: float, kind: str = "screw") -> pin.SE3:
    """The pose at fraction ``t`` ∈ [0, 1] from ``a`` to ``b`` (see module docstring)."""
    if kind == "screw":
        return a * pin.exp6(t * pin.log6(a.actInv(b)))
    if kind == "linear":
        rotation = a.rotation @ pin.exp3(t * pin.log3(a.rotation.T @ b.rotation))
        return pin.SE3(rotation, (1.0 - t) * a.translation + t * b.translation)
    raise PathError(f"path kind must be one of {', '.join(PATH_KINDS)}, got {kind!r}")


@dataclass(frozen=True)
class EEPath:
    """A piecewise path of the EE through waypoints.

    Attributes:
        waypoints: world poses of the EE (≥ 2).
        kind: interpolation between consecutive waypoints (:data:`PATH_KINDS`).
        times: optional arrival time of each waypoint [s], increasing from 0 (a time
            parametrization then stretches each segment to at least its given duration).
    """

    waypoints: tuple[pin.SE3, ...]
    kind: str = "screw"
    times: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        if self.kind not in PATH_KINDS:
            raise PathError(f"path kind must be one of {', '.join(PATH_KINDS)}, got {self.kind!r}")
        if len(self.waypoints) < 2:
            raise PathError(f"a path needs at least 2 waypoints, got {len(self.waypoints)}")
        if self.times is not None:
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
        out = [0.0]
        for k in range(self.segments):
            a, b = self.waypoints[k], self.waypoints[k + 1]
            # the screw path's origin travels at most the chord plus the arc of the turn
            mid = [interpolate_pose(a, b, t, self.kind).translation for t in np.linspace(0, 1, 9)]
            length = float(np.sum(np.linalg.norm(np.diff(mid, axis=0), axis=1)))
            angle = float(np.linalg.norm(pin.log3(a.rotation.T @ b.rotation)))
            m = max(1, math.ceil(max(length / position_step, angle / rotation_step) - 1e-9))
            out.extend(k + np.arange(1, m + 1) / m)
        return np.array(out)


def read_waypoints(path: str | Path, kind: str = "screw") -> EEPath:
    """An :class:`EEPath` from a JSON or CSV waypoint file (see module docstring).

    Raises:
        PathError: the file cannot be read or does not hold valid waypoints.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise PathError(f"cannot read waypoint file '{path}': {exc}") from None
    degrees = False
    times = None
    if path.suffix.lower() == ".json":
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as exc:
            raise PathError(f"'{path}' is not valid JSON: {exc}") from None
        if not isinstance(doc, dict) or not isinstance(doc.get("waypoints"), list):
            raise PathError(f"'{path}': expected {{\"waypoints\": [[x, y, z, rx, ry, rz], ...]}}")
        rows = doc["waypoints"]
        times = doc.get("times")
        degrees = bool(doc.get("degrees", False))
    else:
        rows = [r for r in csv.reader(text.splitlines()) if r and not r[0].lstrip().startswith("#")]
        if rows and not _is_number(rows[0][0]):
            rows = rows[1:]  # header
        try:
            rows = [[float(x) for x in r] for r in rows]
        except ValueError as exc:
            raise PathError(f"'{path}': every CSV row must be numbers x,y,z,rx,ry,rz[,t]: {exc}") from None
        if rows and all(len(r) == 7 for r in rows):
            times = [r[6] for r in rows]
            rows = [r[:6] for r in rows]
    for i, r in enumerate(rows):
        if not isinstance(r, list) or len(r) != 6:
            raise PathError(f"'{path}': waypoint {i} must have 6 numbers x, y, z, rx, ry, rz")
    poses = tuple(taa_to_se3(r, degrees=degrees, what=f"waypoint {i}") for i, r in enumerate(rows))
    return EEPath(poses, kind, None if times is None else tuple(float(t) for t in times))


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
