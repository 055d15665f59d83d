"""Pictures of a map: heatmap slices with the stack drawn for scale, and a Meshcat point cloud."""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from scipy.spatial import ConvexHull

from ..collision.scene import Obstacle, Scene
from ..common.files import write_atomic
from ..common.palette import (
    CAPACITY_CMAP,
    CLEARANCE_CMAP,
    FLOOR,
    FORCE_MAGNITUDE_CMAP,
    LIMIT,
    OBSTACLE,
    OUTSIDE_GRID,
    OUTSIDE_GRID_EDGE,
    OUTSIDE_GRID_HATCH,
    PAGE_EDGE,
    PAGE_INK,
    PAGE_PANEL,
    SAG_CMAP,
    SCALE_POSE,
    SCALE_POSE_PLATE,
    STIFFNESS_CMAP,
    UNREACHABLE,
    UNREACHABLE_MARK,
    hex_color,
)
from ..exceptions import AssemblerError
from ..model.assembler import AssemblerModel
from ..plots.figures import draw_state
from ..state import evaluate_state

__all__ = [
    "MAP_FIGSIZE",
    "capacity_bar_html",
    "capacity_range",
    "clearance_range",
    "map_heatmaps",
    "map_slice",
    "obstacle_outlines",
    "point_size",
    "show_map_points",
    "slice_label",
    "write_map_page",
]

_AXIS = {"x": 0, "y": 1, "z": 2}


def map_slice(table, config: str | None = None, orientation: int = 0) -> tuple[str, str, dict[str, np.ndarray]]:
    """The 2-D slice of a map table: (u axis, v axis, columns gridded as (len(v), len(u)) arrays
    plus ``u`` and ``v`` values [m]). The slice is the first configuration (or ``config``),
    the given orientation index, and the first value of the fixed position axis."""
    scalars = [c for c in table.column_names if c not in ("clearance_between", "plates_xyzquat")]
    cols = {c: np.asarray(table.column(c).to_pylist()) for c in scalars}
    if not len(cols.get("cell", [])):
        raise AssemblerError("the map is empty")
    name = config if config is not None else cols["config"][0]
    keep = (cols["config"] == name) & (cols["io"] == orientation)
    if not keep.any():
        raise AssemblerError(f"no cells for config {name!r} and orientation {orientation}")
    cols = {c: v[keep] for c, v in cols.items()}
    varying = [a for a in "xyz" if len(np.unique(cols[a])) > 1]
    if len(varying) != 2:
        raise AssemblerError(f"a heatmap needs a map varying along two position axes, this one varies along {varying}")
    u_axis, v_axis = varying
    fixed = next(a for a in "xyz" if a not in varying)
    sel = cols[fixed] == cols[fixed].min()
    cols = {c: v[sel] for c, v in cols.items()}
    u, v = np.unique(cols[u_axis]), np.unique(cols[v_axis])
    iu, iv = np.searchsorted(u, cols[u_axis]), np.searchsorted(v, cols[v_axis])
    out: dict[str, np.ndarray] = {"u": u, "v": v}
    for c in ("reachable", "max_abs_force", "capacity_kg", "sag_m", "weakest_stiffness_n_per_m", "clearance_m"):
        grid = np.full((len(v), len(u)), np.nan)
        grid[iv, iu] = cols[c].astype(float)  # a null clearance (no pose) is NaN
        out[c] = grid
    return u_axis, v_axis, out


MAP_FIGSIZE = (13.0, 8.6)
"""Size of :func:`map_heatmaps`' figure [in]: 1950 × 1290 px at the 150 dpi it is saved at,
its text readable on a screen."""


def clearance_range(clearance_mm: np.ndarray, limit_mm: float) -> tuple[float, float]:
    """The clearance colour scale [mm]: from contact (0 mm, or the deepest overlap) to the
    largest finite value (at least the limit plus 1 mm), so that the limit is on the colour
    bar above its dark end."""
    c = np.asarray(clearance_mm, dtype=float)
    ok = np.isfinite(c)
    lo = min(0.0, float(c[ok].min())) if ok.any() else 0.0
    hi = max(float(c[ok].max()), limit_mm + 1.0) if ok.any() else limit_mm + 1.0
    return lo, max(hi, lo + 1.0)


