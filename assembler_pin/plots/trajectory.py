"""The figure of a planned motion: leg lengths, speeds, accelerations and forces over time.

:func:`trajectory_plot` (also importable from :mod:`assembler_pin.plots`) draws one row of
panels per platform ``SPj`` and one column per quantity, the six legs of the platform in
six colours named ``SPj leg i`` (:mod:`~assembler_pin.common.labels`), colours from
:mod:`~assembler_pin.common.palette`. Each panel keeps its data's own scale (a limit far from the
data would squash the curves): a limit is drawn only near the data, and the panel's title
gives the distance from the data to the nearest limit. SI units; forces tension positive.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from matplotlib.figure import Figure

from ..common import palette
from ..common.labels import leg_label, platform_label
from ..common.palette import hex_color
from ..config.schema import LegConfig
from ..model.assembler import AssemblerModel
from ..state import StackState

__all__ = ["LIMIT_VIEW_FRACTION", "trajectory_plot"]


@dataclass(frozen=True)
class _Quantity:
    """One column of :func:`trajectory_plot`: a per-leg quantity over time and its limits."""

    name: str
    unit: str
    times: np.ndarray
    values: np.ndarray | None  # (T, n, 6) or None (not available)
    lower: float
    upper: float
    colors: tuple[str, str]  # lower and upper limit line colours
    mark_far_limits: bool = False  # a limit off the panel's scale is named at its edge (the forces)


LIMIT_VIEW_FRACTION = 0.6
"""A limit is drawn inside a trajectory panel when it lies within this fraction of the
data's own range beyond the data; farther limits would squash the curves, so the panel
keeps the data's scale and its title gives the distance to the nearest limit."""


def _limit_view(ax, lo: float, hi: float, lower: float, upper: float) -> None:
    """y-limits of a panel: the data's range [lo, hi] padded, widened to a limit only when
    that limit lies within :data:`LIMIT_VIEW_FRACTION` of the range beyond the data."""
    span = max(hi - lo, 1e-3 * max(abs(lower), abs(upper)), 1e-12)
    pad = 0.08 * span
    v0, v1 = lo - pad, hi + pad
    if lo - lower <= LIMIT_VIEW_FRACTION * span:
        v0 = min(v0, lower - pad)
    if upper - hi <= LIMIT_VIEW_FRACTION * span:
        v1 = max(v1, upper + pad)
    ax.set_ylim(v0, v1)


def _mark_far_limits(ax, limits: tuple[tuple[float, str, str], ...], unit: str) -> None:
    """Name each limit that lies off the panel's scale at the panel's edge on its side
    (``▲ tension limit 200 N``), in the limit's colour."""
    low, high = ax.get_ylim()
    for value, name, color in limits:
        if low <= value <= high:
            continue
        up = value > high
        ax.text(
            0.99,
            0.97 if up else 0.03,
            f"{'▲' if up else '▼'} {name} limit {value:g} {unit}",
            transform=ax.transAxes,
            ha="right",
            va="top" if up else "bottom",
            fontsize=7,
            color=color,
        )


#: How a margin is written in a panel's title: SI lengths in millimetres.
_TITLE_UNITS = {"m": ("mm", 1e3), "m/s": ("mm/s", 1e3), "m/s²": ("mm/s²", 1e3)}


def _quantity_panel(ax, q: _Quantity, j: int) -> None:
    """Platform ``j``'s six legs of ``q`` (one colour per leg, labelled ``SPj leg i``), its
    limits as dashed lines, and the distance from the data to the nearest limit in the title."""
    for value, color in zip((q.lower, q.upper), q.colors, strict=True):
        ax.axhline(value, color=color, ls="--", lw=1.2)
    ax.set_ylabel(f"{q.name} [{q.unit}]", fontsize=8)
    data = None if q.values is None or len(q.times) == 0 else q.values[:, j, :]
    if data is None:
        ax.set_title(f"{platform_label(j)}: no {q.name} data", fontsize=8, loc="left")
        return
    for i in range(6):
        ax.plot(q.times, data[:, i], color=hex_color(palette.LEG_CYCLE[i]), lw=1.0, label=leg_label(j, i))
    lo, hi = float(np.nanmin(data)), float(np.nanmax(data))
    _limit_view(ax, lo, hi, q.lower, q.upper)
    if q.mark_far_limits:
        _mark_far_limits(ax, ((q.upper, "tension", q.colors[1]), (q.lower, "compression", q.colors[0])), q.unit)
    gap = min(lo - q.lower, q.upper - hi)
    i = int(np.unravel_index(int(np.nanargmin(np.minimum(data - q.lower, q.upper - data))), data.shape)[1])
    verdict = "beyond a limit by" if gap < 0 else "nearest limit"
    unit, scale = _TITLE_UNITS.get(q.unit, (q.unit, 1.0))
    ax.set_title(
        f"{platform_label(j)} {q.name}: {verdict} {scale * abs(gap):.4g} {unit} (leg {i})", fontsize=8, loc="left"
    )


