import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS


@njit(**KERNEL_OPTIONS)
def census_transform(grey, half_w, half_h, band, out):
    """One bit per window neighbour q (row-major, centre skipped): [g(q) < g(p) - band].

    Pixels outside the image repeat the nearest border pixel.
    """
    height, width = grey.shape
    for y in prange(height):
        for x in range(width):
            centre = grey[y, x] - band
            bits = np.uint64(0)
            for dy in range(-half_h, half_h + 1):
                yy = min(max(y + dy, 0), height - 1)
                for dx in range(-half_w, half_w + 1):
                    if dy == 0 and dx == 0:
                        continue
                    xx = min(max(x + dx, 0), width - 1)
                    bits = bits << np.uint64(1)
                    if grey[yy, xx] < centre:
                        bits = bits | np.uint64(1)
            out[y, x] = bits


@njit(inline="always")
def popcount64(v):
    # SWAR bit count; LLVM turns it into a single popcnt instruction.
    v = v - ((v >> np.uint64(1)) & np.uint64(0x5555555555555555))
    v = (v & np.uint64(0x3333333333333333)) + ((v >> np.uint64(2)) & np.uint64(0x3333333333333333))
    v = (v + (v >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return (v * np.uint64(0x0101010101010101)) >> np.uint64(56)
