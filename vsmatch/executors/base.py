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

    def __exit__(self, *exc_info) -> None:
        self.close()

    def close(self) -> None:
        """Release workers, connections, clusters this executor started."""

    def map_unordered(self, fn: Callable[[Any], Any],
                      items: Iterable[Any]) -> Iterator[tuple[Any, Any]]:
        raise NotImplementedError


def share_of_cores(workers: int) -> int:
    """Numba threads for each of ``workers`` processes on this machine."""
    import os

    return max(1, (os.cpu_count() or 1) // workers)
