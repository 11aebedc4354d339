"""Row blocks of a NumPy and OpenCV stage run side by side, one block a thread.

Most of NumPy's and OpenCV's calls use one core; a stage made of them (the confidence's
features, the edges' filters) runs on every core when its rows are cut into blocks that
each read a margin of rows around them. The blocks run on as many threads as Numba's
kernels use (``numba.set_num_threads``), each block's own kernels on one thread. A stage
that splits into blocks must give the same bytes whatever the blocks (its tests say so), so
the result does not depend on the number of threads. Bookkeeping only: what a block
computes is the stage's.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from typing import Callable, Sequence, TypeVar

import numba

T = TypeVar("T")

#: The fewest rows a block is cut to: each block reads its margin again (24 rows for the
#: confidence), so thinner blocks spend more on margins than the threads give back.
MIN_BLOCK_ROWS = 48


def threads() -> int:
    """The threads the calling thread's Numba kernels run on."""
    return numba.get_num_threads()


def block_height(height: int, most: int, least: int = MIN_BLOCK_ROWS) -> int:
    """Rows a block for ``height`` rows: one block a thread, at least ``least`` rows and at
    most ``most`` (the stage's memory bound)."""
    return max(1, min(most, max(least, math.ceil(height / threads()))))


def _on_one_thread(job: Callable[[], T]) -> T:
    # Numba's thread count belongs to the calling thread: a pool's worker would otherwise
    # start every kernel on all the cores, beside the other workers.
    numba.set_num_threads(1)
    return job()


def run_all(jobs: Sequence[Callable[[], T]]) -> list[T]:
    """Each of ``jobs`` called, side by side on :func:`threads` threads (each job's Numba
    kernels on one), their results in order."""
    workers = min(threads(), len(jobs))
    if workers <= 1:
        return [job() for job in jobs]
    with ThreadPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(_on_one_thread, jobs))