def map_heatmaps(
    table,
    am: AssemblerModel,
    config: str | None = None,
    orientation: int = 0,
    title: str = "",
    scene: str = "",
    obstacles: Scene | None = None,
) -> Figure:
    """Clearance [mm], optimized max|F| [N], payload capacity [kg], EE sag [mm] and weakest EE
    stiffness [N/m] over a 2-D map slice, in a grid of panels (two rows of three, the legend
    in the sixth place) readable at screen size, the stack's home pose drawn in each panel for
    scale. Colours are :mod:`~assembler_pin.common.palette`'s, yellow the better end in every
    panel: a cell with no valid state is dark grey with an ``x`` in every panel (so every
    panel shows where the stack reaches), and where no cell was computed is white, hatched;
    the capacity scale is that of the HTML point cloud (:func:`capacity_range`), the clearance
    scale holds the configuration's ``clearance`` limit, drawn on its colour bar. The title
    names the slice: its fixed axis and value, the configuration, the EE orientation and
    ``scene`` (a name for the scene the map was computed with, if any). The obstacles and the
    floor of ``obstacles`` (that scene) are drawn in every panel: filled where the slice's
    plane cuts them, outlined (dashed) where they stand beside it, both as their shadow on the
    plane (:func:`obstacle_outlines`)."""
    u_axis, v_axis, s = map_slice(table, config, orientation)
    fig = Figure(figsize=MAP_FIGSIZE, layout="constrained")
    axes = fig.subplots(2, 3).ravel()
    extent = _extent(s["u"], s["v"])
    home = evaluate_state(am, am.home)
    limit_mm = 1e3 * am.config.clearance
    values = {**s, "sag_mm": 1e3 * s["sag_m"], "clearance_mm": 1e3 * s["clearance_m"]}
    scales = {
        "capacity_kg": capacity_range(s["capacity_kg"]),
        "clearance_mm": clearance_range(values["clearance_mm"], limit_mm),
    }
    panels = (
        ("clearance_mm", "clearance of the nearest two bodies", CLEARANCE_CMAP, "mm"),
        ("max_abs_force", f"optimized max|F| at {am.config.payload.mass:g} kg", FORCE_MAGNITUDE_CMAP, "N"),
        ("capacity_kg", "payload capacity", CAPACITY_CMAP, "kg"),
        ("sag_mm", "EE sag under gravity and payload", SAG_CMAP, "mm"),
        ("weakest_stiffness_n_per_m", "weakest EE stiffness", STIFFNESS_CMAP, "N/m"),
    )
    unreached = s["reachable"] == 0  # NaN (no cell computed) is neither reached nor unreached
    for ax, (key, name, cmap, unit) in zip(axes, panels, strict=False):
        _outside_grid_background(ax)
        lo, hi = scales.get(key, (None, None))
        image = ax.imshow(
            np.ma.masked_invalid(values[key]),
            origin="lower",
            extent=extent,
            cmap=cmap,
            aspect="equal",
            vmin=lo,
            vmax=hi,
        )
        _mark_unreached(ax, s, unreached, extent)
        if obstacles is not None:
            _draw_scene(ax, obstacles, u_axis, v_axis, _slice_value(table, config, orientation))
        draw_state(
            ax, home, (_AXIS[u_axis], _AXIS[v_axis]), hex_color(SCALE_POSE), hex_color(SCALE_POSE_PLATE), "", 0.5
        )
        ax.set_xlabel(f"{u_axis} [m]", fontsize=11)
        ax.set_ylabel(f"{v_axis} [m]", fontsize=11)
        ax.tick_params(labelsize=10)
        ax.set_title(f"{name} [{unit}]", fontsize=12)
        bar = fig.colorbar(image, ax=ax, shrink=0.85, label=f"{name} [{unit}]")
        bar.ax.tick_params(labelsize=10)
        bar.set_label(f"{name} [{unit}]", fontsize=10)
        if key == "clearance_mm":
            bar.ax.axhline(limit_mm, color=hex_color(OUTSIDE_GRID), lw=4.0)  # readable on dark and light
            bar.ax.axhline(limit_mm, color=hex_color(LIMIT), lw=2.0, ls="--")
            bar.set_label(f"clearance [mm] (dashed: the limit, {limit_mm:g} mm)", fontsize=10)
    legend_ax = axes[-1]
    legend_ax.axis("off")
    legend_ax.legend(
        handles=_legend_handles(obstacles),
        fontsize=11,
        loc="center",
        frameon=False,
        title="yellow is better in every panel",
    )
    reached = np.nan_to_num(s["reachable"]).astype(bool)
    within = f", scene {scene}" if scene else ""
    fig.suptitle(
        title
        or f"Capability map: {int(reached.sum())} of {reached.size} cells reachable{within}\n"
        f"{slice_label(table, config, orientation)}",
        fontsize=14,
    )
    return fig


