"""Collisions: the sizes of the stack's bodies, scenes of obstacles, and the clearance of a pose.

* :mod:`~assembler_pin.collision.bodies`: leg capsules and plate cylinders of a pose;
* :mod:`~assembler_pin.collision.pairs`: which pairs are checked (the rule);
* :mod:`~assembler_pin.collision.distance`: closed-form vectorized distances;
* :mod:`~assembler_pin.collision.scene`: obstacles and the floor, read strictly from YAML;
* :mod:`~assembler_pin.collision.clearance`: the check and its derivatives.
"""

from .clearance import NEAR, Clearance, clearance
from .scene import Obstacle, Scene, read_scene, scene_from_dict

__all__ = ["NEAR", "Clearance", "Obstacle", "Scene", "clearance", "read_scene", "scene_from_dict"]
