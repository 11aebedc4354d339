"""Tasks in this process, one after the other."""

from __future__ import annotations

from .base import Executor, describe_error


class SerialExecutor(Executor):
    def map_unordered(self, fn, items):
        for item in items:
            try:
                result = fn(item)
            except Exception as exc:  # noqa: BLE001 - a failed task, not a failed batch
                result = describe_error(exc)
            yield item, result
