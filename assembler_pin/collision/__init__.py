"""Collisions: the sizes of the stack's bodies, scenes of obstacles, and the clearance of a pose.

* :mod:`~assembler_pin.collision.bodies`: leg capsules and plate cylinders of a pose;
* :mod:`~assembler_pin.collision.pairs`: which pairs are checked (the rule);
* :mod:`~assembler_pin.collision.distance`: closed-form vectorized distances;
* :mod:`~assembler_pin.collision.scene`: obstacles and the floor, read strictly from YAML;
* :mod:`~assembler_pin.collision.kernel`: the compiled pass of the stack's own pairs;
* :mod:`~assembler_pin.collision.layout`: the rows of a configuration and a scene;
* :mod:`~assembler_pin.collision.closed`: the payload's, the floor's and the spheres' rows;
* :mod:`~assembler_pin.collision.screens`: lower bounds and coal's distances of the rest;
* :mod:`~assembler_pin.collision.check`: the clearance of a pose and its derivatives;
* :mod:`~assembler_pin.collision.home`: the home pose's clearance on plain floats.

Names are imported on first use, so that :mod:`~assembler_pin.collision.home` loads
without numpy (the fast ``statics --home`` answer).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..common.lazy import lazy_attributes

_LAZY = {
    "NEAR": ".check",
    "Clearance": ".check",
    "clearance": ".check",
    "Obstacle": ".scene",
    "Scene": ".scene",
    "read_scene": ".scene",
    "scene_from_dict": ".scene",
}

__all__ = ["NEAR", "Clearance", "Obstacle", "Scene", "clearance", "read_scene", "scene_from_dict"]


__getattr__, __dir__ = lazy_attributes(__name__, globals(), _LAZY)


if TYPE_CHECKING:
    from .check import NEAR, Clearance, clearance
    from .scene import Obstacle, Scene, read_scene, scene_from_dict
