import numpy as np
from numba import njit

from . import SERIAL_OPTIONS


@njit(**SERIAL_OPTIONS)
def block_means(values, block, out):
    """``out[i, j]`` = the mean of ``values`` over the ``block`` x ``block`` square at
    (i block, j block), summed in float64 (integers, as the noise operator's responses of
    8-bit views are, sum exactly in any order: NumPy's float32 mean of them is the same)."""
    rows, columns = out.shape
    scale = 1.0 / (block * block)
    for i in range(rows):
        sums = np.zeros(columns)
        for k in range(block):
            line = values[i * block + k]
            for j in range(columns):
                for m in range(block):
                    sums[j] += line[j * block + m]
        for j in range(columns):
            out[i, j] = np.float32(sums[j] * scale)
