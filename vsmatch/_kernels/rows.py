from numba import njit

#: Classes :func:`dealt_row` deals out: rows y and y + CLASSES are in one class.
CLASSES = 16


@njit(inline="always")
def dealt_row(i, count):
    """The row that iteration ``i`` of a ``prange(count)`` over rows works on: the rows
    dealt out in :data:`CLASSES` classes (y modulo that), one class after another.

    Numba gives each thread one run of consecutive iterations; where a row's work depends
    on what the image holds there (near depth edges, in blank regions), runs of
    consecutive rows leave one thread working while the others wait. Dealt out, every
    thread's run holds rows from the whole height (a kernel over Middlebury's edges: 1.63
    -> 2.0x from one thread to two). Each row is still worked on by one iteration, so
    the result is the same. Not for kernels whose neighbouring rows read the same rows
    and whose work is even (one thread's rows far apart lose the cache: region voting
    took 1.2x the time on one thread, no less on two)."""
    per = count // CLASSES
    longer = count % CLASSES  # the first classes hold one row more
    first = longer * (per + 1)
    if i < first:
        return (i % (per + 1)) * CLASSES + i // (per + 1)
    rest = i - first
    return (rest % per) * CLASSES + longer + rest // per
