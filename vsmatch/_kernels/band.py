import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS
from .arms import DOWN, LEFT, RIGHT, UP
from .census import popcount64


@njit(inline="always")
def _costs_at(local, first, last, x_q, census_q, census_r, grad_q, grad_r, colour_q,
              colour_r, census_table, grad_table, ad_table, max_cost):
    """local[d - first] = C(q, d) for d in first..last, C as in the cost volume.

    ``census_r`` etc. are the right view's rows reversed along x, from q's place on, so the
    right pixel x_q - d is at index d; where x_q - d < 0 the cost is ``max_cost``.
    """
    use_grad = grad_table.shape[0] > 0
    use_ad = ad_table.shape[0] > 0
    channels = colour_q.shape[0]
    inside = min(last, x_q)
    for d in range(first, inside + 1):
        c = census_table[popcount64(census_q ^ census_r[d])]
        if use_grad:
            c += grad_table[abs(grad_q - grad_r[d])]
        if use_ad:
            s = 0
            for k in range(channels):
                s += abs(colour_q[k] - colour_r[d, k])
            c += ad_table[s]
        local[d - first] = c
    for d in range(max(first, inside + 1), last + 1):
        local[d - first] = max_cost


@njit(**KERNEL_OPTIONS)
def search_band(census_l, census_r_rev, grad_l, grad_r_rev, colour_l, colour_r_rev,
                census_table, grad_table, ad_table, max_cost, arms, lo, hi, n_disp,
                support, tile, subpixel, out):
    """Best disparity in ``lo[y, x] .. hi[y, x]`` of each pixel, to sub-pixel (float32).

    The cost of a candidate d is the sum of the matching costs C(q, d) over the pixels q of
    the pixel's cross (its horizontal and vertical arms, at most ``support`` long). The
    image is cut into ``tile`` x ``tile`` tiles; for each, the costs of the tile and a
    ``support`` margin are computed once over the union of its pixels' bands, with running
    sums along rows and columns, so a cross sum is four lookups per candidate. A parabola
    through the costs at d - 1, d, d + 1 gives the sub-pixel offset, as in the full search
    (``subpixel``; else whole disparities). ``lo > hi`` marks a pixel without an estimate:
    it gets ``inf``.
    """
    height, width = lo.shape
    tiles_y = (height + tile - 1) // tile
    tiles_x = (width + tile - 1) // tile
    for t in prange(tiles_y * tiles_x):
        y0 = (t // tiles_x) * tile
        x0 = (t % tiles_x) * tile
        y1 = min(height, y0 + tile)
        x1 = min(width, x0 + tile)
        d_lo = n_disp
        d_hi = -1
        for y in range(y0, y1):
            for x in range(x0, x1):
                if lo[y, x] <= hi[y, x]:
                    d_lo = min(d_lo, np.int64(lo[y, x]))
                    d_hi = max(d_hi, np.int64(hi[y, x]))
        if d_hi < d_lo:
            for y in range(y0, y1):
                for x in range(x0, x1):
                    out[y, x] = np.inf
            continue
        first = max(d_lo - 1, 0)
        last = min(d_hi + 1, n_disp - 1)
        n = last - first + 1
        ry0 = max(0, y0 - support)
        rx0 = max(0, x0 - support)
        rows = min(height, y1 + support) - ry0
        cols = min(width, x1 + support) - rx0
        # Running sums of the costs along each row (along_x) and each column (along_y).
        along_x = np.empty((rows, cols + 1, n), dtype=np.float32)
        along_y = np.empty((rows + 1, cols, n), dtype=np.float32)
        local = np.empty(n, dtype=np.float32)
        along_x[:, 0, :] = 0.0
        along_y[0, :, :] = 0.0
        for r in range(rows):
            y = ry0 + r
            for c in range(cols):
                x = rx0 + c
                start = width - 1 - x
                _costs_at(local, first, last, x, census_l[y, x], census_r_rev[y, start:],
                          grad_l[y, x], grad_r_rev[y, start:], colour_l[y, x],
                          colour_r_rev[y, start:], census_table, grad_table, ad_table,
                          max_cost)
                for k in range(n):
                    along_x[r, c + 1, k] = along_x[r, c, k] + local[k]
                    along_y[r + 1, c, k] = along_y[r, c, k] + local[k]
        for y in range(y0, y1):
            r = y - ry0
            for x in range(x0, x1):
                a = np.int64(lo[y, x])
                b = np.int64(hi[y, x])
                if a > b:
                    out[y, x] = np.inf
                    continue
                c = x - rx0
                left_c = c - np.int64(arms[LEFT, y, x])
                right_c = c + np.int64(arms[RIGHT, y, x]) + 1
                up_r = r - np.int64(arms[UP, y, x])
                down_r = r + np.int64(arms[DOWN, y, x]) + 1
                lo_k = max(a - 1, first) - first
                hi_k = min(b + 1, last) - first
                for k in range(lo_k, hi_k + 1):
                    # Horizontal arm plus vertical arm, the pixel itself counted once.
                    local[k] = (along_x[r, right_c, k] - along_x[r, left_c, k]
                                + along_y[down_r, c, k] - along_y[up_r, c, k]
                                - (along_x[r, c + 1, k] - along_x[r, c, k]))
                best = a
                best_cost = local[a - first]
                for d in range(a + 1, b + 1):
                    cost = local[d - first]
                    if cost < best_cost:
                        best_cost = cost
                        best = d
                result = np.float32(best)
                if subpixel and best - 1 >= first + lo_k and best + 1 <= first + hi_k:
                    c0 = local[best - 1 - first]
                    c2 = local[best + 1 - first]
                    denom = c0 + c2 - 2.0 * best_cost
                    if denom > 1e-9:
                        offset = (c0 - c2) / (2.0 * denom)
                        result = np.float32(best + min(0.5, max(-0.5, offset)))
                out[y, x] = result
