"""The viewer's former home: every public name now lives in :mod:`assembler_pin.viz`
(import from there); this module re-exports them so older imports keep working."""

from __future__ import annotations

from .viz import *  # noqa: F403
from .viz import __all__  # noqa: F401
