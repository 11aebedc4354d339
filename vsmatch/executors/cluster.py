"""Tasks on a Dask distributed cluster (the optional ``cluster`` extra).

``tcp://HOST:PORT`` connects to a running scheduler; ``local:N`` starts a LocalCluster of
N single-threaded worker processes on this machine, each with its share of the cores for
Numba. Every worker must have vsmatch installed and see the inputs and outputs at the
same paths (shared storage). Dask reruns the tasks of a worker that dies on another one;
a task writes its output atomically, so a killed task leaves no partial output.
"""

from __future__ import annotations

import functools
import logging
import os
import re

from .base import Executor, ExecutorError, describe_error, share_of_cores, use_threads

INSTALL_HINT = "pip install 'vsmatch[cluster]'"


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise ExecutorError(f"--scheduler needs Dask's distributed package: "
                            f"{INSTALL_HINT}") from None
    return distributed


def parse_local(scheduler: str) -> int | None:
    """N of ``local:N`` (None for another address); refuses a bad N."""
    if not scheduler.startswith("local:"):
        return None
    text = scheduler[len("local:"):]
    if not text.isdigit() or int(text) < 1:
        raise ExecutorError(f"--scheduler {scheduler}: expected local:N with N >= 1 workers")
    return int(text)


def _local_cluster(distributed, workers: int):
    """N single-threaded worker processes on this machine.

    Dask starts its worker processes with MALLOC_TRIM_THRESHOLD_=65536, which makes glibc
    hand freed memory back to the system at once; the pipeline allocates and frees
    image-sized arrays between stages and then pays page faults for each (measured: a pair
    about 1.4x slower). The workers started here keep glibc's default. Dask also writes
    its worker settings into this process's environment; they are put back afterwards.
    """
    import dask

    environ = {**dask.config.get("distributed.nanny.pre-spawn-environ", {}),
               "MALLOC_TRIM_THRESHOLD_": None}  # None: not set at all
    saved = dict(os.environ)
    try:
        with dask.config.set({"distributed.nanny.pre-spawn-environ": environ}):
            return distributed.LocalCluster(n_workers=workers, threads_per_worker=1,
                                            processes=True, dashboard_address=":0",
                                            silence_logs=logging.ERROR)
    finally:
        os.environ.clear()
        os.environ.update(saved)


def _with_threads(fn, threads: int, item):
    """``fn(item)`` with Numba using ``threads`` threads in this (worker) thread."""
    use_threads(threads)
    return fn(item)


#: A scheduler's address: PROTOCOL://HOST:PORT or HOST:PORT.
ADDRESS = re.compile(r"^([a-z]+://)?(\[[0-9a-fA-F:.]+\]|[^\s:/\[\]]+):\d{1,5}$")


def check_scheduler(scheduler: str) -> None:
    """Refuse an address that is neither ``local:N`` nor ``[PROTOCOL://]HOST:PORT``."""
    if parse_local(scheduler) is None and not ADDRESS.match(scheduler):
        raise ExecutorError(f"--scheduler {scheduler}: expected tcp://HOST:PORT or local:N")


class ClusterExecutor(Executor):
    def __init__(self, scheduler: str):
        check_scheduler(scheduler)
        workers = parse_local(scheduler)
        distributed = _import_distributed()
        self._cluster = None
        # On a local cluster the workers share this machine's cores; a remote worker
        # uses its machine's (its NUMBA_NUM_THREADS).
        self._threads = share_of_cores(workers) if workers is not None else None
        try:
            if workers is not None:
                self._cluster = _local_cluster(distributed, workers)
                self._client = distributed.Client(self._cluster)
            else:
                self._client = distributed.Client(scheduler)
        except (OSError, TimeoutError, RuntimeError) as exc:
            self.close()
            what = ("could not start a local Dask cluster" if workers is not None
                    else f"cannot reach the Dask scheduler at {scheduler}")
            raise ExecutorError(f"{what} ({describe_error(exc)})") from None

    def close(self) -> None:
        for part in (getattr(self, "_client", None), self._cluster):
            if part is not None:
                try:
                    part.close()
                except Exception:  # noqa: BLE001 - closing a broken connection
                    pass

    def map_unordered(self, fn, items):
        distributed = _import_distributed()
        items = list(items)
        if self._threads is not None:
            fn = functools.partial(_with_threads, fn, self._threads)
        # pure=False: each item its own task, run even if an equal one ran before.
        futures = self._client.map(fn, items, pure=False)
        index = {future.key: item for future, item in zip(futures, items)}
        lost = (OSError, TimeoutError, distributed.CancelledError,
                distributed.comm.CommClosedError)
        try:
            for future in distributed.as_completed(futures):
                try:
                    result = future.result()
                except lost as exc:
                    raise ExecutorError(f"lost the Dask cluster ({describe_error(exc)}); outputs "
                                        "written so far are complete") from None
                except distributed.KilledWorker:
                    result = "every worker that ran it died (out of memory?)"
                except Exception as exc:  # noqa: BLE001 - a failed task, not a failed batch
                    result = describe_error(exc)
                yield index[future.key], result
        finally:
            self._client.cancel(futures)
