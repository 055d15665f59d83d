"""The workspace slice: max |F| over EE positions on a grid in a world plane, and its figure.

Every name is importable from :mod:`assembler_pin.plots` too. Positions in metres (world
frame), forces in newtons.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin
from matplotlib.colors import Normalize
from matplotlib.figure import Figure

from ..common import palette
from ..common.palette import hex_color
from ..exceptions import AssemblerError
from ..model.assembler import AssemblerModel
from ..solver.pipeline import solve
from ..state import StackState

__all__ = [
    "WorkspaceSlice",
    "compute_workspace_slice",
    "default_state_function",
    "plot_workspace_slice",
    "workspace_slice",
]

logger = logging.getLogger(__name__)


@dataclass
class WorkspaceSlice:
    """EE positions on a grid in a plane and the max |F| of the state reached there.

    Attributes:
        plane: the two world axes spanned, e.g. ``"xz"``.
        u, v: grid coordinates along those axes [m] (1-D).
        max_abs_force: (len(v), len(u)) max |F| [N]; NaN where no state was found.
        feasible: (len(v), len(u)) the state found satisfies every constraint.
        rotation: the EE orientation used for every goal (world frame).
        fixed: the coordinate of the third axis [m].
    """

    plane: str
    u: np.ndarray
    v: np.ndarray
    max_abs_force: np.ndarray
    feasible: np.ndarray
    rotation: np.ndarray
    fixed: float

    @property
    def reachable(self) -> np.ndarray:
        """Where a state was found."""
        return np.isfinite(self.max_abs_force)


def default_state_function(am: AssemblerModel) -> Callable[[pin.SE3], StackState | None]:
    """``goal -> state``: the optimized state of :func:`assembler_pin.solver.solve` (falling
    back to its initial state when the optimization gives none). None when no valid state is
    found."""

    def by_solve(goal: pin.SE3) -> StackState | None:
        res = solve(am, goal)
        return res.optimized if res.optimized is not None else res.initial

    return by_solve


_AXES = {"x": 0, "y": 1, "z": 2}


def compute_workspace_slice(
    am: AssemblerModel,
    state_function: Callable[[pin.SE3], StackState | None] | None = None,
    plane: str = "xz",
    u_range: tuple[float, float] = (-0.6, 0.6),
    v_range: tuple[float, float] = (0.3, 1.1),
    resolution: tuple[int, int] = (9, 7),
    fixed: float = 0.0,
    rotation: npt.ArrayLike | None = None,
    progress: bool = True,
) -> WorkspaceSlice:
    """Max |F| over EE positions on a grid in a world plane (orientation held fixed).

    Args:
        state_function: ``goal (pin.SE3) -> StackState | None``; default
            :func:`default_state_function`.
        plane: two of x, y, z (e.g. ``"xz"``, ``"xy"``); the third is held at ``fixed`` [m].
        u_range, v_range: grid extents along the plane's two axes [m].
        resolution: number of points along u and v.
        rotation: EE orientation (3×3, world), default identity.
        progress: show a tqdm progress bar (on stderr).
    """
    from tqdm.auto import tqdm

    if len(plane) != 2 or any(c not in _AXES for c in plane) or plane[0] == plane[1]:
        raise AssemblerError(f"plane must name two different axes of x, y, z (e.g. 'xz'), got {plane!r}")
    fn = state_function or default_state_function(am)
    rot = np.eye(3) if rotation is None else np.asarray(rotation, dtype=float)
    ia, ib = _AXES[plane[0]], _AXES[plane[1]]
    ic = 3 - ia - ib
    u = np.linspace(*u_range, resolution[0])
    v = np.linspace(*v_range, resolution[1])
    force = np.full((v.size, u.size), np.nan)
    feasible = np.zeros((v.size, u.size), dtype=bool)
    with tqdm(total=u.size * v.size, desc=f"workspace {plane}", disable=not progress, leave=False) as bar:
        for r, vv in enumerate(v):
            for c, uu in enumerate(u):
                p = np.zeros(3)
                p[ia], p[ib], p[ic] = uu, vv, fixed
                state = fn(pin.SE3(rot, p))
                if state is not None:
                    force[r, c] = state.max_abs_force
                    feasible[r, c] = state.feasible
                bar.update()
    logger.info("workspace slice %s: %d of %d points reached", plane, int(np.isfinite(force).sum()), force.size)
    return WorkspaceSlice(plane, u, v, force, feasible, rot, fixed)


def plot_workspace_slice(ws: WorkspaceSlice, vmax: float | None = None) -> Figure:
    """Color map of max |F| [N] over the reachable grid points (unreachable: blank, ×)."""
    fig = Figure(figsize=(6.0, 4.8), layout="constrained")
    ax = fig.subplots()
    du = (ws.u[1] - ws.u[0]) / 2 if ws.u.size > 1 else 0.05
    dv = (ws.v[1] - ws.v[0]) / 2 if ws.v.size > 1 else 0.05
    extent = (ws.u[0] - du, ws.u[-1] + du, ws.v[0] - dv, ws.v[-1] + dv)
    finite = ws.max_abs_force[np.isfinite(ws.max_abs_force)]
    top = vmax if vmax is not None else (float(finite.max()) if finite.size else 1.0)
    image = ax.imshow(
        np.ma.masked_invalid(ws.max_abs_force),
        origin="lower",
        extent=extent,
        cmap=palette.CAPACITY_CMAP,
        norm=Normalize(0.0, top),
        aspect="equal",
    )
    uu, vv = np.meshgrid(ws.u, ws.v)
    miss = ~ws.reachable
    ax.plot(uu[miss], vv[miss], "x", color=hex_color(palette.UNREACHABLE), ms=4, label="no state found")
    infeasible = ws.reachable & ~ws.feasible
    if infeasible.any():
        ax.plot(uu[infeasible], vv[infeasible], "o", mfc="none", mec="k", ms=6, label="violates a limit")
    ax.set_xlabel(f"{ws.plane[0]} [m]")
    ax.set_ylabel(f"{ws.plane[1]} [m]")
    third = "xyz".replace(ws.plane[0], "").replace(ws.plane[1], "")
    ax.set_title(f"max |F| over EE positions ({third} = {ws.fixed:g} m)", fontsize=10)
    fig.colorbar(image, ax=ax, label="max |F| [N]")
    if miss.any() or infeasible.any():
        fig.legend(fontsize=8, loc="outside lower center", ncol=2, frameon=False)
    return fig


def workspace_slice(am: AssemblerModel, state_function=None, **kwargs) -> tuple[Figure, WorkspaceSlice]:
    """:func:`compute_workspace_slice` then :func:`plot_workspace_slice`; returns both."""
    ws = compute_workspace_slice(am, state_function, **kwargs)
    return plot_workspace_slice(ws), ws
