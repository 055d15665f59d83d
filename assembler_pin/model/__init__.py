"""The model files and the Pinocchio models of the stack.

- :mod:`.assembler`: :class:`AssemblerModel`, the stack's Pinocchio model and its loop closures.
- :mod:`.platform`: one platform's own model (:class:`PlatformModel`), for the per-platform statics.
- :mod:`.geometry`: the anchor geometry of the design.
- :mod:`.urdf`, :mod:`.urdf_check`, :mod:`.mjcf`: the generated URDF, its checks, and the MJCF.
"""

from __future__ import annotations

from .assembler import WHOLE_DATA_MAX_PLATFORMS, AssemblerModel, Closure, checked_model
from .platform import PlatformModel

__all__ = ["WHOLE_DATA_MAX_PLATFORMS", "AssemblerModel", "Closure", "PlatformModel", "checked_model"]
