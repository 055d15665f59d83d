"""Matplotlib figures of stack states: force tables, side/top views, force bars, workspace.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot's global
state (so it works headless, with any backend, and in notebooks: a Figure displays
inline there); :func:`save` writes one to PNG. The workspace slice lives in
:mod:`~assembler_pin.plots.workspace`, the trajectory figure in :mod:`~assembler_pin.plots.trajectory`.

Conventions (as everywhere in the package): forces in newtons, **tension positive**;
positions in metres in the world frame O (z up). Colours are the package's one colour
language (:mod:`~assembler_pin.common.palette`): the initial condition green, the optimized pose
charcoal, the helper arm violet; force scales run blue (compression) ↔ grey (0) ↔ red
(tension), the viewer's leg colours, so red always means tension. Legends sit outside
the drawn data.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pinocchio as pin
from matplotlib.colors import TwoSlopeNorm
from matplotlib.figure import Figure
from matplotlib.patches import Patch, Rectangle

from ..common import palette
from ..common.files import atomic_path
from ..common.labels import leg_label, platform_label
from ..common.palette import hex_color
from ..config.schema import LegConfig
from ..constraints import at_stroke_end
from ..exceptions import AssemblerError
from ..state import StackState

__all__ = [
    "INITIAL_COLOR",
    "OPTIMIZED_LEG_COLOR",
    "OPTIMIZED_PLATE_COLOR",
    "draw_state",
    "force_bars",
    "force_heatmaps",
    "leg_flags",
    "pose_views",
    "save",
]

logger = logging.getLogger(__name__)

INITIAL_COLOR = hex_color(palette.INITIAL)
"""Green: the initial condition (paper §V)."""
OPTIMIZED_PLATE_COLOR = hex_color(palette.OPTIMIZED)
"""Charcoal: plates of the optimized pose."""
OPTIMIZED_LEG_COLOR = hex_color(palette.OPTIMIZED)
"""Charcoal: legs of the optimized pose (red is tension only)."""
ARM_COLOR = hex_color(palette.ARM)
"""Violet: the helper arm's links (as in the viewer, a color no leg takes)."""
ARM_JOINT_COLOR = hex_color(palette.ARM_JOINT)
"""Dark violet: the helper arm's joint clusters."""
FORCE_CMAP = palette.force_cmap()
"""Diverging colormap: blue = compression (negative), grey = 0, red = tension (positive)."""
VIOLATION_COLOR = hex_color(palette.VIOLATION)
"""Yellow: a leg at a force bound, a grid point violating a limit."""
GOAL_FACE, GOAL_EDGE = hex_color(palette.GOAL_FACE), hex_color(palette.GOAL_EDGE)


def _named_states(
    initial: StackState | None, optimized: StackState | None, titles: Sequence[str]
) -> list[tuple[str, StackState]]:
    out = [(t, s) for t, s in zip(titles, (initial, optimized), strict=True) if s is not None]
    if not out:
        raise AssemblerError("nothing to plot: both states are missing")
    return out


# ---------------------------------------------------------------------- force tables
FORCE_BOUND_FRACTION = 0.99
"""A leg at this fraction of its force limit or more is marked "at the force bound"."""


def leg_flags(state: StackState, leg: LegConfig) -> tuple[np.ndarray, np.ndarray]:
    """(n, 6) masks of the legs at a stroke end (:func:`~assembler_pin.constraints.at_stroke_end`:
    within :data:`~assembler_pin.constraints.STROKE_END_TOLERANCE`) and at the force bound (at
    least :data:`FORCE_BOUND_FRACTION` of the tension or compression limit)."""
    stroke = at_stroke_end(state.leg_lengths, leg.min_length, leg.max_length)
    F = state.forces
    bound = (F >= FORCE_BOUND_FRACTION * leg.max_tension) | (F <= -FORCE_BOUND_FRACTION * leg.max_compression)
    return stroke, bound


