"""A picture of a hexapod's stand: its feet and support polygon from above, with the centre of
mass and the margin, and the machine from the side, every leg coloured by its force."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.colors import TwoSlopeNorm
from matplotlib.figure import Figure
from matplotlib.patches import Circle
from scipy.spatial import ConvexHull, QhullError

from ..kinematics import PlateArrays
from ..kinematics.legs import leg_points
from ..model.assembler import AssemblerModel
from ..plots.figures import save
from .stand import HexapodStand

__all__ = ["save_stand_figure", "stand_figure"]


def _top_view(ax, am: AssemblerModel, result: HexapodStand) -> None:
    feet = result.plates[:, 0, :2, 3]
    radius = am.config.plate.radius
    on = feet[~result.lifted]
    for i, (x, y) in enumerate(feet):
        ax.add_patch(Circle((x, y), radius, fill=not result.lifted[i], alpha=0.25, ec="k", lw=0.8))
        ax.annotate(f"foot {i}", (x, y), ha="center", va="center", fontsize=7)
    try:
        hull = on[ConvexHull(on).vertices] if len(on) >= 3 else on
    except QhullError:
        hull = on
    loop = np.vstack([hull, hull[:1]])
    ax.plot(loop[:, 0], loop[:, 1], "k--", lw=0.8, label="hull of the contact feet")
    ax.plot(*result.com[:2], "r*", ms=12, label="centre of mass")
    margin = result.stability_margin_m
    ax.set_title("from above" + ("" if np.isnan(margin) else f": stability margin {1e3 * margin:.0f} mm"))
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize=7, loc="upper right")


def _side_view(ax, am: AssemblerModel, result: HexapodStand):
    leg = am.config.leg
    limit = max(leg.max_tension, leg.max_compression)
    norm = TwoSlopeNorm(0.0, -limit, limit)
    import matplotlib as mpl  # delays matplotlib's colormaps

    cmap = mpl.colormaps["coolwarm"]
    for i in range(result.plates.shape[0]):
        pa = PlateArrays(result.plates[i, :, :3, :3], result.plates[i, :, :3, 3])
        bottom, top = leg_points(am.geometry, pa.R, pa.p)
        for b, t, f in zip(bottom.reshape(-1, 3), top.reshape(-1, 3), result.forces[i].ravel(), strict=True):
            ax.plot([b[0], t[0]], [b[2], t[2]], color=cmap(norm(f)), lw=1.2)
        r = am.config.plate.radius
        for p in pa.p:
            ax.plot([p[0] - r, p[0] + r], [p[2], p[2]], color="0.3", lw=2)
    hc = am.config.hexapod
    top_z = result.plates[:, -1, 2, 3].max() + 0.5 * am.config.plate.thickness
    x = result.plates[:, -1, 0, 3].mean()
    ax.fill_between([x - hc.body_radius, x + hc.body_radius], top_z, top_z + hc.body_thickness, color="0.6")
    ax.axhline(result.plates[:, 0, 2, 3].min(), color="k", lw=1.0)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_title(f"from the side: max|F| {result.max_abs_force:.1f} N")
    return mpl.cm.ScalarMappable(norm=norm, cmap=cmap)


def stand_figure(am: AssemblerModel, result: HexapodStand) -> Figure:
    """The figure (module doc) of the stand ``result`` of the model ``am``."""
    fig = Figure(figsize=(10, 4.5), layout="constrained")
    top, side = fig.subplots(1, 2)
    _top_view(top, am, result)
    mappable = _side_view(side, am, result)
    fig.colorbar(mappable, ax=side, label="leg force [N], tension positive", shrink=0.8)
    verdict = "feasible" if result.feasible else f"{len(result.violations)} violations"
    fig.suptitle(f"{result.forces.shape[0]} stacks, feet {result.feet}, {result.mass:.1f} kg: {verdict}")
    return fig


def save_stand_figure(am: AssemblerModel, result: HexapodStand, path: str | Path) -> Path:
    """Write :func:`stand_figure` to ``path`` (PNG, atomically) and return the path."""
    return save(stand_figure(am, result), path)
