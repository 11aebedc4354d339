import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS
from .arms import DOWN, LEFT, RIGHT, UP
from .census import popcount64
from .refine import subpixel_offset
from .scanline import path_step


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


@njit(inline="always")
def _parabola(best, c0, c1, c2, fit):
    """``best`` moved to the minimum of the sub-pixel fit ``fit`` (``refine.subpixel_offset``)
    through the costs at best - 1, best, best + 1 (float32)."""
    return np.float32(best + subpixel_offset(c0, c1, c2, fit))


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
                result = _parabola(best, local[best - 1 - first], best_cost,
                                   local[best + 1 - first], subpixel)
            out[y, x] = result


@njit(**KERNEL_OPTIONS)
def band_aggregate(store, starts, arms, first, last, agg_at, agg):
    """The mean matching cost over each pixel's cross (as :func:`search_band` sums it) of
    every candidate d in ``first[y, x] .. last[y, x]``, written to
    ``agg[agg_at[y, x] + d - first[y, x]]`` (nothing where ``first > last``)."""
    height, width = first.shape
    for y in prange(height):
        for x in range(width):
            a = np.int64(first[y, x])
            n = np.int64(last[y, x]) - a + 1
            if n <= 0:
                continue
            local = agg[agg_at[y, x]:agg_at[y, x] + n]
            local[:] = 0.0
            count = 0
            for j in range(-np.int64(arms[LEFT, y, x]), np.int64(arms[RIGHT, y, x]) + 1):
                at = starts[y, x + j] + a
                for k in range(n):
                    local[k] += store[at + k]
                count += 1
            for i in range(-np.int64(arms[UP, y, x]), np.int64(arms[DOWN, y, x]) + 1):
                if i == 0:
                    continue
                at = starts[y + i, x] + a
                for k in range(n):
                    local[k] += store[at + k]
                count += 1
            scale = np.float32(1.0 / count)
            for k in range(n):
                local[k] *= scale


@njit(inline="always")
def _band_path(agg, agg_at, first, lo, hi, ys, xs, change_l, change_r_rev, p1s, p2s, weight,
               later, prev, cur, out):
    """Add ``weight`` x the scanline path costs along the pixels (ys[i], xs[i]) to ``out``,
    over each pixel's band ``lo .. hi`` (the recursion of ``_kernels.scanline``, a
    candidate outside the previous pixel's band counting as infinite). ``prev`` and ``cur``
    hold path costs at 1 + d and are all infinite between pixels. ``later``: the colour
    change crossed is stored at the later pixel in image order, this one (0) or the
    previous one (1). A pixel without a band restarts the path."""
    width = lo.shape[1]
    prev_lo = np.int64(1)
    prev_hi = np.int64(0)
    prev_min = np.float32(0.0)
    for i in range(ys.shape[0]):
        y = ys[i]
        x = xs[i]
        a = np.int64(lo[y, x])
        b = np.int64(hi[y, x])
        base = agg_at[y, x] - np.int64(first[y, x])
        smallest = np.float32(np.inf)
        if a <= b and prev_lo > prev_hi:  # the path starts: its cost is the pixel's
            for d in range(a, b + 1):
                v = agg[base + d]
                cur[d + 1] = v
                out[base + d] += weight * v
                smallest = v if v < smallest else smallest
        elif a <= b:
            ey = ys[i - later]
            ex = xs[i - later]
            cl = change_l[ey, ex]
            change_r = change_r_rev[ey, width - 1 - ex:]
            for d in range(a, b + 1):
                k = cl + 1 if change_r[d] else cl
                v = agg[base + d] + path_step(prev, d, p1s[k], p2s[k] + prev_min) - prev_min
                cur[d + 1] = v
                out[base + d] += weight * v
                smallest = v if v < smallest else smallest
        for d in range(prev_lo, prev_hi + 1):
            prev[d + 1] = np.inf
        for d in range(a, b + 1):  # this pixel's costs become the previous ones
            prev[d + 1] = cur[d + 1]
            cur[d + 1] = np.inf
        prev_lo, prev_hi, prev_min = a, b, smallest


@njit(inline="always")
def _band_paths_both_ways(agg, agg_at, first, lo, hi, ys, xs, change_l, change_r_rev, p1s,
                          p2s, n_disp, out):
    """:func:`_band_path` along the pixels (ys, xs), then back, each weighing a quarter."""
    weight = np.float32(0.25)
    prev = np.full(n_disp + 2, np.inf, dtype=np.float32)
    cur = np.full(n_disp + 2, np.inf, dtype=np.float32)
    _band_path(agg, agg_at, first, lo, hi, ys, xs, change_l, change_r_rev, p1s, p2s, weight,
               0, prev, cur, out)
    prev[:] = np.inf
    _band_path(agg, agg_at, first, lo, hi, ys[::-1].copy(), xs[::-1].copy(), change_l,
               change_r_rev, p1s, p2s, weight, 1, prev, cur, out)


@njit(**KERNEL_OPTIONS)
def band_scanline(agg, agg_at, first, lo, hi, n_disp, change_h, change_r_h, change_v,
                  change_r_v, p1s, p2s, out):
    """The scanline optimisation over the bands (``_kernels.scanline``'s four directions,
    each weighing a quarter): ``out`` (laid out as ``agg``, zeros in) gets the sum of the
    path costs along the rows, both ways, then along the columns, both ways.
    ``change_*``: the colour-change maps of ``optimization.scanline_optimise`` (the right
    view's reversed and padded)."""
    height, width = lo.shape
    for y in prange(height):
        _band_paths_both_ways(agg, agg_at, first, lo, hi, np.full(width, y, dtype=np.int64),
                              np.arange(width), change_h, change_r_h, p1s, p2s, n_disp, out)
    for x in prange(width):
        _band_paths_both_ways(agg, agg_at, first, lo, hi, np.arange(height),
                              np.full(height, x, dtype=np.int64), change_v, change_r_v, p1s,
                              p2s, n_disp, out)


@njit(**KERNEL_OPTIONS)
def band_winners(agg, sums, agg_at, first, last, lo, hi, subpixel, out):
    """Each pixel's candidate in ``lo .. hi`` of least ``sums`` (ties: the smaller d), to
    sub-pixel by a parabola through ``agg`` at d - 1, d, d + 1 (within ``first .. last``),
    as the full search does; ``inf`` where ``lo > hi``."""
    height, width = lo.shape
    for y in prange(height):
        for x in range(width):
            a = np.int64(lo[y, x])
            b = np.int64(hi[y, x])
            if a > b:
                out[y, x] = np.inf
                continue
            base = agg_at[y, x] - np.int64(first[y, x])
            best = a
            best_sum = sums[base + a]
            for d in range(a + 1, b + 1):
                s = sums[base + d]
                if s < best_sum:
                    best_sum = s
                    best = d
            result = np.float32(best)
            if subpixel and best - 1 >= first[y, x] and best + 1 <= last[y, x]:
                result = _parabola(best, agg[base + best - 1], agg[base + best],
                                   agg[base + best + 1], subpixel)
            out[y, x] = result
