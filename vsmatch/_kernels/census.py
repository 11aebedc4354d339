import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS


@njit(**ROW_OPTIONS)
def _census_of_row(padded, half_w, half_h, band, out, y):
    """:func:`census_transform` of row ``y``."""
    width = out.shape[1]
    window_w = 2 * half_w + 1
    count = (2 * half_h + 1) * window_w
    bits = np.zeros(width, dtype=np.uint64)
    centre = np.empty(width, dtype=np.float32)
    centre_row = padded[y + half_h, half_w:half_w + width]
    for x in range(width):
        centre[x] = centre_row[x] - band
    # The neighbours in row-major order, eight a pass over the row, the rest one a pass:
    # the bits are loaded and stored once for eight comparisons (one neighbour a pass, a
    # 9 x 7 window moved them through the cache 62 times; the kernel 1.4-1.7x slower).
    rows = np.empty(8, np.int64)
    firsts = np.empty(8, np.int64)
    k = 0
    while k < count:
        taken = 0
        while taken < 8 and k < count:
            dy, dx = k // window_w, k % window_w
            if not (dy == half_h and dx == half_w):
                rows[taken] = y + dy
                firsts[taken] = dx
                taken += 1
            k += 1
        if taken == 8:
            # Slices that start at the neighbour: indexes Numba knows are >= 0.
            n0 = padded[rows[0], firsts[0]:firsts[0] + width]
            n1 = padded[rows[1], firsts[1]:firsts[1] + width]
            n2 = padded[rows[2], firsts[2]:firsts[2] + width]
            n3 = padded[rows[3], firsts[3]:firsts[3] + width]
            n4 = padded[rows[4], firsts[4]:firsts[4] + width]
            n5 = padded[rows[5], firsts[5]:firsts[5] + width]
            n6 = padded[rows[6], firsts[6]:firsts[6] + width]
            n7 = padded[rows[7], firsts[7]:firsts[7] + width]
            for x in range(width):
                c = centre[x]
                bits[x] = ((bits[x] << np.uint64(8))
                           | (np.uint64(n0[x] < c) << np.uint64(7))
                           | (np.uint64(n1[x] < c) << np.uint64(6))
                           | (np.uint64(n2[x] < c) << np.uint64(5))
                           | (np.uint64(n3[x] < c) << np.uint64(4))
                           | (np.uint64(n4[x] < c) << np.uint64(3))
                           | (np.uint64(n5[x] < c) << np.uint64(2))
                           | (np.uint64(n6[x] < c) << np.uint64(1))
                           | np.uint64(n7[x] < c))
        else:
            for j in range(taken):
                neighbour = padded[rows[j], firsts[j]:firsts[j] + width]
                for x in range(width):
                    bits[x] = (bits[x] << np.uint64(1)) | np.uint64(neighbour[x] < centre[x])
    for x in range(width):
        out[y, x] = bits[x]


@njit(**KERNEL_OPTIONS)
def census_transform(padded, half_w, half_h, band, out):
    """One bit per window neighbour q (row-major, centre skipped): [g(q) < g(p) - band].

    ``padded`` is the grey image with ``half_h`` rows and ``half_w`` columns of repeated
    border pixels on each side. Each row is built eight window offsets at a time, so that
    the loop over x (shift, compare, or) vectorises.
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


@njit(**ROW_OPTIONS)
def _like_of_row(padded, half_w, half_h, threshold, out, y):
    """:func:`like_neighbours` of row ``y``: a neighbour a pass, its largest channel
    difference taken a channel a pass, so that each loop over x vectorises."""
    channels, width = padded.shape[0], out.shape[1]
    window_w = 2 * half_w + 1
    count = (2 * half_h + 1) * window_w
    bits = np.zeros(width, dtype=np.uint64)
    worst = np.empty(width, dtype=np.int16)
    for k in range(count):
        dy, dx = k // window_w, k % window_w
        if dy == half_h and dx == half_w:
            continue
        worst[:] = 0
        for c in range(channels):
            neighbour = padded[c, y + dy, dx:dx + width]
            centre = padded[c, y + half_h, half_w:half_w + width]
            for x in range(width):
                worst[x] = max(worst[x], abs(neighbour[x] - centre[x]))
        for x in range(width):
            bits[x] = (bits[x] << np.uint64(1)) | np.uint64(worst[x] <= threshold)
    for x in range(width):
        out[y, x] = bits[x]


@njit(**KERNEL_OPTIONS)
def like_neighbours(padded, half_w, half_h, threshold, out):
    """One bit per window neighbour q in the census's order (row-major, centre skipped): set
    where every channel of q lies within ``threshold`` grey levels of the centre's.

    ``padded``: the view's channel planes (C, H + 2 half_h, W + 2 half_w), int16, with
    repeated border pixels."""
    height = out.shape[0]
    for y in prange(height):
        _like_of_row(padded, half_w, half_h, threshold, out, np.int64(y))
