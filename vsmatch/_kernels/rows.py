import numba
from numba import njit

#: Rows in a block that :func:`dealt` deals out as one, where neighbouring rows read the
#: same rows (region voting's vertical arms).
BLOCK_ROWS = 4


def thread_classes() -> int:
    """The classes a kernel deals its rows into: the threads it runs on, passed in (a
    kernel that asked Numba itself could not be cached)."""
    return numba.get_num_threads()


@njit(inline="always")
def dealt(i, count, classes):
    """The item (a row, or a block of rows) that iteration ``i`` of a ``prange(count)``
    works on: the items dealt out into ``classes`` classes (item modulo ``classes``), one
    class after another; kernels deal into as many classes as they have threads
    (:func:`thread_classes`).

    Numba gives each thread one run of consecutive iterations; where a row's work depends
    on what the image holds there (near depth edges, around rejected pixels), runs of
    consecutive rows leave one thread working while the others wait. Dealt out, thread t
    of n takes items t, t + n, t + 2n, ...: rows from the whole height, near the rows its
    neighbours take at the same time (they share the cache), and on one thread the rows
    in order. Each item is still worked on by one iteration, so the result is the same."""
    per = count // classes
    longer = count % classes  # the first classes hold one item more
    first = longer * (per + 1)
    if i < first:
        return (i % (per + 1)) * classes + i // (per + 1)
    rest = i - first
    return (rest % per) * classes + longer + rest // per
