"""Tasks in this process, one after the other."""

from __future__ import annotations

from .base import Executor


class SerialExecutor(Executor):
    def map_unordered(self, fn, items):
        for item in items:
            yield item, fn(item)
