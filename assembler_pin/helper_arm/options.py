"""Options of the helper arm's initial condition: :class:`HelperArmOptions` lives in
:mod:`assembler_pin.config.options` (light, the one source of its defaults); re-exported here."""

from __future__ import annotations

from ..config.options import HelperArmOptions

__all__ = ["HelperArmOptions"]
