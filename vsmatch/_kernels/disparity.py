import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS
from .rows import dealt
from .arms import colour_distance
from .confidence import curve_at
from .lanes import LANES, argmin_chunks
from .views import borrowed

VALID, OCCLUDED, MISMATCHED = 0, 1, 2


@njit(inline="always")
def _argmin(costs, n_disp):
    """The d of the smallest of ``costs[:n_disp]``; ties take the smaller d. Whole vectors
    of LANES first (``_kernels.lanes``), then the rest one by one."""
    chunks = n_disp // LANES
    if chunks > 0:
        best = argmin_chunks(costs, chunks)
        start = chunks * LANES
    else:
        best = 0
        start = 1
    best_cost = costs[best]
    for d in range(start, n_disp):
        c = costs[d]
        if c < best_cost:
            best_cost = c
            best = d
    return best


#: A right pixel that no left pixel's band offers a candidate: fails every check.
NO_DISPARITY = -(1 << 30)


@njit(**KERNEL_OPTIONS)
def winner_takes_all(volume, lo, count, out):
    """Left-view smallest-cost disparity per pixel over its band (``lo + argmin_k``);
    :data:`NO_DISPARITY` where the band is empty."""
    height, width, _ = volume.shape
    for y in prange(height):
        for x in range(width):
            n = np.int64(count[y, x])
            out[y, x] = lo[y, x] + _argmin(volume[y, x], n) if n > 0 else NO_DISPARITY


@njit(**ROW_OPTIONS)
def _both_of_row(volume, lo, count, out_l, out_r, exclude, out_best, out_second, out_mean,
                 n_disp, y, best_r, best_rd):
    """:func:`winner_takes_all_both` of row ``y`` (``n_disp``: past every band's end);
    ``best_r``, ``best_rd``: the right pixels' least costs and their disparities so far,
    ``width + n_disp`` each, infinite and :data:`NO_DISPARITY`."""
    volume, lo, count, out_l, out_r = borrowed(volume), borrowed(lo), borrowed(count), \
        borrowed(out_l), borrowed(out_r)
    out_best, out_second, out_mean = borrowed(out_best), borrowed(out_second), \
        borrowed(out_mean)
    best_r, best_rd = borrowed(best_r), borrowed(best_rd)
    width = volume.shape[1]
    curve = out_best.shape[0] > 0
    # Reversed: right pixel xr is at width - 1 - xr, so x - d lies forward in memory.
    for x in range(width):
        costs = volume[y, x]
        base = np.int64(lo[y, x])
        n = np.int64(count[y, x])
        out_l[y, x] = base + _argmin(costs, n) if n > 0 else NO_DISPARITY
        # Views from the band's place on: indexes Numba knows are >= 0 stay affine.
        cost_r = best_r[width - 1 - x + base:]
        disp_r = best_rd[width - 1 - x + base:]
        for k in range(min(n, x + 1 - base)):
            c = costs[k]
            b = cost_r[k]
            take = c < b
            cost_r[k] = c if take else b
            disp_r[k] = np.int32(base + k) if take else disp_r[k]
    for x in range(width):
        out_r[y, x] = best_rd[width - 1 - x]
    if curve:  # the row's costs are still in cache; apart, the loop above vectorises
        for x in range(width):
            base = np.int64(lo[y, x])
            inside = min(np.int64(count[y, x]), x + 1 - base)
            if inside <= 0:
                out_best[y, x] = out_second[y, x] = out_mean[y, x] = 0.0
                continue
            best, second, mean = curve_at(volume[y, x], out_l[y, x] - base, inside,
                                          exclude)
            out_best[y, x] = best
            out_second[y, x] = second
            out_mean[y, x] = mean


