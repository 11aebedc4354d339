"""Numba kernels: contiguous arrays and scalars in, no validation, no allocation policy.

The public functions in the stage modules (``vsmatch.cost``, ``vsmatch.aggregation``,
``vsmatch.disparity``) check and convert their inputs, allocate outputs and call these.
Every kernel is parallel over rows or columns, and each output element is written by
exactly one iteration, so results do not depend on the number of threads.
"""

KERNEL_OPTIONS = dict(parallel=True, cache=True, nogil=True, error_model="numpy")


def cache_is_cold() -> bool:
    """True when no compiled kernel is cached yet for this Python, so the first run
    compiles them all (20-40 s). Numba keeps its cache beside the sources, or under
    NUMBA_CACHE_DIR."""
    import os
    import sys
    from pathlib import Path

    tag = f"py{sys.version_info.major}{sys.version_info.minor}"
    custom = os.environ.get("NUMBA_CACHE_DIR")
    if custom:
        return not any(Path(custom).rglob(f"aggregate.*.{tag}.nbi"))
    folder = Path(__file__).parent / "__pycache__"
    return not any(folder.glob(f"aggregate.*.{tag}.nbi"))
