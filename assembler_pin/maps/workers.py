"""What every Dask worker of a map runs under: one BLAS thread, whatever its environment.

A map's numbers must not depend on the machine that computes them: a threaded BLAS sums in
another order, and the optimizer can turn that into another local optimum
(:mod:`~assembler_pin.common.threads`). :func:`~assembler_pin.maps.cluster.client_for` therefore
registers :class:`OneBlasThread` on every cluster a map runs on (a local one or a remote
scheduler, workers that join later included), and starts local workers with
:data:`ONE_THREAD_ENV` so that a library loaded after the plugin's setup starts with one
thread too. Imported only where Dask is (``distributed`` is an optional dependency).
"""

from __future__ import annotations

from typing import Any

from distributed import WorkerPlugin

from ..common.threads import single_blas_thread

__all__ = ["ONE_THREAD_ENV", "PLUGIN_NAME", "OneBlasThread"]

#: The name the plugin is registered under (registering it again replaces it).
PLUGIN_NAME = "assembler_pin.one_blas_thread"

#: The environment of local worker processes: one thread for OpenBLAS, OpenMP and MKL.
ONE_THREAD_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


class OneBlasThread(WorkerPlugin):
    """Limits every BLAS the worker process has loaded (numpy's and scipy's, loaded first)
    to one thread for the worker's life; the limit is lifted at teardown."""

    idempotent = True

    def __init__(self) -> None:
        self._limiter: Any = None

    def setup(self, worker: Any) -> None:
        self._limiter = single_blas_thread()  # applied on creation, kept until teardown

    def teardown(self, worker: Any) -> None:
        if self._limiter is not None:
            self._limiter.restore_original_limits()
            self._limiter = None
