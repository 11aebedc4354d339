import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS

# The coarse 3 x 3 neighbourhood, the pixel's own cell first (it wins ties).
_STEPS_Y = (0, -1, -1, -1, 0, 0, 1, 1, 1)
_STEPS_X = (0, -1, 0, 1, -1, 1, -1, 0, 1)


@njit(**KERNEL_OPTIONS)
def centre_on_likest(coarse, usable, coarse_grey, fine_grey, wide, penalty, width, n_disp,
                     lo, count):
    """For each fine pixel of a ``wide`` coarse cell (its 3 x 3 range holds more than a
    band of ``width``): the band of ``width`` candidates (within ``0 .. n_disp - 1``)
    centred on twice the disparity of the ``usable`` coarse neighbour whose grey level is
    nearest the pixel's, a neighbour other than the pixel's own cell counting ``penalty``
    grey levels farther; written to ``lo`` and ``count`` (left as they are where no
    neighbour is usable). Fine pixel (y, x) lies in coarse cell (y // 2, x // 2)."""
    height, width_px = fine_grey.shape
    rows, columns = coarse.shape
    top = max(n_disp - width, 0)
    for y in prange(height):
        cy = min(y // 2, rows - 1)
        for x in range(width_px):
            cx = min(x // 2, columns - 1)
            if not wide[cy, cx]:
                continue
            grey = fine_grey[y, x]
            best = np.inf
            chosen = np.nan
            for k in range(9):
                ny = min(max(cy + _STEPS_Y[k], 0), rows - 1)
                nx = min(max(cx + _STEPS_X[k], 0), columns - 1)
                if not usable[ny, nx]:
                    continue
                distance = abs(grey - coarse_grey[ny, nx]) + (0.0 if k == 0 else penalty)
                if distance < best:
                    best = distance
                    chosen = coarse[ny, nx]
            if best < np.inf:
                first = np.rint(2.0 * chosen) - width // 2
                lo[y, x] = np.int32(min(max(first, 0.0), top))
                count[y, x] = min(width, n_disp)
