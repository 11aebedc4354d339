"""Numba kernels: contiguous arrays and scalars in, no validation, no allocation policy.

The public functions in the stage modules (``vsmatch.cost``, ``vsmatch.aggregation``,
``vsmatch.disparity``) check and convert their inputs, allocate outputs and call these.
Every kernel but the few small ones (``SERIAL_OPTIONS``) is parallel over rows or columns,
and each output element is written by exactly one iteration, so results do not depend on
the number of threads.
"""

def _without_overlap():
    """A Numba compiler that takes a function's array arguments not to overlap where one is
    written (LLVM's ``noalias``), as Numba takes a parallel loop's: the loops then vectorise
    without run-time overlap checks."""
    from numba.core.compiler import Compiler

    class WithoutOverlap(Compiler):
        def __init__(self, typingctx, targetctx, library, args, return_type, flags, locals):
            flags = flags.copy()
            flags.noalias = True
            super().__init__(typingctx, targetctx, library, args, return_type, flags, locals)

    return WithoutOverlap


KERNEL_OPTIONS = dict(parallel=True, cache=True, nogil=True, error_model="numpy")
#: The serial kernels and the loop bodies below take their array arguments not to overlap
#: where one is written (the callers' promise, kept by every stage: a kernel's output is an
#: array of its own; inputs may share memory, e.g. a curve passed as two features;
#: ``tests/test_kernels_overlap.py`` checks the calls a match makes). Told so, LLVM drops the
#: run-time overlap checks and the scalar copy of each vectorised loop beside them: the 13
#: standard pairs took 4-7 % less time with `fast` and `default`, 3 % with `accurate` (the
#: same bytes), `default`'s kernels compiled one after another 62-68 s against 68-70 s.
WITHOUT_OVERLAP = _without_overlap()
#: Small kernels that stand for a few NumPy passes over a view: one fused loop, compiled
#: without Numba's parallel passes (3-4x faster to compile; each counts in a first run).
SERIAL_OPTIONS = dict(cache=True, nogil=True, error_model="numpy", pipeline_class=WITHOUT_OVERLAP)
#: A parallel kernel's loop body as a function of its own (``for y in prange(n): body(.., y)``):
#: Numba's parallel passes then see a one-line loop and the body compiles once, as serial
#: code, which cut the compiling of `default`'s kernels by a sixth. Not cached on its own:
#: it is compiled into the kernel that calls it. Left inline where the code came out slower
#: (the cost volume's loop without the colour term, the lanes' scanlines, the bands' walks of
#: the row and column scanlines).
ROW_OPTIONS = dict(nogil=True, error_model="numpy", pipeline_class=WITHOUT_OVERLAP)


def cache_is_cold() -> bool:
    """True when no compiled kernel is cached yet for this Python, so the first run
    compiles them all (50-60 s on 2 cores). Numba itself says where it caches: beside the
    sources, or under ~/.cache/numba when the package is installed read-only, or
    NUMBA_CACHE_DIR."""
    import sys
    from pathlib import Path

    from .aggregate import sum_along_arms

    tag = f"py{sys.version_info.major}{sys.version_info.minor}"
    try:
        folder = Path(sum_along_arms._cache.cache_path)
    except AttributeError:  # a Numba without this cache attribute: assume compiled
        return False
    return not any(folder.glob(f"aggregate.*.{tag}.nbi"))
