"""Capability maps: over a grid of EE goals (× orientations × configurations), where the
stack reaches, its optimized max|F|, its payload capacity, what binds and its clearance
(optionally among a scene's obstacles) — computed in batches on Dask (a local cluster by
default, or an existing one) and written to Parquet.

* :mod:`.grid` — grid and orientation SPECs, cells with stable ids.
* :mod:`.cells` — one cell's numbers (solve, capacity, binding constraint, clearance, pose).
* :mod:`.engine` — :func:`run_map`: serial, local or remote Dask; resumable output.
* :mod:`.store` — the map directory: manifest, Parquet parts, strict reader.
* :mod:`.cluster` — scheduler addresses, bounded connections, the local cluster.
* :mod:`.pictures` — heatmap slices and the Meshcat point cloud.
"""

from ..exceptions import GridError, MapError
from .engine import MapRun, read_map, run_map
from .grid import Cell, Grid, parse_grid, parse_orientations

__all__ = ["Cell", "Grid", "GridError", "MapError", "MapRun", "parse_grid", "parse_orientations", "read_map", "run_map"]
