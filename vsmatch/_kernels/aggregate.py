import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS
from .arms import DOWN, LEFT, RIGHT, UP


@njit(inline="always")
def combined_arm(arms_l, arms_r, y, x, d, which):
    """Shorter of the arm of left pixel (y, x) and of right pixel (y, x - d)."""
    a = arms_l[y, x, which]
    if x - d >= 0:
        b = arms_r[y, x - d, which]
        if b < a:
            a = b
    return a


@njit(**KERNEL_OPTIONS)
def sum_along_arms(src, arms_l, arms_r, along_rows, normalise, out):
    """One pass of cross-region aggregation over a (H, W, D) volume, by 1-D running sums.

    ``along_rows``: sum ``src`` over each pixel's combined horizontal arm (else vertical).
    ``normalise``: this is the second pass of the cross; divide by the number of pixels of
    the whole region, i.e. the running sum of the first pass's arm lengths.
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
        sums = np.zeros((length + 1, n_disp))
        counts = np.zeros((length + 1, n_disp)) if normalise else np.zeros((1, 1))
        for i in range(length):
            y = line * along_rows + i * (1 - along_rows)
            x = i * along_rows + line * (1 - along_rows)
            for d in range(n_disp):
                sums[i + 1, d] = sums[i, d] + src[y, x, d]
                if normalise:
                    counts[i + 1, d] = (counts[i, d] + 1
                                        + combined_arm(arms_l, arms_r, y, x, d, first_lo)
                                        + combined_arm(arms_l, arms_r, y, x, d, first_hi))
        for i in range(length):
            y = line * along_rows + i * (1 - along_rows)
            x = i * along_rows + line * (1 - along_rows)
            for d in range(n_disp):
                lo = i - combined_arm(arms_l, arms_r, y, x, d, lo_arm)
                hi = i + combined_arm(arms_l, arms_r, y, x, d, hi_arm) + 1
                total = sums[hi, d] - sums[lo, d]
                if normalise:
                    total /= counts[hi, d] - counts[lo, d]
                out[y, x, d] = total
