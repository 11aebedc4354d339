import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS
from .arms import DOWN, LEFT, RIGHT, UP
from .census import popcount64


@njit(inline="always")
def _add_costs(acc, first, last, x_q, census_q, census_r, grad_q, grad_r, colour_q, colour_r,
               census_table, grad_table, ad_table, max_cost):
    """acc[d - first] += C(q, d) for d in first..last, C as in the cost volume.

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
        acc[d - first] += c
    for d in range(max(first, inside + 1), last + 1):
        acc[d - first] += max_cost


@njit(**KERNEL_OPTIONS)
def search_band(census_l, census_r_rev, grad_l, grad_r_rev, colour_l, colour_r_rev,
                census_table, grad_table, ad_table, max_cost, arms, lo, hi, n_disp, out):
    """Best disparity in ``lo[y, x] .. hi[y, x]`` of each pixel, to sub-pixel (float32).

    The cost of a candidate d is the sum of the matching costs C(q, d) over the pixels q of
    the pixel's cross (its horizontal and vertical arms), computed here rather than read
    from a volume, so the work is the band width times the cross length per pixel. A
    parabola through the costs at d - 1, d, d + 1 gives the sub-pixel offset, as in the
    full search. ``lo > hi`` marks a pixel without an estimate: it gets ``inf``.
    """
    height, width = lo.shape
    for y in prange(height):
        acc = np.empty(n_disp + 2, dtype=np.float32)
        for x in range(width):
            a = np.int64(lo[y, x])
            b = np.int64(hi[y, x])
            if a > b:
                out[y, x] = np.inf
                continue
            first = max(a - 1, 0)
            last = min(b + 1, n_disp - 1)
            for k in range(last - first + 1):
                acc[k] = 0.0
            # The horizontal arm, p included, then the vertical arm without p.
            for xq in range(x - np.int64(arms[LEFT, y, x]), x + np.int64(arms[RIGHT, y, x]) + 1):
                start = width - 1 - xq
                _add_costs(acc, first, last, xq, census_l[y, xq], census_r_rev[y, start:],
                           grad_l[y, xq], grad_r_rev[y, start:], colour_l[y, xq],
                           colour_r_rev[y, start:], census_table, grad_table, ad_table,
                           max_cost)
            for yq in range(y - np.int64(arms[UP, y, x]), y + np.int64(arms[DOWN, y, x]) + 1):
                if yq == y:
                    continue
                start = width - 1 - x
                _add_costs(acc, first, last, x, census_l[yq, x], census_r_rev[yq, start:],
                           grad_l[yq, x], grad_r_rev[yq, start:], colour_l[yq, x],
                           colour_r_rev[yq, start:], census_table, grad_table, ad_table,
                           max_cost)
            best = a
            best_cost = acc[a - first]
            for d in range(a + 1, b + 1):
                c = acc[d - first]
                if c < best_cost:
                    best_cost = c
                    best = d
            result = np.float32(best)
            if first < best < last:
                c0 = acc[best - 1 - first]
                c2 = acc[best + 1 - first]
                denom = c0 + c2 - 2.0 * best_cost
                if denom > 1e-9:
                    offset = (c0 - c2) / (2.0 * denom)
                    result = np.float32(best + min(0.5, max(-0.5, offset)))
            out[y, x] = result