def force_heatmaps(
    initial: StackState | None,
    optimized: StackState | None = None,
    titles: Sequence[str] = ("initial", "optimized"),
    limit: float | None = None,
    fmt: str = "{:.1f}",
    leg: LegConfig | None = None,
    title: str | None = None,
) -> Figure:
    """Annotated heatmaps of the actuator forces, leg × platform, side by side.

    Rows are legs 0..5, columns platforms SP0..SP(n-1) (0-based, as the arrays:
    :mod:`~assembler_pin.common.labels`); each cell is annotated with its force [N]. The
    colormap is diverging and centred at 0 (red tension, grey 0, blue compression) with one
    symmetric scale for both panels: ±``limit`` if given, else ±max |F| over the states
    shown. With ``leg`` (the leg limits), a leg at a stroke end gets a black frame and
    a leg at the force bound a yellow one (see :func:`leg_flags`), each kind of frame drawn
    listed in a legend below; ``title`` heads the figure.
    """
    states = _named_states(initial, optimized, titles)
    vmax = limit if limit is not None else max(float(np.abs(s.forces).max()) for _, s in states)
    vmax = max(vmax, 1e-9)
    norm = TwoSlopeNorm(vcenter=0.0, vmin=-vmax, vmax=vmax)
    n = states[0][1].forces.shape[0]
    fig = Figure(figsize=(1.2 + 1.25 * n * len(states), 4.2), layout="constrained")
    axes = fig.subplots(1, len(states), squeeze=False)[0]
    image = None
    framed: set[int] = set()  # the kinds of frame drawn: 0 stroke end, 1 force bound
    for ax, (name, state) in zip(axes, states, strict=True):
        table = state.forces.T  # (6, n): leg × platform
        image = ax.imshow(table, cmap=FORCE_CMAP, norm=norm, aspect="auto")
        for i in range(table.shape[0]):
            for j in range(table.shape[1]):
                value = table[i, j]
                dark = abs(value) > 0.6 * vmax
                ax.text(
                    j, i, fmt.format(value), ha="center", va="center", fontsize=8, color="white" if dark else "black"
                )
        ax.set_xticks(range(n), [platform_label(j) for j in range(n)])
        ax.set_yticks(range(6), [f"leg {i}" for i in range(6)])
        ax.set_xlabel("platform")
        ax.set_ylabel("leg")
        ax.set_title(f"{name}: max |F| {state.max_abs_force:.1f} N, mean {state.mean_abs_force:.1f} N", fontsize=9)
        if leg is not None:
            for k, (mask, color) in enumerate(zip(leg_flags(state, leg), ("black", VIOLATION_COLOR), strict=True)):
                for j, i in zip(*np.nonzero(mask), strict=True):
                    ax.add_patch(Rectangle((j - 0.46, i - 0.46), 0.92, 0.92, fill=False, ec=color, lw=2.2))
                    framed.add(k)
    frames = [
        Patch(fill=False, ec=color, lw=2, label=label)
        for k, (color, label) in enumerate((("black", "at a stroke end"), (VIOLATION_COLOR, "at the force bound")))
        if k in framed  # a legend entry only for a frame drawn
    ]
    if frames:
        fig.legend(handles=frames, loc="outside lower center", ncol=2, fontsize=7, frameon=False)
    assert image is not None  # at least one state is drawn
    fig.colorbar(image, ax=list(axes), label="force [N] (tension +, compression −)", shrink=0.9)
    if title:
        fig.suptitle(title)
    return fig