def slice_label(table, config: str | None = None, orientation: int = 0) -> str:
    """Which slice :func:`map_slice` draws: the fixed axis and its value, the configuration
    and the EE orientation (rotation vector [deg])."""
    cols = {c: np.asarray(table.column(c).to_pylist()) for c in ("config", "io", "x", "y", "z")}
    name = config if config is not None else str(cols["config"][0])
    keep = (cols["config"] == name) & (cols["io"] == orientation)
    varying = [a for a in "xyz" if len(np.unique(cols[a][keep])) > 1]
    fixed = next((a for a in "xyz" if a not in varying), "z")
    where = f"{fixed} = {cols[fixed][keep].min():g} m"
    rotation = ""
    if "rx" in table.column_names:
        r = [np.asarray(table.column(c).to_pylist())[keep][0] for c in ("rx", "ry", "rz")]
        rotation = f", EE rotation vector ({', '.join(f'{np.degrees(v):g}' for v in r)})°"
    return f"slice {where}, config {name}, orientation {orientation}{rotation}"


def obstacle_outlines(scene: Scene, u_axis: str, v_axis: str, fixed: float) -> list[tuple[str, np.ndarray, bool]]:
    """Each obstacle of ``scene`` as the slice's panels draw it: (name, its shadow on the
    (u, v) plane as a convex polygon (k, 2) [m], whether the slice's plane cuts it). The plane
    is the third axis at ``fixed`` [m]; a box is exact, a cylinder's rims and a sphere's outline
    are polygons of 48 sides."""
    iu, iv = _AXIS[u_axis], _AXIS[v_axis]
    iw = 3 - iu - iv
    out = []
    for ob in scene.obstacles:
        points = _obstacle_points(ob)
        hull = ConvexHull(points[:, [iu, iv]])
        cut = _half_extent(ob, iw) >= abs(fixed - ob.pose.translation[iw])
        out.append((ob.name, points[hull.vertices][:, [iu, iv]], bool(cut)))
    return out


def _obstacle_points(ob: Obstacle) -> np.ndarray:
    """World points whose convex hull is the obstacle (a box's corners, a cylinder's rims, a
    sphere's great circles) [m]."""
    R, p = ob.pose.rotation, ob.pose.translation
    ang = np.linspace(0.0, 2.0 * np.pi, 48, endpoint=False)
    ring = np.stack([np.cos(ang), np.sin(ang), np.zeros_like(ang)], axis=1)
    if ob.kind == "box":
        local = 0.5 * np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * ob.size
    elif ob.kind == "cylinder":
        r, half = ob.size[0], 0.5 * ob.size[1]
        local = np.concatenate([r * ring + [0.0, 0.0, -half], r * ring + [0.0, 0.0, half]])
    else:
        local = ob.size[0] * np.concatenate([ring, ring[:, [2, 0, 1]], ring[:, [1, 2, 0]]])
    return local @ R.T + p


def _half_extent(ob: Obstacle, axis: int) -> float:
    """Half the obstacle's extent along a world axis [m]."""
    R = ob.pose.rotation
    if ob.kind == "box":
        return float(0.5 * np.abs(R[axis]) @ np.asarray(ob.size))
    if ob.kind == "cylinder":
        r, length = ob.size
        c = abs(R[axis, 2])
        return float(0.5 * length * c + r * np.sqrt(max(0.0, 1.0 - c * c)))
    return float(ob.size[0])


