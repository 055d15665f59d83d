"""The Dask cluster of a map: a checked scheduler address, a bounded connection, a local cluster.

Addresses are those of Dask's communication backends: ``tcp://HOST:PORT`` (also plain
``HOST:PORT``), ``tls://HOST:PORT`` (security from Dask's configuration,
``distributed.comm.tls``), ``ws://``/``wss://HOST:PORT``, ``ucx://HOST:PORT`` (needs ucx-py)
and ``inproc://...`` (a scheduler in this process). Anything else is refused before any
connection is tried; a scheduler that does not answer within :data:`CONNECT_TIMEOUT_S`, or
has no worker within :data:`WORKERS_TIMEOUT_S`, is reported in one line.

Every worker of a map, local or remote, runs with one BLAS thread
(:class:`~assembler_pin.maps.workers.OneBlasThread`), so that a map's numbers are the same
whatever the machines' thread settings. Local workers run without Dask's statistical profiler
(:data:`LOCAL_WORKER_CONFIG`), which would grow their memory with every cell; a remote
cluster's workers keep their own settings (``distributed.worker.profile.enabled: false`` in
their Dask configuration keeps them flat too).
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import signal
import threading

from ..exceptions import AssemblerError, MapError

__all__ = ["CONNECT_TIMEOUT_S", "LOCAL_WORKER_CONFIG", "WORKERS_TIMEOUT_S", "check_scheduler", "client_for", "stop"]

CONNECT_TIMEOUT_S = 10.0
"""How long a connection to a scheduler is tried [s]."""
WORKERS_TIMEOUT_S = 30.0
"""How long a scheduler without workers is waited for [s]."""

_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")
_LABEL = r"[A-Za-z0-9](?:[A-Za-z0-9-]{0,61}[A-Za-z0-9])?"
_HOST = rf"(?:{_LABEL}(?:\.{_LABEL})*|\[[0-9A-Fa-f:.]{{2,45}}\])"
_HOST_PORT = re.compile(rf"{_HOST}:(\d{{1,5}})", re.ASCII)
_INPROC = re.compile(r"inproc://[\x21-\x7e]{1,200}", re.ASCII)
_IGNORE_SIGINT = "import signal\nsignal.signal(signal.SIGINT, signal.SIG_IGN)\n"
"""Preloaded into each local worker process: Ctrl-C (sent to the whole process group) is
handled by the map's own process, which stops the cluster; workers print nothing."""
_ALLOWED = "tcp://HOST:PORT, tls://, ws://, wss://, ucx://HOST:PORT or inproc://..."


def check_scheduler(address: object, what: str = "scheduler") -> str:
    """``address`` when it is a Dask scheduler address (see the module docstring), else a
    :class:`MapError` naming ``what`` and what is allowed."""
    if not isinstance(address, str):
        raise MapError(f"{what} must be an address such as tcp://10.0.0.5:8786, got {type(address).__name__}")
    shown = repr(address) if len(address) <= 60 else repr(address[:57] + "...")
    if _INPROC.fullmatch(address):
        return address
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    m = _HOST_PORT.fullmatch(rest)
    if scheme not in _SCHEMES or m is None or not 1 <= int(m.group(1)) <= 65535:
        raise MapError(f"{what} {shown} is not a Dask scheduler address: give {_ALLOWED} (PORT 1-65535)")
    return address


def _quiet_dask_logs() -> None:
    for name in ("distributed", "distributed.batched", "distributed.comm", "distributed.client"):
        logging.getLogger(name).setLevel(logging.CRITICAL)  # a closing or unreachable cluster logs benign errors


