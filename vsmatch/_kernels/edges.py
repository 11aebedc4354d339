import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS
from .rows import dealt

#: Most candidates a pixel weighs: its own disparity and one from each side.
MAX_CANDIDATES = 3


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
    pixels, those all of them see in the right view. ``left``/``right``: (H, W, C) uint8;
    ``grad_*``: x-gradient, grey levels a pixel; ``skip``: pixels left as they are."""
    height, width = disp.shape
    channels = left.shape[2]
    # The weights' two factors, looked up: the colour difference summed over the channels
    # is a whole number of grey levels, the distance a whole number of pixels.
    by_colour = np.exp(-np.arange(255 * channels + 1) / channels / colour_scale)
    by_distance = np.exp(-np.arange(2 * radius + 1) / distance_scale)
    for i in prange(height):  # rows dealt out: only pixels near a step weigh their windows
        y = dealt(i, height, classes)
        candidates = np.empty(MAX_CANDIDATES, np.float64)
        totals = np.empty(MAX_CANDIDATES, np.float64)
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
            # view (the own disparity is the largest), with one set of weights.
            nearest = candidates[0]
            farthest = candidates[0]
            for c in range(1, count):
                farthest = min(farthest, candidates[c])
            for c in range(count):
                totals[c] = 0.0
            weights = 0.0
            for dy in range(-radius, radius + 1):
                qy = y + dy
                if qy < 0 or qy >= height:
                    continue
                for dx in range(-radius, radius + 1):
                    qx = x + dx
                    if qx < 0 or qx >= width or qx - nearest < 0 or qx - farthest > width - 1:
                        continue
                    similar = 0
                    for ch in range(channels):
                        similar += abs(np.int64(left[y, x, ch]) - np.int64(left[qy, qx, ch]))
                    w = by_colour[similar] * by_distance[abs(dx) + abs(dy)]
                    weights += w
                    for c in range(count):
                        xr = qx - candidates[c]
                        x0 = int(np.floor(xr))
                        f = xr - x0
                        x1 = min(x0 + 1, width - 1)
                        colour = 0.0
                        for ch in range(channels):
                            shown = (1.0 - f) * right[qy, x0, ch] + f * right[qy, x1, ch]
                            colour += abs(np.float64(left[qy, qx, ch]) - shown)
                        colour = min(colour / channels, colour_cap)
                        shown_grad = (1.0 - f) * grad_r[qy, x0] + f * grad_r[qy, x1]
                        gradient = min(abs(grad_l[qy, qx] - shown_grad), gradient_cap)
                        totals[c] += w * ((1.0 - gradient_share) * colour
                                          + gradient_share * gradient)
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
