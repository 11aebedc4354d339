import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS


@njit(**ROW_OPTIONS)
def _noise_blocks_of_row(grey, block, out, i):
    """:func:`noise_block_means` of block row ``i``."""
    columns = out.shape[1]
    scale = 1.0 / (block * block)
    sums = np.zeros(columns)
    for k in range(block):
        y = i * block + k + 1
        up, here, down = grey[y - 1], grey[y], grey[y + 1]
        for j in range(columns):
            for m in range(block):
                x = j * block + m + 1
                response = (_second_difference(up, x) - 2 * _second_difference(here, x)
                            + _second_difference(down, x))
                sums[j] += abs(response)
    for j in range(columns):
        out[i, j] = np.float32(sums[j] * scale)


@njit(inline="always")
def _second_difference(line, x):
    """line[x - 1] - 2 line[x] + line[x + 1], in whole numbers."""
    return np.int64(line[x - 1]) - 2 * np.int64(line[x]) + np.int64(line[x + 1])


@njit(**KERNEL_OPTIONS)
def noise_block_means(grey, block, out):
    """``out[i, j]`` = the mean absolute response of Immerkaer's operator (the 3 x 3
    kernel 1 -2 1 / -2 4 -2 / 1 -2 1) over the ``block`` x ``block`` square at (i block + 1,
    j block + 1) of ``grey`` (whole grey levels; the operator's responses of the interior
    pixels), worked out as it sums them, a row of blocks per iteration. The responses are
    whole numbers, summed exactly in float64 in any order: NumPy's float32 mean of them is
    the same."""
    for i in prange(out.shape[0]):
        _noise_blocks_of_row(grey, block, out, np.int64(i))

