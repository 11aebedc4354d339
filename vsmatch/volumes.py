"""Cost volumes kept from one match to the next, where matches repeat.

A full search fills two float32 volumes of height x width x disparities (the costs and a
work volume). Fresh memory costs the operating system time to map and zero on first touch
(measured: 8 ms per 100 MB, about 6 % of ``default``'s time on the twelve standard pairs),
so callers that match pair after pair (``StereoMatcher`` on video, ``vsmatch bench``,
``vsmatch eval``) open :func:`reused` and the volumes are taken from the last match's
memory. Outside it only the stripes of a level share theirs (:func:`shared_by_stripes`),
and nothing is held after the match. Every cell of a volume is written before it is read,
so results are the same bytes either way.
"""

from __future__ import annotations

import math
import threading
from contextlib import contextmanager
from typing import Iterator

import numpy as np


class VolumePool:
    """One float32 buffer per slot, grown to the largest volume asked of it."""

    def __init__(self) -> None:
        self._held: dict[str, np.ndarray] = {}

    def take(self, slot: str, shape: tuple[int, ...]) -> np.ndarray:
        """An uninitialised C-contiguous float32 array of ``shape`` in ``slot``'s buffer;
        valid until ``slot`` is taken again."""
        size = math.prod(shape)
        held = self._held.get(slot)
        if held is None or held.size < size:
            self._held.pop(slot, None)  # free the smaller one before the larger is mapped
            held = self._held[slot] = np.empty(size, np.float32)
        return held[:size].reshape(shape)

    def release(self) -> None:
        """Drop the buffers (their memory returns to the system once unreferenced)."""
        self._held.clear()


_active = threading.local()  # one pool per thread: Dask threads do not share buffers


@contextmanager
def reused(pool: VolumePool | None = None) -> Iterator[VolumePool]:
    """Within the block, this thread's volumes come from ``pool`` (a new one if None)."""
    previous = getattr(_active, "pool", None)
    _active.pool = pool if pool is not None else VolumePool()
    try:
        yield _active.pool
    finally:
        _active.pool = previous


@contextmanager
def shared_by_stripes() -> Iterator[None]:
    """Within the block (one level's stripes), volumes come from the active pool if there
    is one, else from a pool of the block's own, dropped at its end: each stripe takes the
    last one's memory rather than map and zero its own. A stripe holds its two volumes to
    its end either way, so the pool holds no more than the stripes did (at 4x Adirondack,
    two stripes: 0.95 -> 0.73 million pages faulted, the same peak)."""
    if getattr(_active, "pool", None) is not None:
        yield
        return
    with reused():
        yield


def volume(slot: str, shape: tuple[int, ...]) -> np.ndarray:
    """An uninitialised float32 array of ``shape``: from the active pool's ``slot`` inside
    :func:`reused`, else new. Two live volumes need two slots."""
    pool = getattr(_active, "pool", None)
    if pool is None:
        return np.empty(shape, np.float32)
    return pool.take(slot, shape)
