import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS
from .census import popcount64


@njit(inline="always")
def _candidates(lo, count, y, x, width):
    """Pixel (y, x)'s first candidate, how many of its candidates have a right pixel
    (x - (base + k) >= 0), and its right pixels' place in the reversed right view: right
    pixel x - d is at W - 1 - x + d, read forward from the band's first candidate (indexes
    Numba knows are >= 0)."""
    base = np.int64(lo[y, x])
    last = max(min(np.int64(count[y, x]), x + 1 - base), 0)
    return base, last, width - 1 - x + base


@njit(**ROW_OPTIONS)
def _colour_costs_of_row(census_l, census_r_rev, grad_l, grad_r_rev, colour_l, colour_r_rev,
                         census_table, grad_table, ad_table, max_cost, lo, count, y, out):
    """:func:`matching_cost_volume` of row ``y`` with the three channels' term. Its output
    overlaps no input, and the compiler is told so (as every body is, ``ROW_OPTIONS``): the
    loop over the candidates then vectorises without overlap checks (the 13 standard pairs'
    volumes with `default`: 0.61 -> 0.45 s at one thread, 0.31 -> 0.23 s at two). `fast`'s
    terms (no colour term) came out slower so (0.04 -> 0.05 s; bands of 8 to 31
    candidates): they stay in the loop."""
    width, n_disp = out.shape[1], out.shape[2]
    use_grad = grad_table.shape[0] > 0
    for x in range(width):
        if count[y, x] <= 0:  # no candidates (a held pixel): nothing to compute
            continue
        base, last, start = _candidates(lo, count, y, x, width)
        cl = census_l[y, x]
        gl = grad_l[y, x]
        census_r = census_r_rev[y, start:]
        grad_r = grad_r_rev[y, start:]
        costs = out[y, x]
        c0 = colour_l[0, y, x]
        c1 = colour_l[1, y, x]
        c2 = colour_l[2, y, x]
        r0 = colour_r_rev[0, y, start:]
        r1 = colour_r_rev[1, y, start:]
        r2 = colour_r_rev[2, y, start:]
        for d in range(last):
            c = census_table[popcount64(cl ^ census_r[d])]
            if use_grad:
                c += grad_table[abs(gl - grad_r[d])]
            c += ad_table[abs(c0 - r0[d]) + abs(c1 - r1[d]) + abs(c2 - r2[d])]
            costs[d] = c
        for d in range(last, n_disp):
            costs[d] = max_cost


@njit(inline="always")
def _smaller_count(differing, like_bits, like, n_bits):
    """Where in a ``like_table`` row the smaller census term lies: m of the ``like``
    neighbours differing scaled to the window (m * n_bits / like) against the h of all:
    ``m`` where m * n_bits < h * like, else ``n_bits + 1 + h`` (the same term where equal)."""
    h = np.int64(popcount64(differing))
    m = np.int64(popcount64(differing & like_bits))
    return m if m * n_bits < h * like else n_bits + 1 + h


@njit(**ROW_OPTIONS)
def _like_costs_of_row(census_l, census_r_rev, grad_l, grad_r_rev, colour_l, colour_r_rev,
                       like_l, census_table, like_table, grad_table, ad_table, max_cost, lo,
                       count, y, out):
    """:func:`matching_cost_volume` of row ``y`` with the census also counted over the like
    neighbours (any terms). A function of its own, so that the loops without it compile as
    they did: with its switch beside theirs, `fast`'s plain loop ran 1.6-2x slower."""
    width, n_disp = out.shape[1], out.shape[2]
    use_grad = grad_table.shape[0] > 0
    use_ad = ad_table.shape[0] > 0
    channels = colour_l.shape[0]
    n_bits = np.int64(census_table.shape[0] - 1)
    for x in range(width):
        if count[y, x] <= 0:  # no candidates (a held pixel): nothing to compute
            continue
        base, last, start = _candidates(lo, count, y, x, width)
        cl = census_l[y, x]
        gl = grad_l[y, x]
        ml = like_l[y, x]
        like = np.int64(popcount64(ml))
        terms = like_table[like]
        census_r = census_r_rev[y, start:]
        grad_r = grad_r_rev[y, start:]
        costs = out[y, x]
        if use_ad and channels == 3:  # `default`'s terms, the channels unrolled
            c0 = colour_l[0, y, x]
            c1 = colour_l[1, y, x]
            c2 = colour_l[2, y, x]
            r0 = colour_r_rev[0, y, start:]
            r1 = colour_r_rev[1, y, start:]
            r2 = colour_r_rev[2, y, start:]
            for d in range(last):
                differing = cl ^ census_r[d]
                c = terms[_smaller_count(differing, ml, like, n_bits)]
                if use_grad:
                    c += grad_table[abs(gl - grad_r[d])]
                c += ad_table[abs(c0 - r0[d]) + abs(c1 - r1[d]) + abs(c2 - r2[d])]
                costs[d] = c
        else:
            for d in range(last):
                differing = cl ^ census_r[d]
                c = terms[_smaller_count(differing, ml, like, n_bits)]
                if use_grad:
                    c += grad_table[abs(gl - grad_r[d])]
                if use_ad:
                    s = 0
                    for k in range(channels):
                        s += abs(colour_l[k, y, x] - colour_r_rev[k, y, start + d])
                    c += ad_table[s]
                costs[d] = c
        for d in range(last, n_disp):
            costs[d] = max_cost


