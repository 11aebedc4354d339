import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS
from .arms import DOWN, LEFT, RIGHT, UP


@njit(inline="always")
def _combined_sum(a, arms_r, which, y, x, d_split, d):
    """Shorter of arm ``a`` of the left pixel and of right pixel (y, x - d)."""
    if d < d_split:
        return min(a, np.int64(arms_r[which, y, x - d]))
    return a


@njit(**KERNEL_OPTIONS)
def sum_along_arms(src, arms_l, arms_r, along_rows, normalise, out):
    """One pass of cross-region aggregation over a (H, W, D) volume, by 1-D running sums.

    ``arms_l``, ``arms_r``: (4, H, W) arm lengths. ``along_rows``: sum ``src`` over each
    pixel's combined horizontal arm (else vertical); at disparity d an arm is the shorter
    of the left pixel's and of the right pixel (y, x - d)'s. ``normalise``: this is the
    second pass of the cross; divide by the number of pixels of the whole region, i.e. the
    running sum of the first pass's arm lengths.
    """
    height, width, n_disp = src.shape
    # Lines are rows or columns; plain int arithmetic keeps Numba's parfor typing integral.
    n_lines = height * along_rows + width * (1 - along_rows)
    length = width * along_rows + height * (1 - along_rows)
    lo_arm = LEFT if along_rows else UP
    hi_arm = RIGHT if along_rows else DOWN
    first_lo = UP if along_rows else LEFT
    first_hi = DOWN if along_rows else RIGHT
    for line in prange(n_lines):
        # Running sums in float64: a float32 sum over a long line would lose the low bits
        # that separate close costs.
        sums = np.empty((length + 1, n_disp))
        counts = np.empty((length + 1, n_disp) if normalise else (1, 1))
        sums[0, :] = 0.0
        counts[0, :] = 0.0
        for i in range(length):
            y = line * along_rows + i * (1 - along_rows)
            x = i * along_rows + line * (1 - along_rows)
            for d in range(n_disp):
                sums[i + 1, d] = sums[i, d] + src[y, x, d]
            if normalise:
                a_lo = np.int64(arms_l[first_lo, y, x])
                a_hi = np.int64(arms_l[first_hi, y, x])
                split = min(n_disp, x + 1)  # d below this has a right pixel
                for d in range(n_disp):
                    counts[i + 1, d] = (counts[i, d] + 1
                                        + _combined_sum(a_lo, arms_r, first_lo, y, x, split, d)
                                        + _combined_sum(a_hi, arms_r, first_hi, y, x, split, d))
        for i in range(length):
            y = line * along_rows + i * (1 - along_rows)
            x = i * along_rows + line * (1 - along_rows)
            a_lo = np.int64(arms_l[lo_arm, y, x])
            a_hi = np.int64(arms_l[hi_arm, y, x])
            split = min(n_disp, x + 1)
            for d in range(n_disp):
                lo = i - _combined_sum(a_lo, arms_r, lo_arm, y, x, split, d)
                hi = i + _combined_sum(a_hi, arms_r, hi_arm, y, x, split, d) + 1
                total = sums[hi, d] - sums[lo, d]
                if normalise:
                    total /= counts[hi, d] - counts[lo, d]
                out[y, x, d] = total
