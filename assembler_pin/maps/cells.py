"""One map cell: is the goal reachable, its optimized max|F|, its payload capacity, what binds.

Runs in the map's worker processes: the models of each configuration are built once per
process (:func:`models_for`) and every batch of cells reuses them.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Sequence

import numpy as np

from ..capacity import PayloadModels, payload_capacity
from ..config import AssemblerConfig, config_from_dict
from ..constraints import leg_limit_margins
from ..exceptions import AssemblerError
from ..labels import leg_label
from ..model import AssemblerModel
from ..solver import solve
from ..state import StackState
from .grid import Cell

__all__ = ["COLUMNS", "compute_batch", "compute_cell", "config_key", "models_for"]

COLUMNS = ("config", "cell", "ix", "iy", "iz", "io", "x", "y", "z", "rx", "ry", "rz", "reachable", "reason",
           "max_abs_force", "capacity_kg", "capacity_binding", "binding", "solve_time_s",
           "capacity_time_s")  # fmt: skip
"""The columns of a map file, in order. Positions [m], rotation vector [rad], forces [N]."""

_MODELS: dict[str, PayloadModels] = {}


def config_key(cfg: AssemblerConfig) -> str:
    """A configuration as canonical JSON text: what a worker builds its models from."""
    return json.dumps(cfg.to_dict(), sort_keys=True)


def models_for(key: str) -> PayloadModels:
    """The payload models of a configuration, built once per process."""
    if key not in _MODELS:
        _MODELS[key] = PayloadModels(AssemblerModel.from_config(config_from_dict(json.loads(key))))
    return _MODELS[key]


def geometric_binding(am: AssemblerModel, state: StackState) -> str:
    """The kinematic limit closest to binding at a pose, e.g. ``"SP1 leg 2 max_length"``:
    the smallest of the stroke margins (over the stroke) and deflection margins (over the
    limit angle)."""
    leg = am.config.leg
    rows = leg_limit_margins(leg, state.legs.lengths, np.cos(state.legs.deflection), state.legs.rise, 0.0)
    stroke = leg.max_length - leg.min_length
    scores = {
        "min_length": rows[0] / stroke,
        "max_length": rows[1] / stroke,
        "deflection": (leg.max_deflection - state.legs.deflection.max(axis=-1)) / leg.max_deflection,
    }
    kind, table = min(scores.items(), key=lambda kv: float(kv[1].min()))
    j, i = np.unravel_index(int(np.argmin(table)), table.shape)
    return f"{leg_label(int(j), int(i))} {kind}"


def compute_cell(models: PayloadModels, cell: Cell, config_name: str = "") -> dict:
    """The row of one cell (see :data:`COLUMNS`)."""
    am = models.base
    row = {"config": config_name, "cell": cell.id, "ix": cell.index[0], "iy": cell.index[1], "iz": cell.index[2],
           "io": cell.index[3], "x": cell.position[0], "y": cell.position[1], "z": cell.position[2],
           "rx": cell.rotation[0], "ry": cell.rotation[1], "rz": cell.rotation[2], "reachable": False, "reason": "",
           "max_abs_force": math.nan, "capacity_kg": math.nan, "capacity_binding": "", "binding": "",
           "solve_time_s": 0.0, "capacity_time_s": 0.0}  # fmt: skip
    goal = cell.goal()
    t0 = time.perf_counter()
    result = solve(am, goal)
    row["solve_time_s"] = time.perf_counter() - t0
    state = result.optimized if result.success else None
    if state is not None:
        row["reachable"], row["reason"] = True, ""
        row["max_abs_force"] = state.max_abs_force
        row["binding"] = geometric_binding(am, state)
    else:
        row["reason"] = result.message
    if state is None and not result.initial_result.success:
        return row  # no pose at all: kinematically out of reach, whatever the payload
    arm = result.initial_result.plates_if_valid()
    start = None if state is None else state.plates
    cap = payload_capacity(am, goal, models, start=start, configured_failed=state is None, arm_start=arm)
    row["capacity_time_s"] = cap.time_s
    if cap.success:
        row["reachable"] = True  # some payload (possibly lighter than configured) is held there
        row["capacity_kg"], row["capacity_binding"] = cap.capacity_kg, cap.binding
        if state is None:
            row["reason"] = f"reachable only below the configured payload: {result.message}"
    return row


def compute_batch(key: str, cells: Sequence[Cell], config_name: str = "") -> list[dict]:
    """The rows of a batch of cells of one configuration (the unit of work of a map).

    BLAS runs on one thread here, as in Dask's worker processes, so a cell gives the same
    numbers in this process, a local cluster or a remote one (multithreaded BLAS sums in
    another order, and the optimizer can amplify that into another local optimum).
    """
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        raise AssemblerError("maps need threadpoolctl: pip install 'assembler_pin[maps]'") from None
    models = models_for(key)
    with threadpool_limits(limits=1):
        return [compute_cell(models, cell, config_name) for cell in cells]
