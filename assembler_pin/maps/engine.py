"""Running a map: cells in batches, in this process or on a Dask cluster, written as they finish.

* Serial (``workers=0``): every batch in this process — no Dask needed.
* Local (default): a ``distributed.LocalCluster`` of worker processes, one thread each,
  sized to the machine; nothing to start.
* Remote (``scheduler="tcp://host:8786"``): the work goes to an existing Dask cluster.

Each worker process builds the models of a configuration once (:func:`~.cells.models_for`)
and reuses them for every batch. Batches are a few cells each, so scheduling costs little
against solves of tens to hundreds of milliseconds; a bounded number of batches is in flight
at a time. Every finished batch is written at once, atomically, as its own Parquet part in
the output directory (:mod:`.store`). A rerun into the same directory reuses a finished cell
only when its goal, its configuration's content, the solver settings and the scene are those
of the run (a directory holding another map is refused), and computes only the others, so a crash,
a Ctrl-C or a lost worker loses no finished cell (Dask also retries a batch whose worker
died). On Ctrl-C the cluster is stopped, no partial part is left, and ``KeyboardInterrupt``
propagates to the caller.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from ..collision.scene import Scene, read_scene
from ..common.progress import ProgressCallback
from ..config.bounds import check_bound
from ..config.schema import AssemblerConfig
from ..exceptions import AssemblerError, MapError
from .cells import COLUMNS, cell_key, compute_batch, config_hash, config_key, scene_hash, scene_key, solver_hash
from .cluster import check_scheduler, client_for, stop
from .grid import Cell, Grid
from .store import (
    MANIFEST,
    check_manifest,
    manifest_for,
    need_pyarrow,
    read_manifest,
    read_parts,
    remove_stale_temporaries,
    schema,
    write_part,
)

__all__ = ["MapRun", "done_cells", "read_map", "run_map"]

logger = logging.getLogger(__name__)

Batch = tuple[str, str, list[Cell]]
"""(config name, config key, cells) of one task."""


@dataclass
class MapRun:
    """What a run did.

    Attributes:
        computed: cells computed in this run; skipped: cells already in the output.
        batches: batches sent; workers: worker processes used (0: serial).
        time_s: wall time [s]; out: the output directory.
    """

    computed: int
    skipped: int
    batches: int
    workers: int
    time_s: float
    out: Path

    @property
    def cells_per_second(self) -> float:
        return self.computed / self.time_s if self.time_s > 0 else math.nan

    def __repr__(self) -> str:
        return (
            f"MapRun({self.computed} cells computed, {self.skipped} already done, {self.batches} batches on "
            f"{self.workers or 'no'} workers, {self.time_s:.1f} s, "
            f"{self.cells_per_second:.2f} cells/s)"
        )


def read_map(out: str | Path):
    """Every row written in a map directory, as a ``pyarrow.Table`` sorted by config and cell
    (an empty table when nothing was written).

    Refuses what ``map`` refuses on a rerun: parts without a manifest, a manifest of another
    version or that is not a regular file, a part that is truncated, of another schema, edited
    after it was written (its checksum), repeats a cell, or holds a configuration or a cell
    the manifest does not have.

    Raises:
        MapError: ``out`` is not a directory, or one of the above (named in one line).
    """
    pa, _ = need_pyarrow()
    path = _out_dir(out, create=False)
    parts = read_parts(path) if path.is_dir() else []
    if not parts:
        return schema().empty_table()
    manifest = read_manifest(path)
    cells = math.prod(manifest["shape"])
    for part, table in parts:
        names = set(table.column("config").to_pylist()) - set(manifest["configs"])
        if names:
            raise MapError(f"map part {part} holds configuration {sorted(names)[0]!r:.60}, not in {MANIFEST}")
        ids = table.column("cell").to_pylist()
        if min(ids) < 0 or max(ids) >= cells:
            raise MapError(
                f"map part {part} holds cell {max(ids) if max(ids) >= cells else min(ids)}, "
                f"outside the map's {cells} cells"
            )
    table = pa.concat_tables([t.replace_schema_metadata(None) for _, t in parts])
    return table.sort_by([("config", "ascending"), ("cell", "ascending")])


def done_cells(out: str | Path) -> set[tuple[str, int]]:
    """(config, cell id) of every cell already written in ``out``."""
    table = read_map(out)
    return set(zip(table.column("config").to_pylist(), table.column("cell").to_pylist(), strict=True))


def _out_dir(out: object, create: bool) -> Path:
    if not isinstance(out, (str, os.PathLike)) or not str(out):
        raise MapError(f"out must be a directory path, got {type(out).__name__}")
    path = Path(out)
    if path.exists() and not path.is_dir():
        raise MapError(f"out {str(path)!r} is a file, not a map directory")
    if create:
        try:
            path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise MapError(f"out {str(path)!r}: cannot create the map directory: {exc.strerror or exc}") from None
    return path


def _check_configs(configs: object) -> list[tuple[str, AssemblerConfig]]:
    if isinstance(configs, (str, bytes, AssemblerConfig)) or not isinstance(configs, Sequence) or not configs:
        raise MapError("configs must be a non-empty list of (name, AssemblerConfig) pairs")
    pairs = []
    for item in configs:
        if not (isinstance(item, tuple) and len(item) == 2 and isinstance(item[1], AssemblerConfig)):
            raise MapError(f"configs must hold (name, AssemblerConfig) pairs, got {type(item).__name__}")
        name = item[0]
        if not isinstance(name, str) or not name.strip() or len(name) > 200 or not name.isprintable():
            raise MapError(f"configs: a name must be a short printable text, got {name!r:.60}")
        pairs.append((name, item[1]))
    if len({n for n, _ in pairs}) != len(pairs):
        raise MapError("configs: every configuration needs its own name")
    return pairs


def _check_args(grid, configs, workers, scheduler, batch_size, progress) -> list[tuple[str, AssemblerConfig]]:
    """The checked configurations; every other argument checked (MapError naming it)."""
    if not isinstance(grid, Grid):
        raise MapError(f"grid must be a Grid (see parse_grid), got {type(grid).__name__}")
    pairs = _check_configs(configs)
    if workers is not None:
        check_bound("map.workers", workers, "workers", MapError)
    if batch_size is not None:
        check_bound("map.batch_size", batch_size, "batch_size", MapError)
    if scheduler is not None:
        check_scheduler(scheduler)
    if progress is not None and not callable(progress):
        raise MapError(f"progress must be None or a callable (done, total, note), got {type(progress).__name__}")
    check_bound("map.cells", len(grid) * len(pairs), "the map's number of cells (grid x configs)", MapError)
    return pairs


def _done_rows(parts, grid: Grid, shas: dict[str, str], solver: str, scene: str | None) -> set[tuple[str, int]]:
    """(config, cell) of every finished row, each checked to be of this map (``scene``: its hash)."""
    done: set[tuple[str, int]] = set()
    for path, table in parts:
        rows = zip(*(table.column(c).to_pylist() for c in ("config", "cell", "key")), strict=True)
        for name, cell, key in rows:
            ok = name in shas and 0 <= cell < len(grid) and key == cell_key(shas[name], solver, grid.cell(cell), scene)
            if not ok:
                where = f"map part {path} holds a row of another map (config {name!r}, cell {cell})"
                raise MapError(f"{where}: delete it (its cells are recomputed on the next run)")
            done.add((name, cell))
    return done


def _batches(grid: Grid, pairs, done: set[tuple[str, int]], size: int) -> Iterator[Batch]:
    for name, cfg in pairs:
        key, batch = config_key(cfg), []
        for cell in grid.iter_cells():
            if (name, cell.id) not in done:
                batch.append(cell)
                if len(batch) == size:
                    yield name, key, batch
                    batch = []
        if batch:
            yield name, key, batch


class _Writer:
    """Writes each finished batch as a part with its rows' keys, and reports progress."""

    def __init__(self, out: Path, shas: dict[str, str], solver: str, scene: str | None, total: int, progress) -> None:
        self.out, self.shas, self.solver, self.scene = out, shas, solver, scene
        self.total, self.progress = total, progress
        self.done = 0
        self.tags = {name: sha[:8] for name, sha in shas.items()}
        if progress is not None:
            progress(0, total, "cells")

    def __call__(self, batch: Batch, rows: list[dict]) -> None:
        name, _, cells = batch
        if [r.get("cell") for r in rows] != [c.id for c in cells] or any(set(r) != set(COLUMNS) for r in rows):
            raise MapError(f"a batch of config {name!r} returned rows that are not those of its cells")
        for row, cell in zip(rows, cells, strict=True):
            row["key"] = cell_key(self.shas[name], self.solver, cell, self.scene)
        write_part(self.out, rows, self.tags[name])
        self.done += len(rows)
        if self.progress is not None:
            self.progress(self.done, self.total, "cells")


