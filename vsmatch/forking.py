"""Matching in a process forked from one that has matched.

Numba's kernels run on its threading layer. Where that is GNU OpenMP (the layer Numba picks
on Linux unless TBB is installed), its threads do not survive ``fork()``: a forked child's
first kernel prints "Terminating: fork() called from a process already using GNU OpenMP"
and the child dies, and a ``multiprocessing.Pool`` (fork is Python's default start method
on Linux before 3.14) waits for its task for ever. Each match notes the process it ran in;
a match in a child forked after that is refused in one line, before any kernel starts, so a
pool gets the error instead of hanging. Bookkeeping only: the method is elsewhere.
"""

from __future__ import annotations

import os

#: The process the last match ran in (None: no match yet).
_matched_in: int | None = None


class ForkedProcessError(RuntimeError):
    """A match in a child forked, after a match, from a process on GNU OpenMP threads."""


def _on_gnu_openmp() -> bool:
    """Whether Numba's threading layer is running, and is GNU OpenMP."""
    import numba

    try:
        layer = numba.threading_layer()
    except ValueError:  # no parallel kernel has run: no layer yet
        return False
    if layer != "omp":
        return False
    from numba.np.ufunc import omppool

    return getattr(omppool, "openmp_vendor", "GNU") == "GNU"


def check_not_forked() -> None:
    """Refuse a match in a child forked after a match on GNU OpenMP threads; else note this
    process as one that matches."""
    global _matched_in
    pid = os.getpid()
    if _matched_in is not None and _matched_in != pid and _on_gnu_openmp():
        raise ForkedProcessError(
            "vsmatch cannot match in a process forked from one that had already matched: "
            "Numba's GNU OpenMP threads do not survive fork(); start the worker processes "
            "with multiprocessing.get_context('spawn') (or 'forkserver'), or before the "
            "first match")
    _matched_in = pid
