"""A hexapod of stacks: k stacks (the legs) whose EE plates hold one rigid body, standing on
their base plates (the feet), welded or resting on a floor.

- :mod:`.machine`: the stacks on a ring, the readers of the arguments, the machine's centre of mass.
- :mod:`.structure`: the whole structure's potential and Newton's method on it.
- :mod:`.feet`: a resting foot's admissible wrench and the static stability margin.
- :mod:`.stand`: the equilibrium for commanded lengths (:func:`stand`).
- :mod:`.commands`: the force-optimal commands and ``∂F/∂L_cmd``.
- :mod:`.capacity`: the largest body mass within every limit.
- :mod:`.clearance`: the machine's clearance (stacks, body, scene).
- :mod:`.gait`: the walk on a flat floor, every sample checked (:func:`walk`).
- :mod:`.walkfile`: a walk's trajectory file, written atomically and read back strictly.
"""

from __future__ import annotations

from .capacity import HexapodCapacity, hexapod_capacity
from .clearance import HexapodClearance, hexapod_clearance
from .commands import HexapodCommands, force_optimal_commands, length_sensitivity
from .gait import GAITS, HexapodWalk, WalkSample, walk
from .machine import MAX_STACKS, configured_hexapod, machine_com, ring_stacks
from .stand import FEET, HexapodStand, stand
from .walkfile import WalkFile, read_walk, write_walk

__all__ = [
    "FEET",
    "GAITS",
    "MAX_STACKS",
    "HexapodCapacity",
    "HexapodClearance",
    "HexapodCommands",
    "HexapodStand",
    "HexapodWalk",
    "WalkFile",
    "WalkSample",
    "configured_hexapod",
    "force_optimal_commands",
    "hexapod_capacity",
    "hexapod_clearance",
    "length_sensitivity",
    "machine_com",
    "read_walk",
    "ring_stacks",
    "stand",
    "walk",
    "write_walk",
]
