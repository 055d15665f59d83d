"""The moving foot's path in a walk: arcs through the upright stack, lift-off and landing.

The moving plate's waypoints are world frames (held plate ``base``): off its foothold, back
along an arc to the upright stack, along an arc to the pre-contact pose ``clearance`` above
the next foothold (along its normal) and onto it (:func:`foot_waypoints`); with a scene the
path is planned in pieces, each with the plates that stand on the floor there
(:func:`path_pieces`). Lengths [m], angles [rad].
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin

from ..collision.scene import Scene

__all__ = ["ARC_STEPS", "foot_waypoints", "path_pieces"]


#: Angles [rad] of the arc waypoints between the upright stack (0) and a foot on the surface (π).
ARC_STEPS = np.radians(np.arange(15.0, 180.0, 15.0))


def _arc(base: pin.SE3, toward: np.ndarray, length: np.ndarray, theta: np.ndarray, lift: np.ndarray) -> list[pin.SE3]:
    """Poses of the moving plate on the stack bent into an arc of ``length`` [m] and total turn
    ``theta`` [rad] about ``z × toward`` (the held plate's frame), raised by ``lift`` [m]."""
    axis = np.cross([0.0, 0.0, 1.0], toward)
    out = []
    for ell, th, up in zip(length, theta, lift, strict=True):
        local = ell * ((1.0 - math.cos(th)) / th * toward + math.sin(th) / th * np.array([0.0, 0.0, 1.0]))
        local[2] += up
        out.append(base * pin.SE3(pin.exp3(th * axis), local))
    return out


def _side(base: pin.SE3, foot: pin.SE3) -> tuple[np.ndarray, float]:
    """The unit direction (held plate's frame, horizontal) and distance [m] to a foot's plate."""
    rel = base.actInv(foot).translation
    d = float(np.hypot(rel[0], rel[1]))
    return (np.array([rel[0], rel[1], 0.0]) / d if d > 0 else np.array([1.0, 0.0, 0.0])), d


def foot_waypoints(
    base: pin.SE3, apex: pin.SE3, ee: pin.SE3, target: pin.SE3, clearance: float, lift: bool
) -> tuple[pin.SE3, ...]:
    """The moving plate's path (held plate ``base``): off its foothold (``lift``) and back along
    an arc to the upright ``apex`` (the home pose), then along an arc to ``clearance`` above
    the target (the pre-contact pose) and onto it. The arcs shorten or lengthen the stack
    evenly so that a turn of π ends on the foot's surface. A foot's plate has its +z into its
    surface: the surface's outward normal is its −z."""
    height = float(base.actInv(apex).translation[2])
    points = [ee]
    if lift:
        u0, d0 = _side(base, ee)
        points.append(pin.SE3(ee.rotation, ee.translation - clearance * ee.rotation[:, 2]))
        th = ARC_STEPS[::-1]
        ell = height + (0.5 * math.pi * d0 - height) * th / math.pi
        points += _arc(base, u0, ell, th, clearance * th / math.pi)
        points.append(apex)
    u1, d1 = _side(base, target)
    ell = height + (0.5 * math.pi * d1 - height) * ARC_STEPS / math.pi
    points += _arc(base, u1, ell, ARC_STEPS, clearance * ARC_STEPS / math.pi)
    if clearance > 0:
        points.append(pin.SE3(target.rotation, target.translation - clearance * target.rotation[:, 2]))
    points.append(target)
    return tuple(points)


def path_pieces(
    points: tuple[pin.SE3, ...], lift: bool, scene: Scene | None, n: int
) -> list[tuple[tuple[pin.SE3, ...], Scene | None]]:
    """The moving plate's path in pieces, each with the scene it is planned in: without a scene
    one piece; with one, the lift-off (when ``lift``) and the landing, along the foothold's
    normal, in the scene where both feet stand, and the arcs between them in the scene where
    the held foot alone stands."""
    if scene is None:
        return [(points, None)]
    held, both = dataclasses.replace(scene, standing=(0,)), dataclasses.replace(scene, standing=(0, n))
    last = len(points) - 2  # the pre-contact point opens the landing (clearance > 0 with a scene)
    out: list[tuple[tuple[pin.SE3, ...], Scene | None]] = [(points[:2], both)] if lift else []
    out.append((points[1 if lift else 0 : last + 1], held))
    out.append((points[last:], both))
    return out
