"""Which bodies are checked against which: the pair rule of the stack's own bodies.

Bodies: every leg (two capsules, motor and shaft) and every plate (a flat cylinder). Legs are
numbered ``g = 6 j + i`` (platform j, leg i); plates ``k = 0..n``.

* **Leg against leg**, every pair of legs, of one platform or of two. Legs that share a joint
  node (the two legs of a node of one platform, and the legs of the platform below and above
  an intermediate plate, whose joint centres coincide there) touch there by design: each of
  the two is checked only beyond ``leg.node_zone`` from that node (measured along its axis
  from its joint centre). No two legs share both ends.
* **Leg against plate**, every plate; against the two plates its joints sit on, only beyond
  ``leg.node_zone`` from that joint (a lean can bring the motor into its own base plate).
* **Plate against plate**, every pair of plates (neighbours too: a lean can bring two rims
  together).
* **Scene**: every leg and every plate against every obstacle; every leg and every plate
  against the floor, but not the plates standing on it (:attr:`Scene.standing
  <assembler_pin.collision.scene.Scene.standing>`: the base plate; a walk's foot as it lands
  or lifts off) and not the first ``leg.node_zone`` of a leg from a joint on a standing plate;
  the same rule for an obstacle the stack stands on (``support``, a table or a mount).

The table depends on the configuration only and is built once per configuration.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

import numpy as np

from ..config.schema import AssemblerConfig
from ..model.geometry import LEGS_PER_PLATFORM

__all__ = ["PairTable", "leg_nodes", "pair_table", "per_config"]

_T = TypeVar("_T")


def per_config(build: Callable[[AssemblerConfig], _T]) -> Callable[[AssemblerConfig], _T]:
    """``build(cfg)`` cached per configuration object (by identity, the last 8): hashing a
    nested frozen configuration costs microseconds on every call, a look-up by id does not."""
    cache: dict[int, tuple[AssemblerConfig, _T]] = {}

    @functools.wraps(build)
    def cached(cfg: AssemblerConfig) -> _T:
        hit = cache.get(id(cfg))
        if hit is not None and hit[0] is cfg:
            return hit[1]
        value = build(cfg)
        if len(cache) >= 8:
            cache.pop(next(iter(cache)))
        cache[id(cfg)] = (cfg, value)
        return value

    return cached


def leg_nodes(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The joint node of each leg end: (6n, 2) arrays of (plate, node index 0..2) for the
    bottom and the top end (the rule of :mod:`~assembler_pin.model.geometry`)."""
    bottom = np.array([(j, i // 2) for j in range(n) for i in range(LEGS_PER_PLATFORM)])
    top = np.array([(j + 1, i // 2 if i % 2 == 0 else (i // 2 - 1) % 3) for j in range(n) for i in range(6)])
    return bottom, top


@dataclass(frozen=True)
class PairTable:
    """The checked pairs of one configuration.

    Attributes:
        leg_a, leg_b: (P,) legs of each leg pair, ``leg_a < leg_b``.
        trim: (P, 4) booleans: is leg a trimmed at its bottom, at its top; is leg b trimmed
            at its bottom, at its top (the shared node's end).
        leg_plate: (Q, 2) (leg, plate) pairs: the other plates first, then each leg's own
            two plates.
        leg_plate_trim: (Q, 2) booleans: is the leg trimmed at its bottom, at its top (its
            joint on that plate).
        plate_pairs: (S, 2) (plate, plate) pairs.
    """

    leg_a: np.ndarray
    leg_b: np.ndarray
    trim: np.ndarray
    leg_plate: np.ndarray
    leg_plate_trim: np.ndarray
    plate_pairs: np.ndarray


@per_config
def pair_table(cfg: AssemblerConfig) -> PairTable:
    """The pairs of the rule above for the configuration ``cfg`` (cached)."""
    n = cfg.platforms
    G = LEGS_PER_PLATFORM * n
    bottom, top = leg_nodes(n)
    a, b = np.triu_indices(G, k=1)
    trim = np.stack(
        [
            (bottom[a] == bottom[b]).all(1) | (bottom[a] == top[b]).all(1),
            (top[a] == bottom[b]).all(1) | (top[a] == top[b]).all(1),
            (bottom[b] == bottom[a]).all(1) | (bottom[b] == top[a]).all(1),
            (top[b] == bottom[a]).all(1) | (top[b] == top[a]).all(1),
        ],
        axis=1,
    )
    platform = np.arange(G) // LEGS_PER_PLATFORM
    other = [(g, k) for g in range(G) for k in range(n + 1) if k not in (platform[g], platform[g] + 1)]
    own = [(g, platform[g] + end) for g in range(G) for end in (0, 1)]
    leg_plate = np.array(other + own, dtype=int).reshape(-1, 2)
    lp_trim = np.zeros((len(leg_plate), 2), dtype=bool)
    lp_trim[len(other) :: 2, 0] = True  # its bottom plate: beyond the bottom joint's zone
    lp_trim[len(other) + 1 :: 2, 1] = True  # its top plate: beyond the top joint's zone
    plate_pairs = np.array([(k, m) for k in range(n + 1) for m in range(k + 1, n + 1)]).reshape(-1, 2)
    return PairTable(a, b, trim, leg_plate, lp_trim, plate_pairs.astype(int))
