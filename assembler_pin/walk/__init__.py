"""Two-point support in motion: the stack turned around (:mod:`.turned`) and the inchworm walk
(:mod:`.plan`, checked by :mod:`.verify`)."""

from __future__ import annotations

from .plan import WalkOptions, WalkPhase, WalkResult, checked_footholds, plan_walk, plate_target
from .turned import TurnedModel, turned_config, turned_model
from .verify import verify_walk

__all__ = [
    "TurnedModel",
    "WalkOptions",
    "WalkPhase",
    "WalkResult",
    "checked_footholds",
    "plan_walk",
    "plate_target",
    "turned_config",
    "turned_model",
    "verify_walk",
]
