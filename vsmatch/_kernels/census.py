import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS


@njit(**ROW_OPTIONS)
def _census_of_row(padded, half_w, half_h, band, out, y):
    """:func:`census_transform` of row ``y``."""
    width = out.shape[1]
    bits = np.zeros(width, dtype=np.uint64)
    centre = np.empty(width, dtype=np.float32)
    centre_row = padded[y + half_h, half_w:half_w + width]
    for x in range(width):
        centre[x] = centre_row[x] - band
    for dy in range(-half_h, half_h + 1):
        row = padded[y + half_h + dy]
        for dx in range(-half_w, half_w + 1):
            if dy == 0 and dx == 0:
                continue
            neighbour = row[half_w + dx:half_w + dx + width]
            for x in range(width):
                bits[x] = (bits[x] << np.uint64(1)) | np.uint64(neighbour[x] < centre[x])
    for x in range(width):
        out[y, x] = bits[x]


@njit(**KERNEL_OPTIONS)
def census_transform(padded, half_w, half_h, band, out):
    """One bit per window neighbour q (row-major, centre skipped): [g(q) < g(p) - band].

    ``padded`` is the grey image with ``half_h`` rows and ``half_w`` columns of repeated
    border pixels on each side. Each row is built one window offset at a time, so that the
    loop over x (shift, compare, or) vectorises.
    """
    height = out.shape[0]
    for y in prange(height):
        _census_of_row(padded, half_w, half_h, band, out, np.int64(y))


@njit(inline="always")
def popcount64(v):
    # SWAR bit count; LLVM turns it into a single popcnt instruction.
    v = v - ((v >> np.uint64(1)) & np.uint64(0x5555555555555555))
    v = (v & np.uint64(0x3333333333333333)) + ((v >> np.uint64(2)) & np.uint64(0x3333333333333333))
    v = (v + (v >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return (v * np.uint64(0x0101010101010101)) >> np.uint64(56)