def force_bars(
    initial: StackState | None,
    optimized: StackState | None = None,
    titles: Sequence[str] = ("initial", "optimized"),
    limits: tuple[float, float] | None = None,
    leg: LegConfig | None = None,
    title: str | None = None,
) -> Figure:
    """Per-actuator force bars [N], initial (green) next to optimized (charcoal), labelled ``SPj leg i``.

    Args:
        limits: optional ``(max_tension, max_compression)`` [N] drawn as dashed lines (red
            tension, blue compression). The legend sits to the right of the axes.
        leg: the leg limits: legs at a stroke end are marked ▲ above (below) their bar,
            legs at the force bound ◆ (see :func:`leg_flags`).
        title: figure title.
    """
    states = _named_states(initial, optimized, titles)
    n = states[0][1].forces.shape[0]
    x = np.arange(6 * n)
    width = 0.8 / len(states)
    colors = {titles[0]: INITIAL_COLOR, titles[1]: OPTIMIZED_LEG_COLOR}
    tension, compression = hex_color(palette.TENSION), hex_color(palette.COMPRESSION)
    fig = Figure(figsize=(max(6.0, 0.38 * 6 * n), 3.6), layout="constrained")
    ax = fig.subplots()
    for k, (name, state) in enumerate(states):
        offset = (k - (len(states) - 1) / 2) * width
        ax.bar(x + offset, state.forces.ravel(), width, label=name, color=colors.get(name))
        if leg is not None:
            f = state.forces.ravel()
            pad = 0.04 * max(float(np.abs(s.forces).max()) for _, s in states)
            for mask, marker, what in zip(
                leg_flags(state, leg), ("^", "D"), ("stroke end", "force bound"), strict=True
            ):
                hit = mask.ravel()
                if hit.any():
                    ax.plot(
                        x[hit] + offset,
                        f[hit] + np.sign(f[hit]) * pad,
                        marker,
                        color=colors.get(name, "k"),
                        mec="k",
                        ms=5,
                        ls="none",
                        label=f"{name}: at a {what}",
                    )
    ax.axhline(0.0, color="black", lw=0.8)
    if limits is not None:
        ax.axhline(limits[0], color=tension, ls="--", lw=0.8, label="tension limit")
        ax.axhline(-limits[1], color=compression, ls="--", lw=0.8, label="compression limit")
    for j in range(1, n):
        ax.axvline(6 * j - 0.5, color="0.85", lw=0.8)
    ax.set_xticks(x, [leg_label(j, i) for j in range(n) for i in range(6)], fontsize=7, rotation=90)
    ax.set_xlabel("leg")
    ax.set_ylabel("force [N] (tension +)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    if title:
        ax.set_title(title)
    return fig


# ---------------------------------------------------------------------- side / top views
def _plate_outline(state: StackState, k: int) -> np.ndarray:
    """World points of plate k's leg joints, in angular order around its centre, closed."""
    legs = state.legs
    n = legs.lengths.shape[0]
    pts = []
    if k > 0:
        pts.append(legs.top_points[k - 1])
    if k < n:
        pts.append(legs.bottom_points[k])
    p = np.concatenate(pts)
    local = (p - state.plates.p[k]) @ state.plates.R[k]
    order = np.argsort(np.arctan2(local[:, 1], local[:, 0]))
    p = p[order]
    return np.vstack([p, p[:1]])


def draw_state(
    ax, state: StackState, axes_idx: tuple[int, int], leg_color: str, plate_color: str, label: str, alpha: float = 1.0
) -> None:
    """Draw a state projected on two world axes (``axes_idx``, e.g. (0, 2) for x–z): legs
    between their joint centres, plates outlined through their joints and filled."""
    a, b = axes_idx
    bottom, top = state.legs.bottom_points, state.legs.top_points
    for j in range(bottom.shape[0]):
        for i in range(6):
            ax.plot(
                [bottom[j, i, a], top[j, i, a]],
                [bottom[j, i, b], top[j, i, b]],
                color=leg_color,
                lw=1.4,
                alpha=alpha,
                label=label if (j, i) == (0, 0) else None,
            )
    for k in range(len(state.plates)):
        outline = _plate_outline(state, k)
        ax.plot(outline[:, a], outline[:, b], color=plate_color, lw=2.0, alpha=alpha)
        ax.fill(outline[:, a], outline[:, b], color=plate_color, alpha=0.15 * alpha)
    ax.plot(state.plates.p[:, a], state.plates.p[:, b], "o", color=plate_color, ms=3, alpha=alpha)


VIEWS_LEGEND_PT = 11.0
"""Font size of :func:`pose_views`' legend [pt]: 8.6 px tall when the 13.5-inch figure is shown
760 px wide (a documentation page), readable."""


def pose_views(
    initial: StackState | None,
    optimized: StackState | None = None,
    arm_points: npt.ArrayLike | None = None,
    titles: Sequence[str] = ("initial", "optimized"),
    title: str | None = None,
    goal: pin.SE3 | None = None,
    floor_z: float | None = None,
) -> Figure:
    """Side (x–z), front (y–z) and top (x–y) views of one or two states, as in the paper's figures.

    The initial state is drawn green, the optimized one charcoal (red is tension only);
    legs join their two joint centres, plates are outlined through their leg joints (filled
    translucent, so plates stacked in the top view stay readable; the front view separates
    them in height). ``arm_points`` ((n+2, 3) world points [m]) adds the helper arm: violet
    links, dark violet joint clusters. One legend for the three views, below them (it
    hides nothing drawn).

    Args:
        title: figure title (e.g. the scenario and its goal); max|F| of each state is added.
        goal: the EE goal, marked by a star and its z axis (the payload direction).
        floor_z: height of the floor [m], drawn as a line in the side and front views.
    """
    named = _named_states(initial, optimized, titles)
    fig = Figure(figsize=(13.5, 5.0), layout="constrained")
    side, front, top = fig.subplots(1, 3)
    views = ((side, (0, 2), "side view (x–z)"), (front, (1, 2), "front view (y–z)"), (top, (0, 1), "top view (x–y)"))
    for ax, idx, name in views:
        if initial is not None:
            draw_state(
                ax, initial, idx, INITIAL_COLOR, INITIAL_COLOR, titles[0], alpha=0.8 if optimized is not None else 1.0
            )
        if optimized is not None:
            draw_state(ax, optimized, idx, OPTIMIZED_LEG_COLOR, OPTIMIZED_PLATE_COLOR, f"{titles[1]} legs")
            ax.plot([], [], color=OPTIMIZED_PLATE_COLOR, lw=2.0, label=f"{titles[1]} plates")
        ax.plot([], [], "o", color="0.3", ms=3, label="plate centres")
        if arm_points is not None:
            arm = np.asarray(arm_points, dtype=float)
            ax.plot(arm[:, idx[0]], arm[:, idx[1]], "-", color=ARM_COLOR, lw=2.5, label="helper arm")
            ax.plot(arm[1:-1, idx[0]], arm[1:-1, idx[1]], "o", color=ARM_JOINT_COLOR, ms=7, label="helper arm joints")
        if goal is not None:
            p, z = goal.translation, goal.rotation[:, 2]
            ax.plot(p[idx[0]], p[idx[1]], "*", color=GOAL_EDGE, ms=14, mfc=GOAL_FACE, label="EE goal", zorder=5)
            tip = (p[idx[0]] + 0.12 * z[idx[0]], p[idx[1]] + 0.12 * z[idx[1]])
            ax.annotate("", xy=tip, xytext=(p[idx[0]], p[idx[1]]), arrowprops={"arrowstyle": "->", "color": "k"})
            axis = "EE goal's z axis (to the payload)"
            ax.plot([], [], color="k", lw=1.0, marker=">", ms=5, markevery=[-1], label=axis)
        if floor_z is not None and idx[1] == 2:
            ax.axhline(floor_z, color=hex_color(palette.FLOOR), lw=2.0, label="floor")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("xyz"[idx[0]] + " [m]")
        ax.set_ylabel("xyz"[idx[1]] + " [m]")
        ax.set_title(name)
        ax.grid(True, lw=0.4, alpha=0.5)
    handles, labels = side.get_legend_handles_labels()
    fig.legend(
        handles, labels, loc="outside lower center", ncol=min(len(labels), 5), fontsize=VIEWS_LEGEND_PT, frameon=False
    )
    forces = ", ".join(f"max|F| {t} {st.max_abs_force:.1f} N" for t, st in named)
    fig.suptitle(f"{title}: {forces}" if title else forces)
    return fig


def save(fig: Figure, path: str | Path, dpi: int = 150) -> Path:
    """Write a figure to PNG (parent directories created) and return the path.

    The file is written atomically (:func:`~assembler_pin.common.files.atomic_path`): an interrupted
    write leaves the previous file, never a truncated one.
    """
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")  # explicit: the temporary name ends in .tmp
    logger.info("wrote %s", out)
    return out
