import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS

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


@njit(inline="always")
def extremes_near(values, y, x, radius):
    """Smallest and largest finite value of ``values`` within ``radius`` of (y, x) (the
    window cut at the image's edges); inf and -inf where there is none."""
    height, width = values.shape
    low, high = np.float32(np.inf), np.float32(-np.inf)
    for v in range(max(y - radius, 0), min(y + radius + 1, height)):
        for u in range(max(x - radius, 0), min(x + radius + 1, width)):
            value = values[v, u]
            if np.isfinite(value):
                low = min(low, value)
                high = max(high, value)
    return low, high


@njit(inline="always")
def placed(low, high, centre, n_disp, max_band):
    """The band (first candidate, count) holding ``low .. high`` (rounded outwards) within
    ``0 .. n_disp - 1``; where that is more than ``max_band`` candidates, the ``max_band``
    centred on ``centre`` (rounded half to even), and True; (0, 0) where a value is not
    finite. As ``vsmatch.bands.around`` places bands, in float32 (whole numbers)."""
    if not (np.isfinite(low) and np.isfinite(high) and np.isfinite(centre)):
        return np.int32(0), np.int32(0), False
    first = min(max(np.floor(low), 0), n_disp - 1)
    last = min(max(np.ceil(high), 0), n_disp - 1)
    n = last - first + 1
    if n > max_band:
        middle = np.rint(centre) - max_band // 2
        first = min(max(middle, 0), max(n_disp - max_band, 0))
        return np.int32(first), np.int32(min(max_band, n_disp)), True
    return np.int32(first), np.int32(n), False


@njit(**ROW_OPTIONS)
def _bands_of_coarse_row(coarse, labels, valid, widen, n_disp, max_band, lo, count, wide,
                         cy):
    """:func:`bands_from_coarse` of coarse row ``cy`` and the fine rows it stands for."""
    rows, columns = coarse.shape
    height, width = lo.shape
    labelled = labels.shape[0] > 0
    row_lo = np.empty(columns, np.int32)
    row_count = np.empty(columns, np.int32)
    for cx in range(columns):
        own = coarse[cy, cx]
        if not np.isfinite(own):
            low, high = np.float32(np.inf), np.float32(-np.inf)
        elif labelled and labels[cy, cx] != valid:
            low, high = own, own  # rejected, then filled: its own value only
        else:
            low, high = extremes_near(coarse, cy, cx, 1)
        row_lo[cx], row_count[cx], wide[cy, cx] = placed(
            np.float32(2) * low - np.float32(widen), np.float32(2) * high + np.float32(widen),
            np.float32(2) * own, n_disp, max_band)
    # Fine pixel (y, x) takes coarse cell (y // 2, x // 2), the last ones beyond them.
    last_row = height if cy == rows - 1 else min(height, 2 * cy + 2)
    for y in range(2 * cy, last_row):
        for x in range(width):
            cx = min(x // 2, columns - 1)
            lo[y, x] = row_lo[cx]
            count[y, x] = row_count[cx]


@njit(**KERNEL_OPTIONS)
def bands_from_coarse(coarse, labels, valid, widen, n_disp, max_band, lo, count, wide):
    """The bands (``lo``, ``count``: int32, the fine level's shape) from the disparity one
    level down (``vsmatch.pyramid.bands_from_coarse`` says which): twice the smallest to
    twice the largest finite disparity of each coarse 3 x 3 neighbourhood (a pixel whose
    ``labels`` is not ``valid``: its own value; an empty ``labels``: every pixel valid),
    ``widen`` more each side, placed as :func:`placed` places them; ``wide`` (coarse
    shape): where the band was cut to ``max_band`` around twice the coarse value."""
    for cy in prange(coarse.shape[0]):
        _bands_of_coarse_row(coarse, labels, valid, widen, n_disp, max_band, lo, count,
                             wide, np.int64(cy))

