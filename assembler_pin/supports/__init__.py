"""The stack held at two points or at its end effector.

- :mod:`.two_point`: the statics of the stack held at two plates (:func:`two_point_statics`)
  or at its EE (:func:`ee_held_statics`).
- :mod:`.choice`: the one force distribution chosen among the many a two-point hold allows
  (:func:`chosen_distribution`).
- :mod:`.turned`: the stack turned upside down, held at its top plate (:func:`turned_model`).
"""

from __future__ import annotations

from .choice import ChosenDistribution, chosen_distribution
from .turned import TurnedModel, turned_model
from .two_point import EEHeldStatics, TwoPointStatics, ee_held_statics, held_plates, two_point_statics

__all__ = [
    "ChosenDistribution",
    "EEHeldStatics",
    "TurnedModel",
    "TwoPointStatics",
    "chosen_distribution",
    "ee_held_statics",
    "held_plates",
    "turned_model",
    "two_point_statics",
]
