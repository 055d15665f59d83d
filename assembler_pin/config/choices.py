"""The names a user chooses from, in one light module (no numerical imports).

The command line builds its ``choices`` and help texts from these tuples without loading
Pinocchio; the modules that define what each name means check at import time that their
tables carry exactly these names (:mod:`~assembler_pin.scenarios`,
:mod:`~assembler_pin.carrier`, :mod:`~assembler_pin.viz`).
"""

from __future__ import annotations

from collections.abc import Iterable

__all__ = [
    "CARRIER_NAMES",
    "FORCE_SCALES",
    "OBJECTIVES",
    "OPTIMIZE_METHODS",
    "PATH_KINDS",
    "SCENARIO_NAMES",
    "SOLVE_STARTS",
    "check_names",
]

#: The paper's scenarios (:data:`assembler_pin.scenarios.SCENARIOS`), in the paper's order.
SCENARIO_NAMES = ("translation", "ninety_degrees", "inchworm", "vertical_lift", "orientation_transition")

#: Carrier arms from example-robot-data (:data:`assembler_pin.carrier.CARRIERS`).
CARRIER_NAMES = ("ur3", "ur5", "ur10", "panda")

#: Where the viewer's leg colors saturate: ``auto`` (max|F|, at least 10 % of the limit),
#: ``limit`` (the force limits), ``max`` (max|F| of the shown pose).
FORCE_SCALES = ("auto", "limit", "max")

#: The start portfolios of ``solve --starts`` (:data:`assembler_pin.solver.starts.START_MODES`,
#: the default first): ``first`` runs the starts in order until the answer is settled;
#: ``all`` runs every start and keeps the best optimum.
SOLVE_STARTS = ("first", "all")

#: The optimizer's objectives (:mod:`assembler_pin.objective`, the default first): ``force``
#: (Ω, paper eq. 10), ``sag`` (the EE's sag under its own load), ``weighted`` (Ω plus a
#: weighted, normalized sag).
OBJECTIVES = ("force", "sag", "weighted")

#: The optimizer's methods (:mod:`assembler_pin.optimize`; the default is ``auto``): ``slsqp``
#: (smooth epigraph form, scipy's SLSQP), ``paper`` (the paper's literal form, finite
#: differences), ``ipopt`` (the smooth form by IPOPT on the sparse constraint Jacobian,
#: through CasADi), ``auto`` (IPOPT for long stacks, SLSQP otherwise).
OPTIMIZE_METHODS = ("slsqp", "paper", "ipopt", "auto")

#: Interpolations of an EE path on SE(3): ``screw`` (geodesic) or ``linear`` (line + slerp).
PATH_KINDS = ("screw", "linear")


def check_names(table: Iterable[str], names: tuple[str, ...], what: str) -> None:
    """Raise ``RuntimeError`` at import when a table's keys differ from its declared names."""
    keys = tuple(table)
    if keys != names:
        raise RuntimeError(f"{what} {keys} differ from assembler_pin.config.choices {names}")
