import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS
from .rows import dealt

#: Most candidates a pixel weighs: its own disparity and one from each side (the sums of
#: the window below are written out for three).
MAX_CANDIDATES = 3


@njit(inline="always")
def _capped(value, cap):
    # A conditional expression, not min(): Numba's min stops LLVM vectorising the loop.
    return value if value < cap else cap


@njit(**ROW_OPTIONS)
def _edge_sides_of_row(disp, left, right, grad_l, grad_r, skip, radius, colour_scale,
                       distance_scale, gradient_share, colour_cap, gradient_cap, reach, jump,
                       margin, classes, out, height, width, channels, by_colour, by_distance, i):
    """:func:`weigh_edge_sides` of the ``dealt`` row ``i``."""
    y = dealt(i, height, classes)
    candidates = np.empty(MAX_CANDIDATES, np.float64)
    totals = np.empty(MAX_CANDIDATES, np.float64)
    shifts = np.empty(MAX_CANDIDATES, np.int64)
    fractions = np.empty(MAX_CANDIDATES, np.float64)
    weights_row = np.empty(2 * radius + 1, np.float64)
    # Zeroed once: the rows past a pixel's candidates are summed too (see below), never read.
    costs_row = np.zeros((MAX_CANDIDATES, 2 * radius + 1), np.float64)
    for x in range(width):
        own = disp[y, x]
        out[y, x] = own
        if not np.isfinite(own) or skip[y, x]:
            continue
        count = 1
        candidates[0] = own
        for side in (-1, 1):
            for k in range(1, reach + 1):
                nx = x + side * k
                if nx < 0 or nx >= width:
                    break
                other = disp[y, nx]
                if np.isfinite(other) and other < own - jump:
                    candidates[count] = other
                    count += 1
                    break
        if count == 1:
            continue
        # Every candidate is weighed over the window pixels all of them see in the right
        # view (the own disparity is the largest), with one set of weights: columns
        # qx >= nearest and qx - farthest <= W - 1.
        nearest = candidates[0]
        farthest = candidates[0]
        for c in range(1, count):
            farthest = min(farthest, candidates[c])
        first = max(x - radius, 0, np.int64(np.ceil(nearest)))
        last = min(x + radius, width - 1, np.int64(np.floor(farthest + width - 1)))
        span = last + 1 - first
        totals[:] = 0.0
        for c in range(count):
            # qx - candidate is exact in float64: its whole part moves with qx, its
            # fraction is the same over the window.
            whole = np.floor(-candidates[c])
            shifts[c] = np.int64(whole)
            fractions[c] = -candidates[c] - whole
        weights = 0.0
        for dy in range(-radius, radius + 1):
            qy = y + dy
            if qy < 0 or qy >= height or span <= 0:
                continue
            # A window row's weights and costs at once, in loops that vectorise (the
            # channels written out), then summed in the window's order.
            ady = dy if dy >= 0 else -dy
            # Unsigned indexes: Numba tests a signed one for a negative value (a branch
            # in every look-up, which stops LLVM vectorising the loops).
            ufirst = np.uint64(first)
            uy, uqy = np.uint64(y), np.uint64(qy)
            ux = np.uint64(x)
            uspan = np.uint64(span)
            for j in range(uspan):
                qx = ufirst + j
                if channels == 3:  # written out, as below
                    similar = (abs(np.int64(left[0, uy, ux]) - np.int64(left[0, uqy, qx]))
                               + abs(np.int64(left[1, uy, ux]) - np.int64(left[1, uqy, qx]))
                               + abs(np.int64(left[2, uy, ux]) - np.int64(left[2, uqy, qx])))
                else:
                    similar = 0
                    for ch in range(channels):
                        similar += abs(np.int64(left[ch, uy, ux]) - np.int64(left[ch, uqy, qx]))
                dx = np.int64(qx) - x
                weights_row[j] = (by_colour[np.uint64(similar)]
                                  * by_distance[np.uint64((dx if dx >= 0 else -dx) + ady)])
            for c in range(count):
                f = fractions[c]
                g = 1.0 - f
                uat = np.uint64(first + shifts[c])  # the right column left of the first's match
                for j in range(uspan):
                    qx = ufirst + j
                    x0 = uat + j
                    x1 = x0 + np.uint64(1)
                    if channels == 3:
                        colour = abs(np.float64(left[0, uqy, qx])
                                     - (g * right[0, uqy, x0] + f * right[0, uqy, x1]))
                        colour += abs(np.float64(left[1, uqy, qx])
                                      - (g * right[1, uqy, x0] + f * right[1, uqy, x1]))
                        colour += abs(np.float64(left[2, uqy, qx])
                                      - (g * right[2, uqy, x0] + f * right[2, uqy, x1]))
                    else:
                        colour = 0.0
                        for ch in range(channels):
                            colour += abs(np.float64(left[ch, uqy, qx]) - (
                                g * right[ch, uqy, x0] + f * right[ch, uqy, x1]))
                    colour = _capped(colour / channels, colour_cap)
                    shown_grad = g * grad_r[uqy, x0] + f * grad_r[uqy, x1]
                    gradient = _capped(abs(grad_l[uqy, qx] - shown_grad), gradient_cap)
                    costs_row[c, j] = weights_row[j] * ((1.0 - gradient_share) * colour
                                                        + gradient_share * gradient)
            # In the window's order, as scalars: each sum's chain stays in a register (an
            # array's element went through memory at each add), all MAX_CANDIDATES of them.
            w_sum, t0, t1, t2 = weights, totals[0], totals[1], totals[2]
            for j in range(span):
                w_sum += weights_row[j]
                t0 += costs_row[0, j]
                t1 += costs_row[1, j]
                t2 += costs_row[2, j]
            weights, totals[0], totals[1], totals[2] = w_sum, t0, t1, t2
        if weights <= 0:
            continue
        best = own
        best_cost = totals[0]
        for c in range(1, count):
            # A surface behind must explain the window better by the share margin.
            if totals[c] * (1.0 + margin) < best_cost:
                best_cost = totals[c] * (1.0 + margin)
                best = candidates[c]
        out[y, x] = best


