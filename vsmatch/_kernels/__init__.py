"""Numba kernels: contiguous arrays and scalars in, no validation, no allocation policy.

The public functions in the stage modules (``vsmatch.cost``, ``vsmatch.aggregation``,
``vsmatch.disparity``) check and convert their inputs, allocate outputs and call these.
Every kernel is parallel over rows or columns, and each output element is written by
exactly one iteration, so results do not depend on the number of threads.
"""

KERNEL_OPTIONS = dict(parallel=True, cache=True, nogil=True, error_model="numpy")
