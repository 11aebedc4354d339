"""Threads: OpenCV's calls between the kernels run on the calling thread. Bookkeeping
only: the method does not depend on it (OpenCV's results are the same on any count).

Numba's kernels run on OpenMP's threads, which wait for the next kernel by spinning for a
while; OpenCV's filters hand part of a view to OpenCV's own pool, whose threads spin too.
Between two kernels the two pools then fight for the same cores, and OpenCV's filters on
views of a few hundred rows gain nothing from them: on this project's 2-core machine, the
13 standard pairs with `fast` at 2 threads took 1.59 and 1.62 s with OpenCV's pool, 1.52
and 1.55 s without (alternating runs, fastest of 3 each).
"""

from __future__ import annotations

import contextlib
import threading
from typing import Iterator

import cv2

_lock = threading.Lock()
_inside = 0  # matches under way in this process
_before: int | None = None  # OpenCV's thread count before the first of them


@contextlib.contextmanager
def opencv_on_this_thread() -> Iterator[None]:
    """OpenCV on the calling thread alone inside the block, its thread count set back
    when the last of the blocks under way in the process (a match per thread) ends."""
    global _inside, _before
    with _lock:
        if _inside == 0:
            _before = cv2.getNumThreads()
            cv2.setNumThreads(1)
        _inside += 1
    try:
        yield
    finally:
        with _lock:
            _inside -= 1
            if _inside == 0:
                cv2.setNumThreads(_before)