@njit(**KERNEL_OPTIONS)
def weigh_edge_sides(disp, left, right, grad_l, grad_r, skip, radius, colour_scale,
                     distance_scale, gradient_share, colour_cap, gradient_cap, reach, jump,
                     margin, classes, out):
    """``out[y, x]``: the disparity of ``disp`` at the pixel, or that of the nearest pixel
    within ``reach`` along its row on either side that lies more than ``jump`` behind it
    (a smaller disparity), whichever explains the views best over the pixel's window of
    ``radius``: each window pixel weighs exp(-colour difference from the centre /
    ``colour_scale`` - city-block distance / ``distance_scale``) and costs
    (1 - ``gradient_share``) min(colour difference, ``colour_cap``) + ``gradient_share``
    min(x-gradient difference, ``gradient_cap``) at the candidate's disparity (the right
    view interpolated between columns). A candidate from a side must cost less than the
    pixel's own by the share ``margin``. Every candidate is weighed over the same window
    pixels, those all of them see in the right view. ``left``: (C, H, W) uint8 planes;
    ``right`` and ``grad_r``: (C, H, W + 1) and (H, W + 1), the last column repeated (a
    match at the last column has fraction 0 and reads one column past it, weighed 0);
    ``grad_*``: x-gradient, grey levels a pixel; ``skip``: pixels left as they are."""
    height, width = disp.shape
    channels = left.shape[0]
    # The weights' two factors, looked up: the colour difference summed over the channels
    # is a whole number of grey levels, the distance a whole number of pixels.
    by_colour = np.exp(-np.arange(255 * channels + 1) / channels / colour_scale)
    by_distance = np.exp(-np.arange(2 * radius + 1) / distance_scale)
    for i in prange(height):  # rows dealt out: only pixels near a step weigh their windows
        _edge_sides_of_row(disp, left, right, grad_l, grad_r, skip, radius, colour_scale,
                           distance_scale, gradient_share, colour_cap, gradient_cap, reach, jump,
                           margin, classes, out, height, width, channels, by_colour, by_distance,
                           np.int64(i))
