"""What a user sets, and the limits on it; imports no numerical library (the command line's
light layer).

- :mod:`.schema`: the configuration (YAML 1.2), its defaults and loading (:func:`load_config`).
- :mod:`.checks`: every range check of a configuration (:data:`LIMITS`).
- :mod:`.options`: the solvers' options (:class:`OptimizeOptions`, :class:`HelperArmOptions`,
  :class:`GoalTolerance`), the one source of their defaults.
- :mod:`.choices`: the named choices of the command line and the API.
- :mod:`.bounds`: the documented limits on counts, rates and durations.
- :mod:`.numbers`: the one reader of a number (finite, within a float) in a file or an argument.
- :mod:`.inputs`: the one door of input files (a regular file, bounded, checked before it is opened).
"""

from __future__ import annotations

from .checks import LIMITS
from .schema import AssemblerConfig, LegConfig, PayloadConfig, PlateConfig, load_config

__all__ = ["LIMITS", "AssemblerConfig", "LegConfig", "PayloadConfig", "PlateConfig", "load_config"]