def client_for(scheduler: str | None, workers: int):
    """(client, local cluster or None): a connection to ``scheduler`` with a worker, or a new
    local cluster of ``workers`` single-threaded processes.

    Raises:
        MapError: the scheduler cannot be reached or has no worker (one line).
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise AssemblerError(
            "parallel maps need Dask: pip install 'assembler_pin[maps]' (or run with --workers 0)"
        ) from None
    _quiet_dask_logs()
    if scheduler is None:
        client, cluster = _local(workers, LocalCluster, Client)
        return _one_blas_thread(client, cluster, "the local cluster"), cluster
    try:
        client = Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S:g}s")
    except Exception as exc:  # any failure to connect is reported in one line
        why = " ".join(str(exc).split())[:120] or type(exc).__name__
        raise MapError(
            f"cannot reach the Dask scheduler at {scheduler} within {CONNECT_TIMEOUT_S:g} s: {why}"
        ) from None
    try:
        client.wait_for_workers(1, timeout=WORKERS_TIMEOUT_S)
    except Exception:  # a timeout, or the scheduler went away
        client.close()
        raise MapError(f"the Dask scheduler at {scheduler} has no worker (waited {WORKERS_TIMEOUT_S:g} s)") from None
    except BaseException:
        client.close()
        raise
    return _one_blas_thread(client, None, f"the Dask scheduler at {scheduler}"), None


def _one_blas_thread(client, cluster, where: str):
    """``client`` once every worker (and every worker that joins later) runs with one BLAS
    thread; a :class:`MapError` when the plugin cannot be registered."""
    from .workers import PLUGIN_NAME, OneBlasThread  # delays distributed

    try:
        client.register_plugin(OneBlasThread(), name=PLUGIN_NAME)
    except Exception as exc:  # e.g. a remote worker without assembler_pin installed
        stop(client, cluster, abort=True)
        why = " ".join(str(exc).split())[:120] or type(exc).__name__
        raise MapError(f"the workers of {where} cannot be set to one BLAS thread ({why})") from None
    except BaseException:
        stop(client, cluster, abort=True)
        raise
    return client


@contextlib.contextmanager
def _sigint_ignored():
    """Ignore Ctrl-C while worker processes are spawned: they inherit the ignored signal and
    never see a Ctrl-C (a Ctrl-C pressed while the cluster starts, a few seconds, is lost)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


#: Dask settings of a local cluster's workers. Dask's statistical profiler samples each worker's
#: stack every 10 ms and keeps an hour of call trees: a map's solves have so many distinct call
#: paths that a worker grew ~0.5 MB a cell with it (and ran ~10 % slower); without it a
#: worker's memory is flat.
LOCAL_WORKER_CONFIG = {"distributed.worker.profile.enabled": False}


def _local(workers: int, local_cluster, client):
    """A local cluster of ``workers`` single-threaded processes (one BLAS thread each, no
    profiler: :data:`LOCAL_WORKER_CONFIG`) and its client."""
    import dask

    from .workers import ONE_THREAD_ENV  # delays distributed

    cluster = None
    try:
        with _sigint_ignored(), dask.config.set(LOCAL_WORKER_CONFIG):  # passed on to the workers
            cluster = local_cluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=":0",  # the scheduler's HTTP routes on a free port, never 8787's warning
                scheduler_kwargs={"dashboard": False},
                silence_logs=logging.CRITICAL,
                preload=[_IGNORE_SIGINT],
                env=dict(ONE_THREAD_ENV),
            )
        return client(cluster), cluster
    except Exception as exc:
        if cluster is not None:
            stop(None, cluster, abort=True)
        why = " ".join(str(exc).split())[:120] or type(exc).__name__
        raise MapError(
            f"cannot start a local Dask cluster of {workers} worker processes ({why}); a script calling "
            "run_map with workers > 0 needs an `if __name__ == '__main__':` guard, or use workers=0"
        ) from None
    except BaseException:
        if cluster is not None:
            stop(None, cluster, abort=True)
        raise


def stop(client, cluster, abort: bool = False, timeout: float = 3.0) -> None:
    """Close ``client`` (its pending tasks are cancelled) and stop ``cluster`` (when local).

    Args:
        abort: the run was interrupted or failed: the local worker processes are killed first
            (they hold no result: parts are written by this process), so a worker deep in a
            solve does not hold the stop up.
        timeout: how long each close may take [s].
    """
    if abort and cluster is not None:
        for nanny in list(getattr(cluster, "workers", {}).values()):
            with contextlib.suppress(OSError, AttributeError, TypeError):
                os.kill(nanny.pid, signal.SIGKILL)
    if client is not None:
        with contextlib.suppress(Exception):
            client.close(timeout=timeout)
    if cluster is not None:
        with contextlib.suppress(Exception):
            cluster.close(timeout=timeout)
