"""Matplotlib figures: the forces of a state, its pose, a trajectory and a workspace slice.

- :mod:`.figures`: the state's force bars and heat maps, its pose in three views, saving.
- :mod:`.trajectory`: a planned trajectory's legs, forces and EE path (:func:`trajectory_plot`).
- :mod:`.workspace`: a slice of the workspace, each cell solved (:func:`workspace_slice`).
"""

from __future__ import annotations

from .figures import (
    INITIAL_COLOR,
    OPTIMIZED_LEG_COLOR,
    OPTIMIZED_PLATE_COLOR,
    draw_state,
    force_bars,
    force_heatmaps,
    leg_flags,
    pose_views,
    save,
)
from .trajectory import LIMIT_VIEW_FRACTION, trajectory_plot
from .workspace import (
    WorkspaceSlice,
    compute_workspace_slice,
    default_state_function,
    plot_workspace_slice,
    workspace_slice,
)

__all__ = [
    "INITIAL_COLOR",
    "LIMIT_VIEW_FRACTION",
    "OPTIMIZED_LEG_COLOR",
    "OPTIMIZED_PLATE_COLOR",
    "WorkspaceSlice",
    "compute_workspace_slice",
    "default_state_function",
    "draw_state",
    "force_bars",
    "force_heatmaps",
    "leg_flags",
    "plot_workspace_slice",
    "pose_views",
    "save",
    "trajectory_plot",
    "workspace_slice",
]
