"""Where the tasks of a batch run: one small interface, one module per kind.

An executor is a context manager with one method, ``map_unordered(fn, items)``, which
runs ``fn(item)`` for every item and yields ``(item, result)`` as each one completes.
``fn`` must be a module-level function (it may be sent to another process or machine)
and should return its errors as messages; an exception it raises anyway becomes that
item's result as ``"ExceptionType: message"``, so one failed task never stops the others.

- ``serial``: in this process, one after the other (``--jobs 1``);
- ``processes``: a pool of local worker processes (``--jobs N``);
- ``cluster``: a Dask distributed cluster (``--scheduler tcp://HOST:PORT`` or
  ``--scheduler local:N``), from the optional ``cluster`` extra.
"""

from __future__ import annotations

from .base import Executor, ExecutorError

__all__ = ["Executor", "ExecutorError", "make_executor"]


def make_executor(jobs: int = 1, scheduler: str | None = None) -> Executor:
    """The executor for ``--jobs`` / ``--scheduler`` (the scheduler wins when given)."""
    if scheduler is not None:
        from .cluster import ClusterExecutor

        return ClusterExecutor(scheduler)
    if jobs > 1:
        from .processes import ProcessExecutor

        return ProcessExecutor(jobs)
    from .serial import SerialExecutor

    return SerialExecutor()
