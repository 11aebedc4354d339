import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS
from .arms import colour_distance
from .confidence import curve_at

VALID, OCCLUDED, MISMATCHED = 0, 1, 2


@njit(inline="always")
def _argmin(costs, n_disp):
    """The d of the smallest of ``costs[:n_disp]``; ties take the smaller d."""
    best = 0
    best_cost = costs[0]
    for d in range(1, n_disp):
        c = costs[d]
        if c < best_cost:
            best_cost = c
            best = d
    return best


@njit(**KERNEL_OPTIONS)
def winner_takes_all(volume, out):
    """Left-view smallest-cost disparity per pixel: argmin_d volume[y, x, d]."""
    height, width, n_disp = volume.shape
    for y in prange(height):
        for x in range(width):
            out[y, x] = _argmin(volume[y, x], n_disp)


@njit(**KERNEL_OPTIONS)
def winner_takes_all_both(volume, out_l, out_r, exclude, out_best, out_second, out_mean):
    """:func:`winner_takes_all` of both views in one pass over the volume, and, when the
    ``out_best``... arrays are not empty, each left pixel's :func:`curve_at` while its
    row is in cache (the confidence's; a second pass over the volume cost as much).

    Right view: argmin_d volume[y, xr + d, d] over the d with xr + d inside the image; the
    right view's candidates of right pixel xr sit on a diagonal, (xr + d, d); reading
    the volume in memory order instead, cost (x, d) is offered to right pixel x - d. Each
    right pixel sees its candidates in increasing d, so ties keep the smaller d there too.
    The updates are written as selects, without branches, so that they vectorise.
    """
    height, width, n_disp = volume.shape
    curve = out_best.shape[0] > 0
    for y in prange(height):
        best_r = np.empty(width + n_disp, dtype=volume.dtype)
        best_rd = np.empty(width + n_disp, dtype=np.int32)
        # Reversed: right pixel xr is at width - 1 - xr, so x - d lies forward in memory.
        for x in range(width):
            costs = volume[y, x]
            out_l[y, x] = _argmin(costs, n_disp)
            # Views from x's place on: indexes that Numba knows are >= 0 stay affine.
            cost_r = best_r[width - 1 - x:]
            disp_r = best_rd[width - 1 - x:]
            cost_r[0] = costs[0]
            disp_r[0] = 0
            for d in range(1, min(n_disp, x + 1)):
                c = costs[d]
                b = cost_r[d]
                take = c < b
                cost_r[d] = c if take else b
                disp_r[d] = np.int32(d) if take else disp_r[d]
        for x in range(width):
            out_r[y, x] = best_rd[width - 1 - x]
        if curve:  # the row's costs are still in cache; apart, the loop above vectorises
            for x in range(width):
                best, second, mean = curve_at(volume[y, x], out_l[y, x],
                                              min(n_disp, x + 1), exclude)
                out_best[y, x] = best
                out_second[y, x] = second
                out_mean[y, x] = mean


@njit(**KERNEL_OPTIONS)
def left_right_check(disp_l, disp_r, n_disp, tolerance, labels):
    """Label each left pixel VALID, OCCLUDED (no disparity would pass) or MISMATCHED."""
    height, width = disp_l.shape
    for y in prange(height):
        for x in range(width):
            d = disp_l[y, x]
            if x - d >= 0 and abs(d - disp_r[y, x - d]) <= tolerance:
                labels[y, x] = VALID
                continue
            label = OCCLUDED
            for dd in range(min(n_disp, x + 1)):
                if abs(dd - disp_r[y, x - dd]) <= tolerance:
                    label = MISMATCHED
                    break
            labels[y, x] = label


@njit(**KERNEL_OPTIONS)
def fill_rejected(disp, labels, image, steps_y, steps_x, max_search, invalid, out):
    """Fill every non-VALID pixel from the first VALID pixel found along each direction.

    Occluded pixels take the lowest candidate (the background); mismatched pixels take
    the candidate whose colour is closest. A pixel with no candidate gets ``invalid``.
    """
    height, width = disp.shape
    for y in prange(height):
        for x in range(width):
            label = labels[y, x]
            if label == VALID:
                out[y, x] = disp[y, x]
                continue
            best = invalid
            best_score = np.inf
            for k in range(steps_y.shape[0]):
                for step in range(1, max_search + 1):
                    yy = int(np.round(y + step * steps_y[k]))
                    xx = int(np.round(x + step * steps_x[k]))
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