def _run_serial(batches: Iterator[Batch], write: _Writer, scene: str) -> int:
    count = 0
    for batch in batches:
        name, key, cells = batch
        write(batch, compute_batch(key, cells, name, scene))
        count += 1
    return count


def _result(future, batch: Batch) -> list[dict]:
    try:
        return future.result()
    except AssemblerError:
        raise
    except Exception as exc:  # a task's failure on a worker, reported in one line
        why = " ".join(str(exc).split())[:160]
        raise MapError(
            f"a batch of config {batch[0]!r} failed on the Dask cluster: {type(exc).__name__}: {why}"
        ) from None


def _run_dask(
    batches: Iterator[Batch], write: _Writer, scheduler: str | None, n_workers: int, scene: str
) -> tuple[int, int]:
    """(batches sent, workers) of a run on Dask; at most two batches per worker in flight
    (``scene``: :func:`~.cells.scene_key`, sent with every batch)."""
    from distributed import as_completed

    client, cluster = client_for(scheduler, n_workers)
    sent = 0
    try:
        if scheduler:
            n_workers = len(client.scheduler_info()["workers"])
        pending: dict[str, Batch] = {}
        queue = as_completed()

        def submit() -> None:
            nonlocal sent
            batch = next(batches, None)
            if batch is not None:
                name, key, cells = batch
                future = client.submit(compute_batch, key, cells, name, scene, pure=False, retries=2)
                pending[future.key] = batch
                queue.add(future)
                sent += 1

        for _ in range(2 * max(n_workers, 1)):
            submit()
        for future in queue:
            batch = pending.pop(future.key)
            write(batch, _result(future, batch))
            future.release()
            submit()
    except BaseException:  # Ctrl-C included: pending tasks cancelled, local workers stopped at once
        stop(client, cluster, abort=True)
        raise
    stop(client, cluster)
    return sent, n_workers


