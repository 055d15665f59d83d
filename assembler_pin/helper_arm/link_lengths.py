"""The link lengths d the helper arm's scan tries, in order (paper §III: the recursion over d) [m]."""

from __future__ import annotations

from collections.abc import Iterator

__all__ = ["link_length_scan"]


def _around(d0: float, step: float, d_range: tuple[float, float]) -> Iterator[float]:
    """d0, d0+s, d0-s, d0+2s, … within ``d_range``, stopping when both sides are out."""
    lo, hi = d_range
    if lo <= d0 <= hi:
        yield d0
    k = 1
    while True:
        up, down = d0 + k * step, d0 - k * step
        if up > hi and down < lo:
            return
        if up <= hi:
            yield up
        if down >= lo:
            yield down
        k += 1


def link_length_scan(d0: float, distance: float, n: int, step: float, d_range: tuple[float, float]) -> Iterator[float]:
    """The link lengths tried [m]: the home height d0 first (the paper's start), then
    ``d* = distance/n`` (the straight arm's length to the goal point) clipped to half a step
    inside ``d_range``, then d*+s, d*-s, d*+2s, … within ``d_range``, leaving out the values
    within half a step of d0 (already tried)."""
    lo, hi = d_range
    if lo <= d0 <= hi:
        yield d0
    d_star = min(max(distance / n, lo + 0.5 * step), hi - 0.5 * step)
    for d in _around(d_star, step, d_range):
        if abs(d - d0) >= 0.5 * step:
            yield d
