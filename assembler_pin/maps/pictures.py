"""Pictures of a map: heatmap slices with the stack drawn for scale, and a Meshcat point cloud."""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from ..exceptions import AssemblerError
from ..model import AssemblerModel
from ..plots import draw_state
from ..state import evaluate_state

__all__ = ["map_heatmaps", "map_slice", "show_map_points"]

_AXIS = {"x": 0, "y": 1, "z": 2}


def map_slice(table, config: str | None = None, orientation: int = 0) -> tuple[str, str, dict[str, np.ndarray]]:
    """The 2-D slice of a map table: (u axis, v axis, columns gridded as (len(v), len(u)) arrays
    plus ``u`` and ``v`` values [m]). The slice is the first configuration (or ``config``),
    the given orientation index, and the first value of the fixed position axis."""
    cols = {c: np.asarray(table.column(c).to_pylist()) for c in table.column_names}
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
    for c in ("reachable", "max_abs_force", "capacity_kg", "sag_m", "weakest_stiffness_n_per_m"):
        grid = np.full((len(v), len(u)), np.nan)
        grid[iv, iu] = cols[c].astype(float)
        out[c] = grid
    return u_axis, v_axis, out


def map_heatmaps(table, am: AssemblerModel, config: str | None = None, orientation: int = 0, title: str = "") -> Figure:
    """Reachability, optimized max|F| [N] and payload capacity [kg] over a 2-D map slice,
    the stack's home pose drawn in each panel for scale; unreached cells are hatched gray."""
    u_axis, v_axis, s = map_slice(table, config, orientation)
    fig = Figure(figsize=(25, 4.8), layout="constrained")
    axes = fig.subplots(1, 5)
    extent = _extent(s["u"], s["v"])
    home = evaluate_state(am, am.home)
    panels = (
        ("reachable", "reachable (a valid pose exists)", ListedColormap(["#d9d9d9", "#2ca02c"]), "reachable"),
        ("max_abs_force", f"optimized max|F| [N] at {am.config.payload.mass:g} kg", colormaps["viridis"], "N"),
        ("capacity_kg", "payload capacity [kg]", colormaps["magma"], "kg"),
        ("sag_m", "EE sag under gravity and payload [m]", colormaps["cividis"], "m"),
        ("weakest_stiffness_n_per_m", "weakest EE stiffness [N/m]", colormaps["plasma"], "N/m"),
    )
    for ax, (key, name, cmap, unit) in zip(axes, panels, strict=True):
        data = np.ma.masked_invalid(s[key])
        image = ax.imshow(
            data,
            origin="lower",
            extent=extent,
            cmap=cmap,
            aspect="equal",
            vmin=0 if key == "reachable" else None,
            vmax=1 if key == "reachable" else None,
        )
        ax.set_facecolor("#eeeeee")
        draw_state(ax, home, (_AXIS[u_axis], _AXIS[v_axis]), "#444444", "#222222", "home pose (scale)", alpha=0.5)
        ax.set_xlabel(f"{u_axis} [m]")
        ax.set_ylabel(f"{v_axis} [m]")
        ax.set_title(name, fontsize=10)
        if key != "reachable":
            fig.colorbar(image, ax=ax, shrink=0.8, label=unit)
    axes[0].legend(
        handles=[
            _patch("#2ca02c", "reachable"),
            _patch("#d9d9d9", "not reachable"),
            _line("#444444", "home pose, for scale"),
        ],
        fontsize=8,
        loc="upper right",
    )
    reached = np.nan_to_num(s["reachable"]).astype(bool)
    fig.suptitle(title or f"Capability map: {int(reached.sum())} of {reached.size} cells reachable")
    return fig


def _extent(u: np.ndarray, v: np.ndarray) -> tuple[float, float, float, float]:
    du = (u[1] - u[0]) / 2 if len(u) > 1 else 0.05
    dv = (v[1] - v[0]) / 2 if len(v) > 1 else 0.05
    return (u[0] - du, u[-1] + du, v[0] - dv, v[-1] + dv)


def _patch(color: str, label: str):
    from matplotlib.patches import Patch

    return Patch(color=color, label=label)


def _line(color: str, label: str):
    from matplotlib.lines import Line2D

    return Line2D([], [], color=color, label=label)


def show_map_points(viewer, table, size: float = 0.03, config: str | None = None) -> tuple[float, float]:
    """Draw a map's cells as a point cloud in a :class:`~assembler_pin.viewer.StackViewer`,
    colored by payload capacity (magma, light to dark = low to high); unreached cells light gray.

    Returns:
        The capacity range of the color scale (min, max) [kg].
    """
    cols = {c: np.asarray(table.column(c).to_pylist()) for c in ("config", "x", "y", "z", "capacity_kg")}
    name = config if config is not None else cols["config"][0]
    keep = cols["config"] == name
    pts = np.stack([cols["x"][keep], cols["y"][keep], cols["z"][keep]], axis=1).astype(float)
    cap = cols["capacity_kg"][keep].astype(float)
    ok = np.isfinite(cap)
    lo, hi = (float(cap[ok].min()), float(cap[ok].max())) if ok.any() else (0.0, 1.0)
    colors = np.full(pts.shape, 0.85)
    if ok.any():
        colors[ok] = colormaps["magma_r"]((cap[ok] - lo) / max(hi - lo, 1e-9))[:, :3]
    viewer.show_points("capability_map", pts, colors, size)
    return lo, hi
