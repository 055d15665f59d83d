"""Two-point support in motion: the stack turned around (:mod:`.turned`) and the inchworm walk
(:mod:`.plan`, checked by :mod:`.verify`), and stacks joined to one body (:mod:`.macro`)."""

from __future__ import annotations

from .macro import MacroStatics, macro_capacity, macro_statics
from .plan import WalkOptions, WalkPhase, WalkResult, checked_footholds, plan_walk, plate_target
from .turned import TurnedModel, turned_config, turned_model
from .verify import verify_walk

__all__ = [
    "MacroStatics",
    "TurnedModel",
    "WalkOptions",
    "WalkPhase",
    "WalkResult",
    "checked_footholds",
    "macro_capacity",
    "macro_statics",
    "plan_walk",
    "plate_target",
    "turned_config",
    "turned_model",
    "verify_walk",
]