def _slice_value(table, config: str | None, orientation: int) -> float:
    """The fixed axis's value of the slice :func:`map_slice` draws [m]."""
    u_axis, v_axis, _ = map_slice(table, config, orientation)
    fixed = next(a for a in "xyz" if a not in (u_axis, v_axis))
    cols = {c: np.asarray(table.column(c).to_pylist()) for c in ("config", "io", fixed)}
    name = config if config is not None else cols["config"][0]
    return float(cols[fixed][(cols["config"] == name) & (cols["io"] == orientation)].min())


def _draw_scene(ax, scene: Scene, u_axis: str, v_axis: str, fixed: float) -> None:
    """The scene in one panel: obstacles (:func:`obstacle_outlines`) over the cells, the floor
    as a line where it is in the plane's view (a vertical slice)."""
    from matplotlib.patches import Polygon

    for name, polygon, cut in obstacle_outlines(scene, u_axis, v_axis, fixed):
        ax.add_patch(
            Polygon(
                polygon,
                closed=True,
                facecolor=OBSTACLE if cut else "none",
                edgecolor=PAGE_INK,
                ls="-" if cut else "--",
                lw=0.8,
                zorder=3,
                gid=f"obstacle {name}",
            )
        )
    if scene.floor_z is not None and "z" in (u_axis, v_axis):
        line = ax.axhline if v_axis == "z" else ax.axvline
        line(scene.floor_z, color=hex_color(FLOOR), lw=2.5, zorder=3, label="floor")


def capacity_range(capacity: np.ndarray) -> tuple[float, float]:
    """The capacity colour scale [kg]: the finite values' (min, max), (0, 1) when none; one
    rule for the PNG and the HTML point cloud."""
    cap = np.asarray(capacity, dtype=float)
    ok = np.isfinite(cap)
    if not ok.any():
        return 0.0, 1.0
    lo, hi = float(cap[ok].min()), float(cap[ok].max())
    return (lo, hi) if hi > lo else (lo, lo + 1e-9)


def _outside_grid_background(ax) -> None:
    """White, hatched behind the panel: what shows where no cell was computed."""
    from matplotlib.patches import Rectangle

    ax.set_facecolor(OUTSIDE_GRID)
    ax.add_patch(
        Rectangle(
            (0, 0),
            1,
            1,
            transform=ax.transAxes,
            facecolor=OUTSIDE_GRID,
            edgecolor=OUTSIDE_GRID_EDGE,
            hatch=OUTSIDE_GRID_HATCH,
            lw=0,
            zorder=-1,
        )
    )


def _mark_unreached(ax, s: dict[str, np.ndarray], unreached: np.ndarray, extent) -> None:
    """Cells with no valid state: dark grey, with an ``x`` at each centre."""
    if not unreached.any():
        return
    ax.imshow(
        np.ma.masked_where(~unreached, np.ones_like(s["reachable"])),
        origin="lower",
        extent=extent,
        cmap=ListedColormap([UNREACHABLE]),
        aspect="equal",
        vmin=0,
        vmax=1,
    )
    iv, iu = np.nonzero(unreached)
    ax.scatter(
        s["u"][iu], s["v"][iv], marker="x", s=18, color=hex_color(UNREACHABLE_MARK), lw=0.8, label="not reachable"
    )


def _legend_handles(scene: Scene | None = None) -> list:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    drawn: list = []
    if scene is not None and scene.obstacles:
        drawn += [
            Patch(facecolor=OBSTACLE, edgecolor=PAGE_INK, label="obstacle the slice cuts"),
            Patch(facecolor="none", edgecolor=PAGE_INK, ls="--", label="obstacle beside the slice (its shadow)"),
        ]
    if scene is not None and scene.floor_z is not None:
        drawn.append(Line2D([], [], color=FLOOR, lw=2.5, label="floor"))
    return [
        *drawn,
        Patch(facecolor=UNREACHABLE, label="not reachable (marked x)"),
        Patch(facecolor=OUTSIDE_GRID, edgecolor=OUTSIDE_GRID_EDGE, hatch=OUTSIDE_GRID_HATCH, label="outside the grid"),
        Line2D([], [], color=LIMIT, lw=2.5, ls="--", label="clearance limit (on its colour bar)"),
        Line2D([], [], color=SCALE_POSE, label="home pose, for scale"),
    ]