@njit(**KERNEL_OPTIONS)
def winner_takes_all_both(volume, lo, count, out_l, out_r, exclude, out_best, out_second,
                          out_mean):
    """:func:`winner_takes_all` of both views in one pass over the volume, and, when the
    ``out_best``... arrays are not empty, each left pixel's :func:`curve_at` while its
    row is in cache (the confidence's; a second pass over the volume cost as much).

    Right view: argmin_d volume[y, xr + d, d] over the d with xr + d inside the image
    whose band holds d; the right view's candidates of right pixel xr sit on a diagonal,
    (xr + d, d); reading the volume in memory order instead, cost (x, d) is offered to
    right pixel x - d. Each right pixel sees its candidates in increasing d, so ties keep
    the smaller d there too; one offered nothing gets :data:`NO_DISPARITY`. The updates
    are written as selects, without branches, so that they vectorise.
    """
    height, width, _ = volume.shape
    # The bands' largest first candidate plus their largest count: every right pixel's
    # candidates lie below it. Loops, not lo.max(): in a parallel kernel Numba makes an
    # array's max a parallel reduction of its own (this kernel compiled in 6.1 s, 3.4-4.4 s
    # without).
    lo_max = np.int64(0)
    count_max = np.int64(1)
    if height * width > 0:
        lo_max = np.int64(lo[0, 0])
        count_max = np.int64(count[0, 0])
        for y in range(height):
            for x in range(width):
                lo_max = max(lo_max, np.int64(lo[y, x]))
                count_max = max(count_max, np.int64(count[y, x]))
    n_disp = lo_max + count_max
    for y in prange(height):
        best_r = np.full(width + n_disp, np.inf, dtype=volume.dtype)
        best_rd = np.full(width + n_disp, NO_DISPARITY, dtype=np.int32)
        _both_of_row(volume, lo, count, out_l, out_r, exclude, out_best, out_second, out_mean,
                     n_disp, np.int64(y), best_r, best_rd)


@njit(**ROW_OPTIONS)
def _check_row(disp_l, disp_r, n_disp, tolerance, labels, hit, y):
    """:func:`left_right_check` of row ``y`` (``hit``: room for the row's flags)."""
    width = disp_l.shape[1]
    # A left pixel x is MISMATCHED when some right pixel xr = x - dd (0 <= dd < n_disp)
    # has |dd - d_R(xr)| <= tolerance, i.e. points within the tolerance of x: each right
    # pixel marks the left pixels it points at, once, where scanning the candidates of
    # every rejected pixel took up to n_disp steps a pixel (3 % of `fast`).
    hit[:] = False
    for xr in range(width):
        target = np.int64(xr) + np.int64(disp_r[y, xr])
        first = max(target - tolerance, np.int64(xr))  # dd = x - xr >= 0
        stop = min(min(target + tolerance + 1, np.int64(xr) + n_disp), np.int64(width))
        for x in range(first, stop):
            hit[x] = True
    for x in range(width):
        d = disp_l[y, x]
        if d < 0:  # no candidate in the pixel's band
            labels[y, x] = OCCLUDED
        elif x - d >= 0 and abs(d - disp_r[y, x - d]) <= tolerance:
            labels[y, x] = VALID
        else:
            labels[y, x] = MISMATCHED if hit[x] else OCCLUDED


@njit(**KERNEL_OPTIONS)
def left_right_check(disp_l, disp_r, n_disp, tolerance, labels):
    """Label each left pixel VALID, OCCLUDED (no disparity would pass) or MISMATCHED."""
    height, width = disp_l.shape
    for y in prange(height):
        hit = np.empty(width, np.bool_)
        _check_row(disp_l, disp_r, np.int64(n_disp), np.int64(tolerance), labels, hit,
                   np.int64(y))


@njit(**ROW_OPTIONS)
def _fill_row(disp, labels, image, steps_y, steps_x, max_search, invalid, out, y):
    """:func:`fill_rejected` of row ``y``."""
    height, width = disp.shape
    for x in range(width):
        label = labels[y, x]
        if label == VALID:
            out[y, x] = disp[y, x]
            continue
        best = invalid
        best_score = np.inf
        for k in range(steps_y.shape[0]):
            for step in range(1, max_search + 1):
                # np.rint: np.round's halves to even, and faster to compile.
                yy = int(np.rint(y + step * steps_y[k]))
                xx = int(np.rint(x + step * steps_x[k]))
                if yy < 0 or yy >= height or xx < 0 or xx >= width:
                    break
                if labels[yy, xx] == VALID:
                    if label == OCCLUDED:
                        score = disp[yy, xx]
                    else:
                        score = colour_distance(image, y, x, yy, xx)
                    if score < best_score:
                        best_score = score
                        best = disp[yy, xx]
                    break
        out[y, x] = best


@njit(**KERNEL_OPTIONS)
def fill_rejected(disp, labels, image, steps_y, steps_x, max_search, invalid, classes, out):
    """Fill every non-VALID pixel from the first VALID pixel found along each direction.

    Occluded pixels take the lowest candidate (the background); mismatched pixels take
    the candidate whose colour is closest. A pixel with no candidate gets ``invalid``.
    """
    height = disp.shape[0]
    for i in prange(height):  # rows dealt out: only rejected pixels search
        _fill_row(disp, labels, image, steps_y, steps_x, max_search, invalid, out,
                  dealt(i, height, classes))
