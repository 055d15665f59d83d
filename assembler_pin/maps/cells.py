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
import pinocchio as pin

from ..collision.check import clearance
from ..collision.scene import Obstacle, Scene
from ..common.labels import leg_label
from ..compliance.ee_stiffness import stiffness
from ..config.schema import AssemblerConfig, config_from_dict
from ..constraints import leg_limit_margins
from ..exceptions import AssemblerError
from ..helper_arm import HelperArmOptions
from ..kinematics import PlateArrays
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
    "pose_columns",
    "scene_from_key",
    "scene_hash",
    "scene_key",
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
    "clearance_m",
    "clearance_between",
    "plates_xyzquat",
    "key",
)
"""The columns of a map file, in order. Positions [m], rotation vector [rad], forces [N];
``sag_m``: the EE's sag [m] at the optimized pose (``|sag translation|`` of
:func:`~assembler_pin.compliance.ee_stiffness.stiffness`, legs of ``leg.stiffness``), and
``weakest_stiffness_n_per_m`` its smallest principal stiffness under a pure force [N/m] (both
NaN where no pose was optimized or the stiffness is not defined);
``clearance_m``: the clearance [m] of the cell's pose (:func:`~assembler_pin.collision.check.clearance`:
the smallest distance between two bodies that must not touch, the map's scene included) and
``clearance_between`` those two bodies' names; ``plates_xyzquat``: the cell's pose, the world
poses of plates 0..n as ``x, y, z, qx, qy, qz, qw`` each (7 (n+1) numbers, pinocchio's
``SE3ToXYZQUAT``). The cell's pose is the optimum at the configured payload, or, where only a
lighter payload is held, the capacity's pose; without a pose ``plates_xyzquat`` and
``clearance_between`` are empty and ``clearance_m`` is null (as it is when no pair is checked);
``key``: what the row was computed from (:func:`cell_key`)."""


class _CapacitySettings(TypedDict):
    """Arguments of :func:`~assembler_pin.solver.capacity.payload_capacity`: ``rtol`` and ``max_iterations``."""

    rtol: float
    max_iterations: int


CAPACITY_OPTIONS: _CapacitySettings = {"rtol": 1e-3, "max_iterations": 12}
"""The payload-capacity search settings of every cell (:func:`~assembler_pin.solver.capacity.payload_capacity`)."""

_MODELS: dict[str, PayloadModels] = {}
_SCENES: dict[str, Scene] = {}


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


def scene_key(scene: Scene | None) -> str:
    """A scene as canonical JSON text (``""`` for none): what a worker rebuilds it from, bit for
    bit (every number by its ``repr``, each obstacle's frame as its rotation matrix and its
    translation [m]), and what a map records it by (:func:`scene_hash`)."""
    if scene is None:
        return ""
    obstacles = [
        {
            "kind": o.kind,
            "name": o.name,
            "rotation": o.pose.rotation.tolist(),
            "translation": o.pose.translation.tolist(),
            "size": [float(v) for v in o.size],
            "support": o.support,
        }
        for o in scene.obstacles
    ]
    doc = {"floor_z": scene.floor_z, "standing": list(scene.standing), "obstacles": obstacles}
    return json.dumps(doc, sort_keys=True)


def scene_from_key(key: str) -> Scene | None:
    """The scene of :func:`scene_key` (None for ``""``), built once per process."""
    if not key:
        return None
    if key not in _SCENES:
        doc = json.loads(key)
        frames = [pin.SE3(np.array(o["rotation"]), np.array(o["translation"])) for o in doc["obstacles"]]
        obstacles = tuple(
            Obstacle(o["kind"], o["name"], frame, tuple(o["size"]), bool(o.get("support", False)))
            for o, frame in zip(doc["obstacles"], frames, strict=True)
        )
        _SCENES[key] = Scene(obstacles, doc["floor_z"], tuple(doc["standing"]))
    return _SCENES[key]


def scene_hash(scene: Scene | None) -> str | None:
    """The SHA-256 of a scene's canonical content (:func:`scene_key`), None without a scene."""
    return None if scene is None else _sha(scene_key(scene))


