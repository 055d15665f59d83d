"""The meshcat server's former home: it is :mod:`assembler_pin.viz.server` (import from
there); this module re-exports its public names so older imports keep working."""

from __future__ import annotations

from .viz.server import *  # noqa: F403
from .viz.server import __all__  # noqa: F401
