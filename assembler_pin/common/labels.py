"""How a platform and a leg are written wherever a person reads them.

One numbering, the arrays' own: **0-based**. Platform ``j`` (``j = 0..n-1``, joining
plate ``j`` to plate ``j+1``) is written ``SPj``; leg ``i`` (``i = 0..5``) of it
``SPj leg i``. So the text ``SP1 leg 2`` is ``forces[1, 2]``, the JSON violation
``{"platform": 1, "leg": 2}`` and the URDF joint ``sp1_leg2_actuator``: the same two
numbers everywhere (tables, violation messages, figure labels, viewer node names).
"""

from __future__ import annotations

__all__ = ["leg_label", "platform_label"]


def platform_label(j: int) -> str:
    """``SPj``: platform ``j`` (0-based, joins plate ``j`` to plate ``j+1``)."""
    return f"SP{int(j)}"


def leg_label(j: int, i: int) -> str:
    """``SPj leg i``: leg ``i`` (0..5) of platform ``j``, both 0-based."""
    return f"{platform_label(j)} leg {int(i)}"