def _trajectory_quantities(am: AssemblerModel, traj, states, state_times) -> list[_Quantity]:
    """The columns of :func:`trajectory_plot`: length, speed, acceleration, force (statics)
    and, when the trajectory has them, the forces with the motion's own part."""
    leg = am.config.leg
    t = np.asarray(traj.times, dtype=float)
    mid = 0.5 * (t[1:] + t[:-1])
    grey = hex_color(palette.LIMIT)
    forces, ts = None, np.zeros(0)
    if states:
        ts = np.asarray(state_times, dtype=float)
        forces = np.array([st.forces for st in states])
    return [
        _Quantity("length", "m", t, traj.lengths, leg.min_length, leg.max_length, (grey, grey)),
        _Quantity("speed", "m/s", mid, traj.speeds(), -leg.max_speed, leg.max_speed, (grey, grey)),
        _Quantity(
            "acceleration",
            "m/s²",
            0.5 * (mid[1:] + mid[:-1]),
            traj.accelerations(),
            -leg.max_acceleration,
            leg.max_acceleration,
            (grey, grey),
        ),
        _Quantity(
            "force",
            "N",
            ts,
            forces,
            -leg.max_compression,
            leg.max_tension,
            (hex_color(palette.COMPRESSION), hex_color(palette.TENSION)),
            mark_far_limits=True,
        ),
    ] + (
        []
        if traj.dynamic_forces is None
        else [
            _Quantity(
                "force static+dynamic",
                "N",
                t,
                traj.dynamic_forces,
                -leg.max_compression,
                leg.max_tension,
                (hex_color(palette.COMPRESSION), hex_color(palette.TENSION)),
                mark_far_limits=True,
            )
        ]
    )


def trajectory_plot(
    am: AssemblerModel,
    traj,
    states: Sequence[StackState] | None = None,
    state_times: npt.ArrayLike | None = None,
    title: str = "Planned motion",
) -> Figure:
    """Leg lengths, speeds, accelerations and actuator forces of a trajectory over time: the
    static forces and (last column, every row) the forces with the motion's own part.

    One row of panels per platform (``SPj``), one column per quantity; in each panel the
    platform's six legs, one colour each, named ``SPj leg i`` in the row's legend (right of
    the row). Every panel keeps its data's own scale: a limit (dashed; force limits red
    tension, blue compression) is drawn inside it only when it is close to the data, and the
    panel's title gives the distance from the data to the nearest limit (and which leg).
    Samples that violate a constraint are shaded yellow.

    Args:
        traj: a :class:`~assembler_pin.motion.trajfile.Trajectory`.
        states: the stack at some of its samples (e.g. from
            :func:`~assembler_pin.motion.timing.trajectory_states`) for the per-leg forces;
            without them the force column shows the trajectory's max|F| only (first row).
        state_times: (len(states),) times of ``states`` [s].
        title: figure title (the path, e.g. "home → vertical_lift").
    """
    n = traj.lengths.shape[1]
    quantities = _trajectory_quantities(am, traj, states, state_times)
    fig = Figure(figsize=(17.0, 1.2 + 2.4 * n), layout="constrained")
    axes = fig.subplots(n, len(quantities), sharex=True, squeeze=False)
    t = np.asarray(traj.times, dtype=float)
    infeasible = ~np.asarray(traj.feasible, dtype=bool)
    for j in range(n):
        for ax, q in zip(axes[j], quantities, strict=True):
            _quantity_panel(ax, q, j)
            ax.tick_params(labelsize=7)
            if infeasible.any():
                shade = hex_color(palette.VIOLATION)
                ax.fill_between(t, 0, 1, where=infeasible, transform=ax.get_xaxis_transform(), color=shade, alpha=0.3)
        handles, labels = axes[j, 0].get_legend_handles_labels()
        outside = {"loc": "center left", "bbox_to_anchor": (1.02, 0.5), "fontsize": 7, "frameon": False}
        axes[j, -1].legend(handles, labels, **outside)
    if not states:
        _max_force_panel(axes[:, 3], t, traj.max_abs_force, am.config.leg)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    verdict = "every sample valid" if not infeasible.any() else f"{int(infeasible.sum())} samples INVALID (yellow)"
    law = traj.meta.get("time_law", "quintic")
    dynamic = "" if traj.dynamic_forces is None else f" ({np.nanmax(traj.max_abs_dynamic_force):.1f} N with the motion)"
    note = (
        "\nthe time-optimal law (TOPP-RA) is bang-bang: a leg that sets the pace switches between its "
        "acceleration limits"
        if law == "optimal"
        else ""
    )
    fig.suptitle(
        f"{title}: {law} time law, {traj.duration:.1f} s, peak max|F| {np.nanmax(traj.max_abs_force):.1f} N"
        f"{dynamic}, {verdict}{note}"
    )
    return fig


def _max_force_panel(column, t: np.ndarray, max_abs_force: np.ndarray, leg: LegConfig) -> None:
    """Without per-leg forces: the stack's max|F| in the first row's force panel, the rest hidden."""
    ax = column[0]
    ax.plot(t, max_abs_force, color=hex_color(palette.OPTIMIZED), lw=1.5, label="max|F| (all legs)")
    peak = float(np.nanmax(max_abs_force))
    limit = min(leg.max_tension, leg.max_compression)
    _limit_view(ax, float(np.nanmin(max_abs_force)), peak, -limit, limit)
    _mark_far_limits(ax, ((limit, "force", hex_color(palette.TENSION)),), "N")
    ax.set_title(f"max|F| of the stack: nearest limit {limit - peak:.3g} N", fontsize=8, loc="left")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7, frameon=False)
    for other in column[1:]:
        other.set_visible(False)
