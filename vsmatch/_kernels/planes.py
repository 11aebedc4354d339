import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS, SERIAL_OPTIONS

#: Channels of the moments volume: weight, then weight times u, v, u^2, u v, v^2, d, u d, v d,
#: d^2, and 1 (summed over a region: its pixel count).
N_MOMENTS = 11


@njit(**SERIAL_OPTIONS)
def take_planes(disp, kept, plane, spread, max_spread, snap, fill, out):
    """``out[y, x]``: the ``plane``'s value where it fits (finite, its region's ``spread``
    at most ``max_spread``) and the pixel is not ``kept`` (with ``fill``) or lies within
    ``snap`` of it; ``disp`` elsewhere."""
    height, width = disp.shape
    for y in range(height):
        for x in range(width):
            p = plane[y, x]
            d = disp[y, x]
            fitted = np.isfinite(p) and spread[y, x] <= max_spread
            take = fitted and ((fill and not kept[y, x]) or abs(d - p) <= snap)
            out[y, x] = p if take else d


@njit(**KERNEL_OPTIONS)
def plane_moments(disp, weight, out):
    """``out[y, x]`` = w (1, u, v, u^2, u v, v^2, d, u d, v d) with u, v the pixel's
    coordinates from the image centre, w = ``weight[y, x]`` (0 where the disparity is not
    finite)."""
    height, width = disp.shape
    cx = np.float32((width - 1) / 2.0)
    cy = np.float32((height - 1) / 2.0)
    for y in prange(height):
        v = np.float32(y) - cy
        for x in range(width):
            d = disp[y, x]
            w = weight[y, x]
            out[y, x, 10] = 1.0
            if not np.isfinite(d) or w <= 0:
                for k in range(10):
                    out[y, x, k] = 0.0
                continue
            u = np.float32(x) - cx
            out[y, x, 0] = w
            out[y, x, 1] = w * u
            out[y, x, 2] = w * v
            out[y, x, 3] = w * u * u
            out[y, x, 4] = w * u * v
            out[y, x, 5] = w * v * v
            out[y, x, 6] = w * d
            out[y, x, 7] = w * u * d
            out[y, x, 8] = w * v * d
            out[y, x, 9] = w * d * d


@njit(**ROW_OPTIONS)
def _plane_values_of_row(sums, min_weight, min_spread, out, spread, width, cx, cy, y):
    """:func:`plane_values` of row ``y``."""
    v0 = y - cy
    m = np.empty((N_MOMENTS, width))
    for x in range(width):
        for k in range(N_MOMENTS):
            m[k, x] = sums[y, x, k]
    for x in range(width):
        w = m[0, x]
        # The threshold a float32 product, as the moments are float32.
        fits = (w > 0) & (not (w < min_weight * np.float32(m[10, x])))
        mu = m[1, x] / w
        mv = m[2, x] / w
        md = m[6, x] / w
        suu = m[3, x] / w - mu * mu
        suv = m[4, x] / w - mu * mv
        svv = m[5, x] / w - mv * mv
        sud = m[7, x] / w - mu * md
        svd = m[8, x] / w - mv * md
        det = suu * svv - suv * suv
        wide_u = suu >= min_spread
        wide_v = svv >= min_spread
        both = wide_u & wide_v & (det > 1e-6 * suu * svv)
        a_both = (sud * svv - svd * suv) / det
        b_both = (svd * suu - sud * suv) / det
        a_u = sud / suu
        b_v = svd / svv
        a = a_both if both else (a_u if wide_u else 0.0)
        b = b_both if both else (0.0 if wide_u else (b_v if wide_v else 0.0))
        value = np.float32(md + a * ((x - cx) - mu) + b * (v0 - mv))
        rest = m[9, x] / w - md * md - a * sud - b * svd
        rest = rest if rest > 0.0 else 0.0
        out[y, x] = value if fits else np.float32(np.nan)
        spread[y, x] = np.float32(np.sqrt(rest)) if fits else np.float32(np.nan)


@njit(**KERNEL_OPTIONS)
def plane_values(sums, min_weight, min_spread, out, spread):
    """The least-squares plane d = a u + b v + c through each pixel's support region
    (``sums``: the moments summed over it), evaluated at the pixel, and the standard
    deviation of the region's disparities about it (``spread``); NaN where the region's
    weight is below ``min_weight`` of its pixels. Where its pixels do not span a plane (the
    variance along u or v below ``min_spread``) a constant is fitted along that axis.

    A row's moments are laid out a moment a line first, and each pixel's cases are
    selects, not branches: the loop over x vectorises (1.7x faster, the same values)."""
    height, width, _ = sums.shape
    cx = (width - 1) / 2.0
    cy = (height - 1) / 2.0
    for y in prange(height):
        _plane_values_of_row(sums, min_weight, min_spread, out, spread, width, cx, cy,
                             np.int64(y))


