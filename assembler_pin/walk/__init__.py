"""Two-point support in motion: the stack turned around (:mod:`~assembler_pin.supports.turned`) and the inchworm walk
(:mod:`.plan`, checked by :mod:`.verify`, its samples file :mod:`.samples`), and stacks joined
to one body (:mod:`.macro`)."""

from __future__ import annotations

from ..supports.turned import TurnedModel, turned_config, turned_model
from .footholds import checked_footholds, plate_target
from .macro import MacroStatics, macro_capacity, macro_statics
from .plan import WalkOptions, WalkPhase, WalkResult, plan_walk
from .samples import WalkSamples, parse_walk_csv, read_walk_csv
from .verify import verify_walk

__all__ = [
    "MacroStatics",
    "TurnedModel",
    "WalkOptions",
    "WalkPhase",
    "WalkResult",
    "WalkSamples",
    "checked_footholds",
    "macro_capacity",
    "macro_statics",
    "parse_walk_csv",
    "plan_walk",
    "plate_target",
    "read_walk_csv",
    "turned_config",
    "turned_model",
    "verify_walk",
]
