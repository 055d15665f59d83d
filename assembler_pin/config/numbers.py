"""The one reader of a number a user gives: in a file the package reads (a configuration, a
scene, footholds, a plate file, a map spec, a trajectory) or as an argument.

A value is a number only when it is a real number (not a boolean, a string or None) that a
float holds finitely: an integer of hundreds of digits (``1`` followed by 400 zeros in YAML or
JSON) is refused exactly like ``1e308`` or ``.inf``, never converted into an
``OverflowError``. Imports nothing but the standard library and the exceptions.
"""

from __future__ import annotations

import math
import numbers

from ..exceptions import short_repr

__all__ = ["finite_float", "is_number", "read_number"]


def is_number(value: object) -> bool:
    """A real number (Python or numpy, not a boolean: numpy's bool is not a ``numbers.Real``)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def finite_float(value: object) -> float | None:
    """``value`` as a finite float, or None when it is not a real number, is NaN or infinite, or
    is an integer too large for a float (more than about 1.8e308 in magnitude)."""
    if not is_number(value):
        return None
    try:
        x = float(value)  # type: ignore[arg-type]
    except (OverflowError, ValueError, TypeError):
        return None
    return x if math.isfinite(x) else None


def read_number(
    value: object,
    what: str,
    error: type[Exception],
    low: float = -math.inf,
    high: float = math.inf,
    unit: str = "",
) -> float:
    """``value`` as a float when it is a finite real number in ``[low, high]``; else ``error``,
    one line ``"{what} = {value} is invalid: must be ..."`` naming the value (cut short) and the
    allowed range in ``unit``."""
    x = finite_float(value)
    shown = short_repr(value, 40)
    if x is None:
        raise error(f"{what} = {shown} is invalid: must be a finite number")
    if not low <= x <= high:
        where = f"at most {high:g}" if low == -math.inf else f"at least {low:g}" if high == math.inf else None
        allowed = where or f"in [{low:g}, {high:g}]"
        raise error(f"{what} = {shown} is invalid: must be {allowed}{f' [{unit}]' if unit else ''}")
    return x