@njit(**KERNEL_OPTIONS)
def matching_cost_volume(census_l, census_r_rev, grad_l, grad_r_rev, colour_l, colour_r_rev,
                         like_l, census_table, like_table, grad_table, ad_table, max_cost, lo,
                         count, out):
    """C(p, d) = rho(Hamming) + rho(|G_L - G_R|) [+ rho(mean |I_L - I_R|)], layout (H, W, B):
    ``out[y, x, k]`` is the cost of disparity ``lo[y, x] + k`` for ``k < count[y, x]`` (the
    pixel's band; the whole range is ``lo`` 0 and ``count`` D), ``max_cost`` past it.

    Every term is a table lookup: ``census_table[k]`` for k differing bits, or with the
    neighbours like the left pixel (the bits of ``like_l[y, x]``) the smaller of that and
    the term of the m of them among its n like ones, scaled (``cost.like_table``: an empty
    one, the census alone),
    ``grad_table[|g_L - g_R|]`` on gradients quantised to integers, ``ad_table[s]`` for the
    sum s of the channels' absolute differences. An empty table switches its term off.
    Where x - d < 0 the cost is ``max_cost``. The right view's arrays are reversed along x.
    The colours come as planes, (C, H, W), so that the right pixels' values of a channel
    are contiguous over d.
    """
    height, width, n_disp = out.shape
    use_grad = grad_table.shape[0] > 0
    use_ad = ad_table.shape[0] > 0
    use_like = like_table.shape[0] > 0
    channels = colour_l.shape[0]
    for y in prange(height):
        if use_like:  # the census over the like neighbours too: a function of its own
            _like_costs_of_row(census_l, census_r_rev, grad_l, grad_r_rev, colour_l,
                               colour_r_rev, like_l, census_table, like_table, grad_table,
                               ad_table, max_cost, lo, count, np.int64(y), out)
            continue
        if use_ad and channels == 3:  # `default`'s terms: a function of its own, below
            _colour_costs_of_row(census_l, census_r_rev, grad_l, grad_r_rev, colour_l,
                                 colour_r_rev, census_table, grad_table, ad_table, max_cost,
                                 lo, count, np.int64(y), out)
            continue
        for x in range(width):
            if count[y, x] <= 0:  # no candidates (a held pixel): nothing to compute
                continue
            base, last, start = _candidates(lo, count, y, x, width)
            cl = census_l[y, x]
            gl = grad_l[y, x]
            census_r = census_r_rev[y, start:]
            grad_r = grad_r_rev[y, start:]
            costs = out[y, x]
            for d in range(last):
                c = census_table[popcount64(cl ^ census_r[d])]
                if use_grad:
                    c += grad_table[abs(gl - grad_r[d])]
                if use_ad:
                    s = 0
                    for k in range(channels):
                        s += abs(colour_l[k, y, x] - colour_r_rev[k, y, start + d])
                    c += ad_table[s]
                costs[d] = c
            for d in range(last, n_disp):
                costs[d] = max_cost


@njit(**KERNEL_OPTIONS)
def view_terms(colour_l, colour_r, census_r, grad_l, grad_r, steps, planes_l, planes_r_rev,
               census_r_rev, q_l, q_r_rev, row_max):
    """What :func:`matching_cost_volume` reads of the views: the colours (H, W, C) as int16
    planes (C, H, W), the gradients quantised to ``round(g * steps)`` (int32), the right
    view's census, gradients and colours reversed along x, and each row's largest
    quantised gradient (``row_max``)."""
    height, width, channels = colour_l.shape
    for y in prange(height):
        largest = 0
        for x in range(width):
            xr = width - 1 - x
            for c in range(channels):
                planes_l[c, y, x] = colour_l[y, x, c]
                planes_r_rev[c, y, xr] = colour_r[y, x, c]
            census_r_rev[y, xr] = census_r[y, x]
            ql = np.int32(np.rint(grad_l[y, x] * steps))
            qr = np.int32(np.rint(grad_r[y, x] * steps))
            q_l[y, x] = ql
            q_r_rev[y, xr] = qr
            largest = max(largest, ql, qr)
        row_max[y] = largest
