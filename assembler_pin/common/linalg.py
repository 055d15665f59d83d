"""Batched 3-vector helpers for the vectorized glue (numpy's ``np.cross`` is slow on the
small arrays of one stack; these are a few array operations each)."""

from __future__ import annotations

import numpy as np

__all__ = ["cross", "inverse_or_nan", "skew"]


def skew(v: np.ndarray) -> np.ndarray:
    """(..., 3) → (..., 3, 3) with ``skew(a) @ b == a × b``."""
    out = np.zeros((*v.shape, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product along the last axis, broadcasting like numpy."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def inverse_or_nan(blocks: np.ndarray) -> np.ndarray:
    """Inverses of a stack of square blocks (..., m, m); an exactly singular block's inverse
    is NaN (its condition number then reads as infinite)."""
    try:
        return np.linalg.inv(blocks)
    except np.linalg.LinAlgError:
        out = np.full(blocks.shape, np.nan)
        flat, res = blocks.reshape(-1, *blocks.shape[-2:]), out.reshape(-1, *blocks.shape[-2:])
        for k, block in enumerate(flat):
            try:
                res[k] = np.linalg.inv(block)
            except np.linalg.LinAlgError:
                pass
        return out