def run_map(
    grid: Grid,
    configs: Sequence[tuple[str, AssemblerConfig]],
    out: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    batch_size: int | None = None,
    progress: ProgressCallback | None = None,
    scene: Scene | str | Path | None = None,
) -> MapRun:
    """Compute every cell of ``grid`` for each configuration not yet in ``out``.

    Args:
        grid: the EE goals (:func:`~.grid.parse_grid`).
        configs: (name, configuration) pairs; a design sweep gives several.
        out: the map directory (created; a manifest and one Parquet part per finished batch).
            A rerun reuses the cells finished there; a directory holding another map (another
            grid, configuration content or solver settings) is refused.
        workers: local worker processes (default: the machine's cores; 0: serial, no Dask;
            bounds key ``map.workers``).
        scheduler: address of an existing Dask scheduler (then ``workers`` is ignored).
        batch_size: cells per task (default: about four tasks per worker, at most 16 cells;
            bounds key ``map.batch_size``).
        progress: called as ``progress(done, total, "cells")`` as parts are written.
        scene: obstacles and floor (:class:`~assembler_pin.collision.scene.Scene`, a scene
            file or its mapping; world frame): every cell's optimizations keep their clearance
            from them, a goal no pose reaches clear of them is an unreachable cell, and every
            cell records its pose's clearance. The scene is part of the map: a directory
            computed with another scene (or none) is refused.

    Raises:
        MapError: an argument (named), the directory, one of its parts, or the cluster.
        SceneError: ``scene`` cannot be read (one line).
        KeyboardInterrupt: on Ctrl-C, after the cluster is stopped; finished parts stay.
    """
    pairs = _check_args(grid, configs, workers, scheduler, batch_size, progress or None)
    obstacles = read_scene(scene)
    out = _out_dir(out, create=True)
    shas = {name: config_hash(cfg) for name, cfg in pairs}
    solver, scene_sha, scene_text = solver_hash(), scene_hash(obstacles), scene_key(obstacles)
    check_manifest(out, manifest_for(grid, shas, solver, scene_sha))
    remove_stale_temporaries(out)
    done = _done_rows(read_parts(out), grid, shas, solver, scene_sha)
    remaining = len(grid) * len(pairs) - len(done)
    n_workers = 0 if scheduler is None and workers == 0 else int(workers or os.cpu_count() or 1)
    size = int(batch_size or max(1, min(16, math.ceil(remaining / (4 * max(n_workers, 1))))))
    batches = _batches(grid, pairs, done, size)
    write = _Writer(out, shas, solver, scene_sha, remaining, progress or None)
    t0 = time.perf_counter()
    if n_workers == 0 and scheduler is None:
        sent = _run_serial(batches, write, scene_text)
    elif remaining:
        sent, n_workers = _run_dask(batches, write, scheduler, n_workers, scene_text)
    else:
        sent = 0
    run = MapRun(write.done, len(done), sent, n_workers, time.perf_counter() - t0, out)
    logger.info("map: %s", run)
    return run
