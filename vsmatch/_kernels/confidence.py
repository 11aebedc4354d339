import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS


@njit(**KERNEL_OPTIONS)
def cost_curve(volume, disp, exclude, out_best, out_second, out_mean):
    """Per pixel, from its cost curve ``volume[y, x, :]`` over the candidates inside the
    right view (d <= x): the cost at the chosen disparity ``disp[y, x]``, the smallest
    cost at least ``exclude + 1`` disparities away from it (the second minimum; the best
    cost when there is none), and the mean cost. The candidates outside the view hold
    the volume's largest cost: counting them would make a curve of few candidates look
    sharp."""
    height, width, n_disp = volume.shape
    for y in prange(height):
        for x in range(width):
            d1 = disp[y, x]
            best = volume[y, x, d1]
            second = np.inf
            total = 0.0
            inside = min(n_disp, x + 1)
            for d in range(inside):
                c = volume[y, x, d]
                total += c
                if abs(d - d1) > exclude and c < second:
                    second = c
            out_best[y, x] = best
            out_second[y, x] = second if second < np.inf else best
            out_mean[y, x] = total / inside