def _extent(u: np.ndarray, v: np.ndarray) -> tuple[float, float, float, float]:
    du = (u[1] - u[0]) / 2 if len(u) > 1 else 0.05
    dv = (v[1] - v[0]) / 2 if len(v) > 1 else 0.05
    return (u[0] - du, u[-1] + du, v[0] - dv, v[-1] + dv)


def point_size(points: np.ndarray) -> float:
    """A point size for a map's cells [m]: 0.6 of the smallest spacing of the grid (points
    that fill most of their cell and never touch), within [0.02, 0.15] m; 0.05 m for one cell."""
    gaps = [np.diff(np.unique(points[:, k])) for k in range(3)]
    gaps = [g.min() for g in gaps if g.size]
    return float(np.clip(0.6 * min(gaps), 0.02, 0.15)) if gaps else 0.05


def show_map_points(viewer, table, size: float | None = None, config: str | None = None) -> tuple[float, float]:
    """Draw a map's cells as a point cloud in a :class:`~assembler_pin.viz.StackViewer`,
    colored by payload capacity on :data:`~assembler_pin.common.palette.CAPACITY_CMAP` (dark = low,
    yellow = high, the PNG's scale); unreached cells :data:`~assembler_pin.common.palette.UNREACHABLE`.

    Args:
        size: point size [m] (default :func:`point_size` of the grid).

    Returns:
        The capacity range of the color scale (min, max) [kg].
    """
    cols = {c: np.asarray(table.column(c).to_pylist()) for c in ("config", "x", "y", "z", "capacity_kg")}
    name = config if config is not None else cols["config"][0]
    keep = cols["config"] == name
    pts = np.stack([cols["x"][keep], cols["y"][keep], cols["z"][keep]], axis=1).astype(float)
    cap = cols["capacity_kg"][keep].astype(float)
    ok = np.isfinite(cap)
    lo, hi = capacity_range(cap)
    colors = np.tile(np.asarray(UNREACHABLE, dtype=float), (len(pts), 1))
    if ok.any():
        colors[ok] = colormaps[CAPACITY_CMAP]((cap[ok] - lo) / (hi - lo))[:, :3]
    viewer.show_points("capability_map", pts, colors, point_size(pts) if size is None else size)
    return lo, hi


def capacity_bar_html(lo: float, hi: float) -> str:
    """The HTML colour bar of the point cloud: the capacity scale with its ends [kg], and
    the swatch of an unreached cell (placed at the page's bottom left, clear of the legend)."""
    stops = ",".join(hex_color(colormaps[CAPACITY_CMAP](t)) for t in np.linspace(0.0, 1.0, 9))
    grey, ink, edge = hex_color(UNREACHABLE), hex_color(PAGE_INK), hex_color(PAGE_EDGE)
    panel = "rgba({},{},{},0.85)".format(*(round(255 * c) for c in PAGE_PANEL))
    swatch = f"display:inline-block;width:12px;height:12px;background:{grey};margin-right:6px;border:1px solid {edge}"
    return (
        '<div id="assembler-map-colorbar" style="position:absolute;bottom:12px;left:8px;z-index:10;'
        f"background:{panel};padding:6px 8px;border-radius:4px;font:13px sans-serif;color:{ink};"
        'pointer-events:none">payload capacity [kg]'
        f'<div style="height:14px;width:260px;background:linear-gradient(to right,{stops});border:1px solid {edge}">'
        '</div><div style="display:flex;justify-content:space-between;width:262px">'
        f"<span>{lo:.2f}</span><span>{0.5 * (lo + hi):.2f}</span><span>{hi:.2f}</span></div>"
        f'<div style="margin-top:4px"><span style="{swatch}"></span>not reachable</div></div>'
    )


def write_map_page(viewer, table, path, config: str | None = None) -> tuple[float, float]:
    """The map's standalone page: the cells over the stack, a title, and the capacity colour
    bar (:func:`capacity_bar_html`), written atomically to ``path``. Returns the scale [kg]."""
    lo, hi = show_map_points(viewer, table, config=config)
    viewer.set_title(f"Capability map: payload capacity {lo:.2f} (dark) – {hi:.2f} kg (yellow); grey: not reachable")
    html = viewer.static_html().replace("</body>", capacity_bar_html(lo, hi) + "\n</body>", 1)
    write_atomic(path, html)
    return lo, hi
