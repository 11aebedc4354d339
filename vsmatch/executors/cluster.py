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
import threading
import time

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
ADDRESS = re.compile(r"^(?:([a-z0-9]+)://)?(\[[0-9a-fA-F:.]+\]|[^\s:/\[\]]+):(\d{1,5})$")
#: The protocols a scheduler is reached by here (Dask's UCX needs a package of its own).
PROTOCOLS = ("tcp", "tls")


def check_scheduler(scheduler: str) -> None:
    """Refuse an address that is neither ``local:N`` nor ``[tcp|tls://]HOST:PORT`` with a
    port from 1 to 65535."""
    if parse_local(scheduler) is not None:
        return
    match = ADDRESS.match(scheduler)
    if not match:
        raise ExecutorError(f"--scheduler {scheduler}: expected tcp://HOST:PORT or local:N")
    protocol, _, port = match.groups()
    if protocol is not None and protocol not in PROTOCOLS:
        raise ExecutorError(f"--scheduler {scheduler}: the protocol {protocol}:// is not "
                            f"supported (use {' or '.join(p + '://' for p in PROTOCOLS)})")
    if not 1 <= int(port) <= 65535:
        raise ExecutorError(f"--scheduler {scheduler}: the port {int(port)} is not in "
                            "1..65535")


def _patience(distributed) -> float:
    """Seconds to wait for a scheduler's answer or for a worker: Dask's connect timeout
    (``DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT``, 30 s by default)."""
    import dask

    return float(dask.utils.parse_timedelta(
        dask.config.get("distributed.comm.timeouts.connect"), default="seconds"))


def _connect(distributed, scheduler: str, seconds: float):
    """A client of ``scheduler``, within ``seconds``: Dask's own client waits forever on a
    port that accepts and never answers, so it connects in a thread of its own that is
    given up after the time (a daemon thread: it does not hold the process)."""
    box: dict = {}

    def connect() -> None:
        try:
            box["client"] = distributed.Client(scheduler, timeout=seconds)
        except BaseException as exc:  # noqa: BLE001 - handed to the caller
            box["error"] = exc

    thread = threading.Thread(target=connect, name="vsmatch-dask-connect", daemon=True)
    thread.start()
    thread.join(seconds + 1)
    if thread.is_alive():
        raise TimeoutError(f"no answer in {seconds:g} s")
    if "error" in box:
        raise box["error"]
    return box["client"]


#: How often a batch looks at the cluster while no task completes (seconds).
POLL_SECONDS = 1.0


class ClusterExecutor(Executor):
    def __init__(self, scheduler: str):
        check_scheduler(scheduler)
        workers = parse_local(scheduler)
        distributed = _import_distributed()
        self._cluster = None
        # On a local cluster the workers share this machine's cores; a remote worker
        # uses its machine's (its NUMBA_NUM_THREADS).
        self._threads = share_of_cores(workers) if workers is not None else None
        self._patience = _patience(distributed)
        self._scheduler = scheduler
        # Dask's own log lines (tracebacks of lost connections) stay off stderr: the
        # batch says what happened in one line. They stay off for the rest of the process:
        # a lost cluster's leftovers (asyncio's "Task exception was never retrieved" for
        # a fetch given up) are collected and logged after the executor is closed.
        _quiet_dask_logs()
        try:
            if workers is not None:
                self._cluster = _local_cluster(distributed, workers)
                self._client = distributed.Client(self._cluster)
            else:
                self._client = _connect(distributed, scheduler, self._patience)
        except (OSError, TimeoutError, RuntimeError, ValueError) as exc:
            self.close()
            what = ("could not start a local Dask cluster" if workers is not None
                    else f"cannot reach the Dask scheduler at {scheduler}")
            raise ExecutorError(f"{what} ({describe_error(exc)})") from None
        try:
            self._client.wait_for_workers(1, timeout=self._patience)
        except (OSError, TimeoutError) as exc:
            self.close()
            if isinstance(exc, TimeoutError):
                raise ExecutorError(f"the Dask scheduler at {scheduler} has no worker "
                                    f"(waited {self._patience:g} s); start one with "
                                    f"'dask worker {scheduler}'") from None
            raise ExecutorError(f"lost the Dask scheduler at {scheduler} "
                                f"({describe_error(exc)})") from None

    def close(self) -> None:
        for part in (getattr(self, "_client", None), self._cluster):
            if part is not None:
                try:
                    part.close(timeout=self._patience)
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
        pending = set(futures)
        workerless_since = None
        try:
            while pending:
                try:
                    done, pending = distributed.wait(pending, timeout=POLL_SECONDS,
                                                     return_when="FIRST_COMPLETED")
                except TimeoutError:
                    done = set()
                except lost as exc:
                    raise self._lost(exc) from None
                if not done:
                    workerless_since = self._check_workers(workerless_since, lost)
                    continue
                workerless_since = None
                for future in done:
                    try:
                        result = self._result(future, lost)
                    except lost as exc:
                        raise self._lost(exc) from None
                    except distributed.KilledWorker:
                        result = "every worker that ran it died (out of memory?)"
                    except Exception as exc:  # noqa: BLE001 - a failed task, not the batch
                        result = describe_error(exc)
                    yield index[future.key], result
        finally:
            try:
                self._client.cancel(futures)
            except Exception:  # noqa: BLE001 - the cluster may be gone already
                pass

    def _result(self, future, lost):
        """A finished task's result. It is fetched from the worker that holds it: if that
        worker dies meanwhile, the task runs again, so the wait is watched like any."""
        since = None
        while True:
            try:
                return future.result(timeout=POLL_SECONDS)
            except TimeoutError:
                since = self._check_workers(since, lost)

    def _check_workers(self, since: float | None, lost) -> float | None:
        """While no task completes: when the cluster has had no worker for the whole
        patience, the batch stops (its tasks would wait forever). The time the cluster
        has been without workers, or None."""
        try:
            workers = len(self._client.nthreads())
        except lost as exc:
            raise self._lost(exc) from None
        if workers:
            return None
        now = time.monotonic()
        if since is None:
            return now
        if now - since > self._patience:
            raise ExecutorError(f"the Dask cluster has had no worker for "
                                f"{self._patience:g} s; outputs written so far are "
                                "complete")
        return since

    def _lost(self, exc: BaseException) -> ExecutorError:
        # Dask's message lists every cancelled task after "Futures:": cut there.
        reason = describe_error(exc).split(" Futures: [")[0][:200]
        return ExecutorError(f"lost the Dask cluster ({reason}); outputs written so far are "
                             "complete")


#: Loggers whose lines Dask and its event loop print on a lost connection.
DASK_LOGGERS = ("distributed", "tornado", "asyncio")


def _quiet_dask_logs() -> None:
    """Raise Dask's loggers (and those below them, which Dask's config gives levels of
    their own) to CRITICAL."""
    names = [name for name in logging.root.manager.loggerDict
             if name.split(".")[0] in DASK_LOGGERS]
    for name in {*DASK_LOGGERS, *names}:
        logging.getLogger(name).setLevel(logging.CRITICAL)
