import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS


@njit(**ROW_OPTIONS)
def _bridges_of_line(sure, unsure, span, agree, along_rows, out, length, line):
    """:func:`bridges_along` of line ``y``."""
    before = np.empty(length, np.int64)
    last = np.int64(-1)
    for i in range(length):
        y = line * along_rows + i * (1 - along_rows)
        x = i * along_rows + line * (1 - along_rows)
        if np.isfinite(sure[y, x]):
            last = i
        before[i] = last
    after = length
    for i in range(length - 1, -1, -1):
        y = line * along_rows + i * (1 - along_rows)
        x = i * along_rows + line * (1 - along_rows)
        if np.isfinite(sure[y, x]):
            after = i
        out[y, x] = np.float32(np.nan)
        first = before[i]
        if not unsure[y, x] or first < 0 or after >= length or after - first > span:
            continue
        ya = line * along_rows + first * (1 - along_rows)
        xa = first * along_rows + line * (1 - along_rows)
        yb = line * along_rows + after * (1 - along_rows)
        xb = after * along_rows + line * (1 - along_rows)
        top = sure[ya, xa]
        bottom = sure[yb, xb]
        if not abs(top - bottom) <= agree:
            continue
        share = (i - first) / max(after - first, 1)
        out[y, x] = np.float32(np.float64(top) + share * np.float64(bottom - top))


@njit(**KERNEL_OPTIONS)
def bridges_along(sure, unsure, span, agree, along_rows, out):
    """``out[y, x]``: for an ``unsure`` pixel, the disparity on the line between the
    nearest pixels of ``sure`` (finite there, NaN elsewhere) before it (at or above it in
    its column; with ``along_rows``, at or left of it in its row) and after it, where they
    are at most ``span`` apart and their disparities differ by at most ``agree``
    (float32); NaN elsewhere. The line is taken in float64 from the float32 difference and
    rounded to float32, as NumPy takes ``top + share * (bottom - top)``."""
    height, width = sure.shape
    n_lines = height * along_rows + width * (1 - along_rows)
    length = width * along_rows + height * (1 - along_rows)
    for line in prange(n_lines):
        _bridges_of_line(sure, unsure, span, agree, along_rows, out, length, np.int64(line))
