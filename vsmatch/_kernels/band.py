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
def band_costs(census_l, census_r_rev, grad_l, grad_r_rev, colour_l, colour_r_rev,
               census_table, grad_table, ad_table, max_cost, need_lo, need_hi, offsets, store):
    """The matching costs each pixel's neighbours will ask of it: C(q, d) for d in
    ``need_lo[q] .. need_hi[q]``, written to ``store[offsets[q]:]`` (one run per pixel,
    nothing where ``need_lo > need_hi``). The arguments before ``need_lo`` are
    :func:`vsmatch.cost.cost_terms`'s."""
    height, width = need_lo.shape
    for y in prange(height):
        for x in range(width):
            first = np.int64(need_lo[y, x])
            last = np.int64(need_hi[y, x])
            if first > last:
                continue
            start = width - 1 - x
            at = offsets[y, x]
            _costs_at(store[at:at + last - first + 1], first, last, x, census_l[y, x],
                      census_r_rev[y, start:], grad_l[y, x], grad_r_rev[y, start:],
                      colour_l[y, x], colour_r_rev[y, start:], census_table, grad_table,
                      ad_table, max_cost)


#: Candidates summed as one fixed-length run (a vector or two): most bands are shorter,
#: and a loop of constant length vectorises where one of 5-7 steps does not. The store
#: holds this many values more at its end, so a short run may read past its own.
RUN = 8


@njit(inline="always")
def _add_costs(local, store, starts, y, x, first, n):
    """local[k] += C((y, x), first + k) for k < n (and for k < RUN where n <= RUN,
    the values past n unused), from :func:`band_costs`' store."""
    at = starts[y, x] + first
    if n <= RUN:
        for k in range(RUN):
            local[k] += store[at + k]
    else:
        for k in range(n):
            local[k] += store[at + k]


@njit(**KERNEL_OPTIONS)
def search_band(store, starts, arms, lo, hi, n_disp, subpixel, out):
    """Best disparity in ``lo[y, x] .. hi[y, x]`` of each pixel, to sub-pixel (float32).

    The cost of a candidate d is the sum of the matching costs C(q, d) over the pixels q of
    the pixel's cross (its horizontal and vertical arms), read from :func:`band_costs`'
    store, which holds every (q, d) a cross asks for, C(q, d) at ``starts[q] + d``
    (``offsets - need_lo``). A parabola through the costs at
    d - 1, d, d + 1 gives the sub-pixel offset, as in the full search (``subpixel``; else
    whole disparities). ``lo > hi`` marks a pixel without an estimate: it gets ``inf``.
    """
    height, width = lo.shape
    for y in prange(height):
        local = np.empty(max(n_disp, RUN), dtype=np.float32)
        for x in range(width):
            a = np.int64(lo[y, x])
            b = np.int64(hi[y, x])
            if a > b:
                out[y, x] = np.inf
                continue
            first = max(a - 1, 0)
            last = min(b + 1, n_disp - 1)
            n = last - first + 1
            for k in range(max(n, RUN)):
                local[k] = 0.0
            # The pixel, its left and right arms, then its up and down arms.
            for j in range(-np.int64(arms[LEFT, y, x]), np.int64(arms[RIGHT, y, x]) + 1):
                _add_costs(local, store, starts, y, x + j, first, n)
            for i in range(1, np.int64(arms[UP, y, x]) + 1):
                _add_costs(local, store, starts, y - i, x, first, n)
            for i in range(1, np.int64(arms[DOWN, y, x]) + 1):
                _add_costs(local, store, starts, y + i, x, first, n)
            best = a
            best_cost = local[a - first]
            for d in range(a + 1, b + 1):
                cost = local[d - first]
                if cost < best_cost:
                    best_cost = cost
                    best = d
            result = np.float32(best)
            if subpixel and best - 1 >= first and best + 1 <= last:
                c0 = local[best - 1 - first]
                c2 = local[best + 1 - first]
                denom = c0 + c2 - 2.0 * best_cost
                if denom > 1e-9:
                    offset = (c0 - c2) / (2.0 * denom)
                    result = np.float32(best + min(0.5, max(-0.5, offset)))
            out[y, x] = result
