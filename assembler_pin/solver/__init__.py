"""Goal pose → internal poses: the pipeline behind ``assembler-pin solve`` and the payload
capacity of a goal.

- :mod:`.pipeline`: :func:`solve`, the helper arm's start then the optimizer from each start.
- :mod:`.starts`: the start portfolio: the starts, their order, when to stop, which answer.
- :mod:`.sag`: the EE's sag of a solve's answer.
- :mod:`.capacity`: :func:`payload_capacity`, the largest payload a goal can hold.
"""

from __future__ import annotations

from .capacity import CapacityResult, payload_capacity
from .pipeline import SolveResult, solve

__all__ = ["CapacityResult", "SolveResult", "payload_capacity", "solve"]
