"""The hexapod's capacity: the largest body mass it stands with within every limit.

:func:`hexapod_capacity` holds the commanded lengths fixed (each pose's own by default) and
the body's centre of mass, and searches the body's mass: doubled from 1 kg until the stand
breaks a limit (or up to ``hexapod.body_mass``'s bound), then bisected to a relative
tolerance. The answer is a mass that stands within every limit and, ``rtol`` above it, the
mass that does not with what it breaks. (With the force-optimal commands of every mass, the
welded machine's capacity is :func:`~assembler_pin.walk.macro_capacity`, a linear program.)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy.typing as npt

from ..collision import Scene, read_scene
from ..config.bounds import BOUNDS, check_bound
from ..exceptions import HexapodError
from ..model.assembler import AssemblerModel
from .stand import HexapodStand, stand

__all__ = ["HexapodCapacity", "hexapod_capacity"]


@dataclass(frozen=True)
class HexapodCapacity:
    """Outcome of :func:`hexapod_capacity`.

    Attributes:
        mass: the largest body mass found that stands within every limit [kg] (0 when not
            even the empty body does).
        at_capacity: the stand with that mass; above: the stand ``rtol`` above it (None when
            the bound was reached); limit: what breaks above, or why nothing does.
    """

    mass: float
    at_capacity: HexapodStand
    above: HexapodStand | None
    limit: str


def hexapod_capacity(
    am: AssemblerModel,
    stacks: Sequence,
    body_com: npt.ArrayLike,
    lengths: npt.ArrayLike | None = None,
    feet: str = "welded",
    friction: float = 0.5,
    min_margin: float = 0.0,
    rtol: float = 1e-4,
    scene: Scene | str | None = None,
) -> HexapodCapacity:
    """The largest body mass (module doc) of the hexapod ``stacks`` with the body centred at
    ``body_com`` (world [m]) and the legs commanded ``lengths`` (None: each pose's own), its
    clearance kept among ``scene``'s obstacles and floor (:func:`~assembler_pin.hexapod.stand`).

    Raises:
        HexapodError: as :func:`~assembler_pin.hexapod.stand`, or ``rtol`` outside [1e-9, 0.1].
    """
    if not (isinstance(rtol, float | int) and not isinstance(rtol, bool) and 1e-9 <= rtol <= 0.1):
        raise HexapodError(f"rtol must be a number in [1e-9, 0.1], got {rtol!r:.40}")

    def at(mass: float) -> HexapodStand:
        return stand(am, stacks, mass, body_com, lengths, feet, friction, min_margin, obstacles)

    obstacles = read_scene(scene)
    empty = at(0.0)
    if not empty.feasible:
        return HexapodCapacity(
            0.0, empty, empty, f"the machine does not stand even without a body: {empty.violations[0]}"
        )
    high_bound = BOUNDS["hexapod.body_mass"].high
    lo, lo_result, hi = 0.0, empty, 1.0
    hi_result = at(hi)
    while hi_result.feasible:
        if hi >= high_bound:
            return HexapodCapacity(hi, hi_result, None, f"stands up to the body_mass bound {high_bound:g} kg")
        lo, lo_result, hi = hi, hi_result, min(2.0 * hi, high_bound)
        hi_result = at(hi)
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        result = at(mid)
        if result.feasible:
            lo, lo_result = mid, result
        else:
            hi, hi_result = mid, result
    check_bound("hexapod.body_mass", lo, "capacity", HexapodError)
    return HexapodCapacity(lo, lo_result, hi_result, hi_result.violations[0])
