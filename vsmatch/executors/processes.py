"""Tasks in a pool of local worker processes, each with its share of the cores."""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool

from .base import Executor, ExecutorError, describe_error, share_of_cores, use_threads


class ProcessExecutor(Executor):
    def __init__(self, workers: int):
        # Fresh interpreters, not forks: forking a process whose Numba thread pool is
        # running can kill the child.
        self._pool = ProcessPoolExecutor(max_workers=workers, initializer=use_threads,
                                         initargs=(share_of_cores(workers),),
                                         mp_context=multiprocessing.get_context("spawn"))

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)

    def abort(self) -> None:
        # shutdown() would wait for the running pairs; a killed task leaves only a
        # temporary file, which run_batch removes.
        processes = list((getattr(self._pool, "_processes", None) or {}).values())
        for process in processes:
            process.terminate()
        self._pool.shutdown(wait=True, cancel_futures=True)

    def map_unordered(self, fn, items):
        futures = {self._pool.submit(fn, item): item for item in items}
        try:
            for future in as_completed(futures):
                try:
                    result = future.result()
                except BrokenProcessPool:
                    raise ExecutorError("a worker process died (out of memory?); outputs "
                                        "written so far are complete") from None
                except Exception as exc:  # noqa: BLE001 - a failed task, not a failed batch
                    result = describe_error(exc)
                yield futures[future], result
        finally:
            for future in futures:
                future.cancel()
