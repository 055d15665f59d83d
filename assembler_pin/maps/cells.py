"""One map cell: is the goal reachable, its optimized max|F|, its payload capacity, what binds.

Runs in the map's worker processes: the models of each configuration are built once per
process (:func:`models_for`) and every batch of cells reuses them.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import time
from collections.abc import Sequence
from typing import TypedDict

import numpy as np

from ..common.labels import leg_label
from ..compliance.ee_stiffness import stiffness
from ..config.schema import AssemblerConfig, config_from_dict
from ..constraints import leg_limit_margins
from ..exceptions import AssemblerError
from ..helper_arm import HelperArmOptions
from ..model.assembler import AssemblerModel
from ..optimize import OptimizeOptions
from ..solver.capacity import PayloadModels, payload_capacity
from ..solver.pipeline import solve
from ..state import StackState
from .grid import Cell

__all__ = [
    "COLUMNS",
    "cell_key",
    "cell_stiffness",
    "compute_batch",
    "compute_cell",
    "config_hash",
    "config_key",
    "models_for",
    "solver_hash",
]

COLUMNS = (
    "config",
    "cell",
    "ix",
    "iy",
    "iz",
    "io",
    "x",
    "y",
    "z",
    "rx",
    "ry",
    "rz",
    "reachable",
    "reason",
    "max_abs_force",
    "capacity_kg",
    "capacity_binding",
    "binding",
    "sag_m",
    "weakest_stiffness_n_per_m",
    "solve_time_s",
    "capacity_time_s",
    "key",
)
"""The columns of a map file, in order. Positions [m], rotation vector [rad], forces [N];
``sag_m``: the EE's sag [m] at the optimized pose (``|sag translation|`` of
:func:`~assembler_pin.compliance.ee_stiffness.stiffness`, legs of ``leg.stiffness``), and
``weakest_stiffness_n_per_m`` its smallest principal stiffness under a pure force [N/m] (both
NaN where no pose was optimized or the stiffness is not defined);
``key``: what the row was computed from (:func:`cell_key`)."""


class _CapacitySettings(TypedDict):
    """Arguments of :func:`~assembler_pin.solver.capacity.payload_capacity`: ``rtol`` and ``max_iterations``."""

    rtol: float
    max_iterations: int


CAPACITY_OPTIONS: _CapacitySettings = {"rtol": 1e-3, "max_iterations": 12}
"""The payload-capacity search settings of every cell (:func:`~assembler_pin.solver.capacity.payload_capacity`)."""

_MODELS: dict[str, PayloadModels] = {}


def config_key(cfg: AssemblerConfig) -> str:
    """A configuration as canonical JSON text: what a worker builds its models from."""
    return json.dumps(cfg.to_dict(), sort_keys=True)


def _sha(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def config_hash(cfg: AssemblerConfig) -> str:
    """A stable hash of a configuration's full content (SHA-256 of :func:`config_key`)."""
    return _sha(config_key(cfg))


def solver_hash() -> str:
    """A stable hash of every solver setting a cell is computed with: the optimizer's and the
    helper arm's options, the capacity search's settings and the row layout."""
    settings = {
        "optimize": dataclasses.asdict(OptimizeOptions()),
        "helper": dataclasses.asdict(HelperArmOptions()),
        "capacity": CAPACITY_OPTIONS,
        "columns": COLUMNS,
    }
    return _sha(json.dumps(settings, sort_keys=True, default=repr))


def cell_key(config_sha: str, solver_sha: str, cell: Cell) -> str:
    """What a row was computed from: the configuration's and the solver's hashes and the cell's
    goal (position [m] and rotation vector [rad], exactly). A row is reused only under its key."""
    goal = ",".join(float(v).hex() for v in (*cell.position, *cell.rotation))
    return _sha(f"{config_sha}|{solver_sha}|{goal}")[:32]


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


def cell_stiffness(am: AssemblerModel, state: StackState) -> tuple[float, float]:
    """The EE's sag [m] and weakest stiffness [N/m] at a pose (NaN when not defined there)."""
    result = stiffness(am, state.plates)
    if not result.success:
        return math.nan, math.nan
    return float(np.linalg.norm(result.sag_translation)), result.weakest_stiffness


def compute_cell(models: PayloadModels, cell: Cell, config_name: str = "") -> dict:
    """The row of one cell (see :data:`COLUMNS`)."""
    am = models.base
    row = {
        "config": config_name,
        "cell": cell.id,
        "ix": cell.index[0],
        "iy": cell.index[1],
        "iz": cell.index[2],
        "io": cell.index[3],
        "x": cell.position[0],
        "y": cell.position[1],
        "z": cell.position[2],
        "rx": cell.rotation[0],
        "ry": cell.rotation[1],
        "rz": cell.rotation[2],
        "reachable": False,
        "reason": "",
        "max_abs_force": math.nan,
        "capacity_kg": math.nan,
        "capacity_binding": "",
        "binding": "",
        "sag_m": math.nan,
        "weakest_stiffness_n_per_m": math.nan,
        "solve_time_s": 0.0,
        "capacity_time_s": 0.0,
        "key": "",
    }
    goal = cell.goal()
    t0 = time.perf_counter()
    result = solve(am, goal)
    row["solve_time_s"] = time.perf_counter() - t0
    state = result.optimized if result.success else None
    if state is not None:
        row["reachable"], row["reason"] = True, ""
        row["max_abs_force"] = state.max_abs_force
        row["binding"] = geometric_binding(am, state)
        row["sag_m"], row["weakest_stiffness_n_per_m"] = cell_stiffness(am, state)
    else:
        row["reason"] = result.message
    if state is None and not result.initial_result.success:
        return row  # no pose at all: kinematically out of reach, whatever the payload
    arm = result.initial_result.plates_if_valid()
    start = None if state is None else state.plates
    opts = CAPACITY_OPTIONS
    cap = payload_capacity(am, goal, models, opts["rtol"], opts["max_iterations"], start, state is None, arm)
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
