"""Running a map: cells in batches, in this process or on a Dask cluster, written as they finish.

* Serial (``workers=0``): every batch in this process — no Dask needed.
* Local (default): a ``distributed.LocalCluster`` of worker processes, one thread each,
  sized to the machine; nothing to start.
* Remote (``scheduler="tcp://host:8786"``): the work goes to an existing Dask cluster.

Each worker process builds the models of a configuration once (:func:`~.cells.models_for`)
and reuses them for every batch. Batches are a few cells each, so scheduling costs little
against solves of tens to hundreds of milliseconds. Every finished batch is written at once
as its own Parquet file in the output directory; a rerun reads the finished cells there and
computes only the others, so a crash, a Ctrl-C or a lost worker loses no finished cell (Dask
also retries a batch whose worker died).
"""

from __future__ import annotations

import hashlib
import logging
import math
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from ..config import AssemblerConfig
from ..exceptions import AssemblerError
from .cells import COLUMNS, compute_batch, config_key
from .grid import Cell, Grid

__all__ = ["MapRun", "done_cells", "read_map", "run_map"]

logger = logging.getLogger(__name__)


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
        return (f"MapRun({self.computed} cells computed, {self.skipped} already done, {self.batches} batches on "
                f"{self.workers or 'no'} workers, {self.time_s:.1f} s, "
                f"{self.cells_per_second:.2f} cells/s)")  # fmt: skip


def _need_pyarrow():
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise AssemblerError("maps need pyarrow: pip install 'assembler_pin[maps]'") from None
    return pa, pq


def read_map(out: str | Path):
    """Every row written in a map directory, as a ``pyarrow.Table`` sorted by config and cell
    (an empty table when nothing was written)."""
    pa, pq = _need_pyarrow()
    parts = sorted(Path(out).glob("part-*.parquet"))
    if not parts:
        return pa.table({c: [] for c in COLUMNS})
    table = pa.concat_tables([pq.read_table(p) for p in parts])
    return table.sort_by([("config", "ascending"), ("cell", "ascending")])


def done_cells(out: str | Path) -> set[tuple[str, int]]:
    """(config, cell id) of every cell already written in ``out``."""
    table = read_map(out)
    return set(zip(table.column("config").to_pylist(), table.column("cell").to_pylist(), strict=True))


def _write_part(out: Path, rows: list[dict]) -> None:
    pa, pq = _need_pyarrow()
    table = pa.table({c: [r[c] for r in rows] for c in COLUMNS})
    tag = hashlib.sha1(rows[0]["config"].encode()).hexdigest()[:8]
    path = out / f"part-{tag}-{rows[0]['cell']:09d}.parquet"
    tmp = path.with_suffix(".tmp")
    pq.write_table(table, tmp)
    os.replace(tmp, path)  # a part is either whole or absent


def _client(scheduler: str | None, workers: int):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise AssemblerError(
            "parallel maps need Dask: pip install 'assembler_pin[maps]' (or run with --workers 0)"
        ) from None
    if scheduler:
        try:
            return Client(scheduler, timeout="20s"), None
        except OSError as exc:
            raise AssemblerError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.ERROR)  # fmt: skip
    return Client(cluster), cluster


def run_map(
    grid: Grid,
    configs: Sequence[tuple[str, AssemblerConfig]],
    out: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    batch_size: int | None = None,
    progress: bool = False,
) -> MapRun:
    """Compute every cell of ``grid`` for each configuration not yet in ``out``.

    Args:
        configs: (name, configuration) pairs; a design sweep gives several.
        out: the map directory (created; one Parquet file per finished batch).
        workers: local worker processes (default: the machine's cores; 0: serial, no Dask).
        scheduler: address of an existing Dask scheduler (then ``workers`` is ignored).
        batch_size: cells per task (default: about four tasks per worker, at most 16 cells).
        progress: show a progress bar (tqdm) on stderr.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    done = done_cells(out)
    todo: list[tuple[str, str, list[Cell]]] = []
    skipped = 0
    for name, cfg in configs:
        cells = [c for c in grid.cells() if (name, c.id) not in done]
        skipped += len(grid) - len(cells)
        todo.append((name, config_key(cfg), cells))
    remaining = sum(len(c) for _, _, c in todo)
    n_workers = 0 if scheduler is None and workers == 0 else (workers or os.cpu_count() or 1)
    size = batch_size or max(1, min(16, math.ceil(remaining / (4 * max(n_workers, 1)))))
    batches = [(name, key, cells[k : k + size]) for name, key, cells in todo for k in range(0, len(cells), size)]
    t0 = time.perf_counter()
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=remaining, unit="cell", desc="map")
    try:
        if n_workers == 0 and scheduler is None:
            for name, key, cells in batches:
                rows = compute_batch(key, cells, name)
                _write_part(out, rows)
                if bar is not None:
                    bar.update(len(rows))
        elif batches:
            from distributed import as_completed

            for name in ("distributed", "distributed.batched", "distributed.comm"):
                logging.getLogger(name).setLevel(logging.ERROR)  # a closing cluster logs benign errors
            client, cluster = _client(scheduler, n_workers)
            try:
                if scheduler:
                    n_workers = len(client.scheduler_info()["workers"])
                futures = [client.submit(compute_batch, key, cells, name, pure=False, retries=2)
                           for name, key, cells in batches]  # fmt: skip
                for future in as_completed(futures):
                    rows = future.result()
                    _write_part(out, rows)
                    if bar is not None:
                        bar.update(len(rows))
            finally:
                client.close()
                if cluster is not None:
                    cluster.close()
    finally:
        if bar is not None:
            bar.close()
    run = MapRun(remaining, skipped, len(batches), n_workers, time.perf_counter() - t0, out)
    logger.info("map: %s", run)
    return run
