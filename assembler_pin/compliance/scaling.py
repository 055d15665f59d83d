"""How the EE's stiffness and sag scale with the number of platforms (``stiffness --scaling``).

For each n the stack of the configuration with ``platforms = n`` is taken at its home pose,
its legs commanded to the home lengths: :func:`~assembler_pin.compliance.ee_stiffness.stiffness` gives
the tangent stiffness at the loaded equilibrium and the sag under gravity and payload; the
elastic part alone (the legs' springs, :func:`~assembler_pin.compliance.ee_stiffness.elastic_compliance`)
is given beside it, and stays defined where the loaded stack buckles.

Stiffnesses are under a pure force or moment along one world axis at the EE origin, i.e. the
inverse of the compliance's diagonal: lateral ``1/C_xx`` [N/m], axial ``1/C_zz`` [N/m],
torsional ``1/C_ωz ωz`` [N·m/rad]; the sag is ``|sag translation|`` [m].
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import cast

import numpy as np
import pinocchio as pin

from ..common.palette import LEG_CYCLE, LIMIT, OPTIMIZED
from ..common.progress import ProgressCallback, checked_progress
from ..config.bounds import check_bound
from ..config.schema import AssemblerConfig, load_config
from ..exceptions import OptionsError
from ..model.assembler import AssemblerModel
from ..model.geometry import LegGeometry, home_plates, leg_geometry
from .ee_stiffness import elastic_compliance, stiffness

__all__ = ["ScalingTable", "scaling_figure", "stiffness_scaling"]

_QUANTITIES = ("lateral", "axial", "torsional")
_DIAGONAL = {"lateral": 0, "axial": 2, "torsional": 5}


@dataclass(frozen=True)
class ScalingTable:
    """Stiffness and sag of the home pose against the number of platforms.

    Attributes:
        platforms: (m,) the numbers of platforms n.
        lateral, axial, torsional: (m,) the loaded stiffness [N/m, N/m, N·m/rad] (NaN where
            the loaded stack buckles); elastic: the same three of the springs alone.
        sag: (m,) ``|sag translation|`` [m] (NaN where it buckles).
        stable: (m,) the loaded equilibrium exists and is stable; message: why not, per n.
        leg_stiffness: k [N/m].
    """

    platforms: np.ndarray
    lateral: np.ndarray
    axial: np.ndarray
    torsional: np.ndarray
    sag: np.ndarray
    elastic: dict[str, np.ndarray]
    stable: np.ndarray
    message: list[str]
    leg_stiffness: float

    @property
    def first_unstable(self) -> int | None:
        """The smallest n whose loaded stack buckles (None: none in the table)."""
        bad = self.platforms[~self.stable]
        return int(bad[0]) if bad.size else None

    def to_dict(self) -> dict:
        """The JSON of ``stiffness --scaling --json`` (NaN as null through ``dumps``)."""
        return {
            "platforms": self.platforms.tolist(),
            "leg_stiffness": self.leg_stiffness,
            "lateral": self.lateral.tolist(),
            "axial": self.axial.tolist(),
            "torsional": self.torsional.tolist(),
            "sag": self.sag.tolist(),
            "elastic": {q: self.elastic[q].tolist() for q in _QUANTITIES},
            "stable": self.stable.tolist(),
            "message": self.message,
            "first_unstable": self.first_unstable,
            "units": {"lateral": "N/m", "axial": "N/m", "torsional": "N m/rad", "sag": "m"},
        }


@dataclass(frozen=True)
class _Truss:
    """What the stiffness reads of a model (its configuration, size, leg anchors and home
    pose), without the Pinocchio model an :class:`AssemblerModel` builds (0.3–0.6 s each)."""

    config: AssemblerConfig
    n: int
    geometry: LegGeometry
    home: list[pin.SE3]


def _truss(config: AssemblerConfig) -> AssemblerModel:
    truss = _Truss(config, config.platforms, leg_geometry(config), home_plates(config))
    return cast(AssemblerModel, truss)  # the stiffness reads only config, n, geometry and home


def stiffness_scaling(
    config: AssemblerConfig | None = None, max_platforms: int = 64, progress: ProgressCallback | None = None
) -> ScalingTable:
    """The :class:`ScalingTable` of n = 1..``max_platforms`` (bounds key ``config.platforms``).

    Raises:
        OptionsError: ``max_platforms`` out of its bounds.
    """
    top = int(check_bound("config.platforms", max_platforms, "max_platforms", OptionsError))
    progress = checked_progress(progress)
    if config is not None and not isinstance(config, AssemblerConfig):
        raise OptionsError(f"config must be an AssemblerConfig or None, got {type(config).__name__}")
    base = config if config is not None else load_config()
    ns = np.arange(1, top + 1)
    rows, elastic, stable, message = [], [], [], []
    for i, n in enumerate(ns):
        am = _truss(dataclasses.replace(base, platforms=int(n)))
        result = stiffness(am, am.home)
        C_el = elastic_compliance(am, am.home)
        diag = np.diag(result.compliance)
        rows.append([*(1.0 / diag[_DIAGONAL[q]] for q in _QUANTITIES), float(np.linalg.norm(result.sag_translation))])
        elastic.append([1.0 / C_el[_DIAGONAL[q], _DIAGONAL[q]] for q in _QUANTITIES])
        stable.append(result.success)
        message.append(result.message)
        if progress is not None:
            progress(i + 1, len(ns), f"{n} platforms")
    table, el = np.array(rows), np.array(elastic)
    lateral, axial, torsional, sag = table.T
    return ScalingTable(
        ns,
        lateral,
        axial,
        torsional,
        sag,
        {q: el[:, j] for j, q in enumerate(_QUANTITIES)},
        np.array(stable),
        message,
        float(base.leg.stiffness),
    )


def scaling_figure(table: ScalingTable):
    """Log-log figure, one unit per axis: the translational stiffnesses [N/m], the torsional
    one [N·m/rad] (loaded solid, springs alone dashed) and the sag [mm] against n, the first
    buckling n marked; every axis labels enough ticks to be read (minor ones too when its data
    spans less than a few decades)."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import LogFormatterSciNotation, ScalarFormatter

    fig = Figure(figsize=(14, 4.6), layout="constrained")
    ax_t, ax_r, ax_s = fig.subplots(1, 3)
    names = {"lateral": "lateral (x)", "axial": "axial (z)", "torsional": "torsional (about z)"}
    for colour, q in zip(LEG_CYCLE, _QUANTITIES, strict=False):
        ax = ax_r if q == "torsional" else ax_t
        ax.loglog(table.platforms, getattr(table, q), "-", color=colour, lw=2, label=f"{names[q]}, loaded")
        ax.loglog(table.platforms, table.elastic[q], "--", color=colour, lw=1, label=f"{names[q]}, legs' springs alone")
    ax_s.loglog(table.platforms, 1e3 * table.sag, "-", color=OPTIMIZED, lw=2, label="EE sag, gravity + payload")
    for ax in (ax_t, ax_r, ax_s):
        if table.first_unstable is not None:
            ax.axvline(
                table.first_unstable, color=LIMIT, ls=":", lw=1.2, label=f"buckles from n = {table.first_unstable}"
            )
        ax.set_xlabel("platforms n")
        ax.xaxis.set_major_formatter(ScalarFormatter())  # counts: 1, 10, not 10⁰, 10¹
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        ax.yaxis.set_minor_formatter(LogFormatterSciNotation(labelOnlyBase=False, minor_thresholds=(2, 0.5)))
    ax_t.set_ylabel("stiffness under a pure force [N/m]")
    ax_r.set_ylabel("stiffness under a pure moment [N·m/rad]")
    ax_s.set_ylabel("sag [mm]")
    k = table.leg_stiffness
    ax_t.set_title(f"EE translational stiffness at home (legs {k:g} N/m)", fontsize=10)
    ax_r.set_title("EE torsional stiffness at home", fontsize=10)
    ax_s.set_title("EE sag at home, legs commanded to the home lengths", fontsize=10)
    return fig