def cell_key(config_sha: str, solver_sha: str, cell: Cell, scene_sha: str | None = None) -> str:
    """What a row was computed from: the configuration's and the solver's hashes, the scene's
    (none: the key of a map without a scene) and the cell's goal (position [m] and rotation
    vector [rad], exactly). A row is reused only under its key."""
    goal = ",".join(float(v).hex() for v in (*cell.position, *cell.rotation))
    scene = "" if scene_sha is None else f"|scene {scene_sha}"
    return _sha(f"{config_sha}|{solver_sha}|{goal}{scene}")[:32]


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


def pose_columns(am: AssemblerModel, plates: PlateArrays | None, scene: Scene | None) -> dict:
    """``clearance_m`` [m], ``clearance_between`` and ``plates_xyzquat`` of a cell's pose
    (world frame; see :data:`COLUMNS`): null, empty and empty without a pose."""
    if plates is None:
        return {"clearance_m": None, "clearance_between": [], "plates_xyzquat": []}
    near = clearance(am, plates, scene)
    found = math.isfinite(near.min_distance)
    xyzquat = [float(v) for k in range(len(plates)) for v in pin.SE3ToXYZQUAT(plates.se3(k))]
    return {
        "clearance_m": float(near.min_distance) if found else None,
        "clearance_between": list(near.between) if found else [],
        "plates_xyzquat": xyzquat,
    }


def compute_cell(models: PayloadModels, cell: Cell, config_name: str = "", scene: Scene | None = None) -> dict:
    """The row of one cell (see :data:`COLUMNS`): every optimization keeps its clearance from
    ``scene`` (obstacles and floor, world frame) when one is given."""
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
        **pose_columns(am, None, scene),
        "key": "",
    }
    goal = cell.goal()
    t0 = time.perf_counter()
    result = solve(am, goal, scene=scene)
    row["solve_time_s"] = time.perf_counter() - t0
    state = result.optimized if result.success else None
    if state is not None:
        row["reachable"], row["reason"] = True, ""
        row["max_abs_force"] = state.max_abs_force
        row["binding"] = geometric_binding(am, state)
        row["sag_m"], row["weakest_stiffness_n_per_m"] = cell_stiffness(am, state)
        row |= pose_columns(am, state.plates, scene)
    else:
        row["reason"] = result.message
    if state is None and not result.initial_result.success:
        return row  # no pose at all: kinematically out of reach, whatever the payload
    arm = result.initial_result.plates_if_valid()
    start = None if state is None else state.plates
    opts = CAPACITY_OPTIONS
    cap = payload_capacity(
        am, goal, models, opts["rtol"], opts["max_iterations"], start, state is None, arm, scene=scene
    )
    row["capacity_time_s"] = cap.time_s
    if cap.success:
        row["reachable"] = True  # some payload (possibly lighter than configured) is held there
        row["capacity_kg"], row["capacity_binding"] = cap.capacity_kg, cap.binding
        if state is None:
            row["reason"] = f"reachable only below the configured payload: {result.message}"
            row |= pose_columns(am, cap.plates, scene)
    return row


def compute_batch(key: str, cells: Sequence[Cell], config_name: str = "", scene: str = "") -> list[dict]:
    """The rows of a batch of cells of one configuration (the unit of work of a map).

    BLAS runs on one thread here, as in Dask's worker processes, so a cell gives the same
    numbers in this process, a local cluster or a remote one (multithreaded BLAS sums in
    another order, and the optimizer can amplify that into another local optimum).

    Args:
        key: the configuration (:func:`config_key`).
        scene: the scene (:func:`scene_key`; ``""`` for none).
    """
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        raise AssemblerError("maps need threadpoolctl: pip install 'assembler_pin[maps]'") from None
    models = models_for(key)
    obstacles = scene_from_key(scene)
    with threadpool_limits(limits=1):
        return [compute_cell(models, cell, config_name, obstacles) for cell in cells]
