"""Input checks shared by the API's entry points: numbers, arrays of numbers, nesting.

A user's value reaches the numerics only through these checks, so a boolean, a string, a
deeply nested list or an overflowing number is refused here with a message naming what was
given and what is allowed — never passed along as NaN or raised from inside numpy.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..config.numbers import is_number
from ..exceptions import PoseError, short_repr

__all__ = ["MAX_NESTING", "as_float_array"]

#: Deepest list nesting accepted in an array argument (a (B, n+1, 4, 4) batch is 4 deep).
MAX_NESTING = 6


def _has_bool_or_deep(value: Any, depth: int) -> str:
    """Why a nested list cannot be an array of real numbers ("" when it can, as far as this
    checks): a boolean, a string, a complex number or any other non-real leaf, or nesting
    deeper than :data:`MAX_NESTING`."""
    if isinstance(value, (list, tuple)):
        if depth >= MAX_NESTING:
            return f"nested deeper than {MAX_NESTING} levels"
        for item in value:
            why = _has_bool_or_deep(item, depth + 1)
            if why:
                return why
        return ""
    if isinstance(value, np.ndarray):
        return "" if value.dtype.kind in "iuf" else f"an array of {value.dtype} is not numbers"
    if isinstance(value, (bool, np.bool_)):
        return "true/false is not a number"
    if not is_number(value):
        return f"{short_repr(value, 30)} is not a real number"
    return ""


def as_float_array(value: Any, what: str, shape: tuple[int, ...] | None = None, error: type = PoseError) -> np.ndarray:
    """``value`` as a float array, refusing booleans, strings, ragged or deep nesting.

    Args:
        what: the argument's name, for the message.
        shape: the required shape, if any.
        error: the exception class raised (a subclass of AssemblerError).

    Raises:
        ``error``: the value is not an array of numbers (of ``shape``).
    """
    expected = f" of shape {shape}" if shape is not None else ""
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "iuf":  # not booleans, complex numbers, strings or objects
            raise error(f"{what} must be real numbers{expected}, got an array of {value.dtype}")
        arr = value.astype(float, copy=False)
    else:
        why = _has_bool_or_deep(value, 0)
        if why:
            raise error(f"{what} must be real numbers{expected}: {why}")
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError, OverflowError, RecursionError):
            raise error(f"{what} must be numbers{expected}") from None
    if shape is not None and arr.shape != shape:
        raise error(f"{what} must have shape {shape}, got {arr.shape}")
    return arr