@njit(inline="always")
def _reach(values, jump, out):
    """out[i] = how far back from i (towards index 0) one may walk along ``values``
    without a step of more than ``jump`` between consecutive finite values (non-finite
    ones are walked over and compared with nothing)."""
    start = 0  # the first index reachable from the current place
    last = np.float32(np.nan)
    last_at = -1
    for i in range(values.shape[0]):
        v = values[i]
        if np.isfinite(v):
            if last_at >= 0 and not (np.abs(v - last) <= jump):
                start = last_at + 1
            last = v
            last_at = i
        out[i] = i - start


@njit(**ROW_OPTIONS)
def _cut_row_arms(arms, disp, jump, y):
    """:func:`cut_arms_at_jumps`' left and right arms of row ``y``."""
    width = disp.shape[1]
    reach = np.empty(width, np.int64)
    _reach(disp[y], jump, reach)
    for x in range(width):
        arms[0, y, x] = min(np.int64(arms[0, y, x]), reach[x])
    _reach(disp[y, ::-1], jump, reach)
    for x in range(width):
        arms[1, y, x] = min(np.int64(arms[1, y, x]), reach[width - 1 - x])


@njit(**ROW_OPTIONS)
def _cut_column_arms(arms, disp, jump, x):
    """:func:`cut_arms_at_jumps`' up and down arms of column ``x``."""
    height = disp.shape[0]
    column = disp[:, x].copy()
    reach = np.empty(height, np.int64)
    _reach(column, jump, reach)
    for y in range(height):
        arms[2, y, x] = min(np.int64(arms[2, y, x]), reach[y])
    _reach(column[::-1], jump, reach)
    for y in range(height):
        arms[3, y, x] = min(np.int64(arms[3, y, x]), reach[height - 1 - y])


@njit(**KERNEL_OPTIONS)
def cut_arms_at_jumps(arms, disp, jump):
    """Shorten each arm (left, right, up, down) to end before the first step of more than
    ``jump`` between the disparities of the kept pixels along it: a support region then
    stays on one surface however alike its colours. Pixels without a kept disparity (NaN:
    rejected by the left-right check) neither end an arm nor count in a step. One scan
    each way per row and per column."""
    height, width = disp.shape
    for y in prange(height):
        _cut_row_arms(arms, disp, jump, np.int64(y))
    for x in prange(width):
        _cut_column_arms(arms, disp, jump, np.int64(x))


@njit(inline="always")
def _line_sums(values, lo_arms, hi_arms, out):
    """``out[i]`` = the sum of ``values`` (n, C) over i - lo_arms[i] .. i + hi_arms[i],
    by running sums in float64."""
    length, channels = values.shape
    sums = np.empty((length + 1, channels))
    sums[0, :] = 0.0
    for i in range(length):
        for k in range(channels):
            sums[i + 1, k] = sums[i, k] + values[i, k]
    for i in range(length):
        lo = i - np.int64(lo_arms[i])
        hi = i + np.int64(hi_arms[i]) + 1
        for k in range(channels):
            out[i, k] = sums[hi, k] - sums[lo, k]


#: Columns the column pass of :func:`region_sums` runs along at once: their running sums
#: side by side in memory (a column alone of the (H, W, C) rows is read with a stride of a
#: whole row). 16 was fastest of 8 to 64 (13.0 -> 8.5 ms on a 942 x 489 image, 11 channels).
COLUMN_BLOCK = 16


@njit(**KERNEL_OPTIONS)
def region_sums(src, arms, scratch, out):
    """``out[y, x]`` = the sum of ``src`` (H, W, C) over pixel (y, x)'s cross region: the
    horizontal arms (left, right) of the pixels on its vertical arm (up, down). Each row,
    then each column of the row sums (``scratch``), :data:`COLUMN_BLOCK` columns at a time,
    each by running sums in float64 (the same sums, in the same order, as one at a time).
    ``out`` may be ``src``: every row is summed into ``scratch`` before a sum is written."""
    height, width, channels = src.shape
    for y in prange(height):
        _line_sums(src[y], arms[0, y], arms[1, y], scratch[y])
    for block in prange((width + COLUMN_BLOCK - 1) // COLUMN_BLOCK):
        x0 = block * COLUMN_BLOCK
        n = min(width, x0 + COLUMN_BLOCK) - x0
        sums = np.empty((height + 1, n, channels))
        sums[0] = 0.0
        for y in range(height):
            for j in range(n):
                for k in range(channels):
                    sums[y + 1, j, k] = sums[y, j, k] + scratch[y, x0 + j, k]
        for y in range(height):
            for j in range(n):
                lo = y - np.int64(arms[2, y, x0 + j])
                hi = y + np.int64(arms[3, y, x0 + j]) + 1
                for k in range(channels):
                    out[y, x0 + j, k] = sums[hi, j, k] - sums[lo, j, k]
