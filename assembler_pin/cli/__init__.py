"""The ``assembler-pin`` command (:func:`main`); one module per subcommand."""

from __future__ import annotations

from .app import build_parser, main
from .common import format_state_table

__all__ = ["build_parser", "format_state_table", "main"]
