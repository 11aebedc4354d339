"""The executor interface."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from typing import Any


class ExecutorError(RuntimeError):
    """Workers or a cluster that failed as a whole; the message is one line and says
    that the outputs written so far are complete."""


class Executor:
    """Runs tasks; see the package docstring."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, exc_type, exc, traceback) -> None:
        if exc_type is not None and issubclass(exc_type, KeyboardInterrupt):
            self.abort()  # Ctrl-C or SIGTERM: the workers end with the batch, now
        else:
            self.close()

    def close(self) -> None:
        """Release workers, connections, clusters this executor started."""

    def abort(self) -> None:
        """Stop at once: end running tasks where that is possible, then release all."""
        self.close()

    def map_unordered(self, fn: Callable[[Any], Any],
                      items: Iterable[Any]) -> Iterator[tuple[Any, Any]]:
        raise NotImplementedError


def describe_error(exc: BaseException) -> str:
    """One line for a failure: the exception's type and its message."""
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def use_threads(threads: int) -> None:
    """Numba's thread count for the calling thread, within what it was started with."""
    import numba

    numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))


def share_of_cores(workers: int) -> int:
    """Numba threads for each of ``workers`` processes on this machine."""
    import os

    return max(1, (os.cpu_count() or 1) // workers)
