import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS


@njit(inline="always")
def curve_at(costs, d1, inside, exclude):
    """From one cost curve over its in-view candidates ``costs[:inside]``: the cost at
    the chosen ``d1``, the smallest cost at least ``exclude + 1`` disparities away from
    it (the second minimum; the best cost when there is none), and the mean cost."""
    # One walk: the runs either side of the winner give the second minimum too.
    total = np.float32(0.0)
    second = np.float32(np.inf)
    near = max(0, d1 - exclude)
    far = min(inside, d1 + exclude + 1)
    for d in range(0, near):
        c = costs[d]
        total += c
        second = min(second, c)
    for d in range(near, far):
        total += costs[d]
    for d in range(far, inside):
        c = costs[d]
        total += c
        second = min(second, c)
    best = costs[d1]
    return best, (second if second < np.inf else best), total / inside


@njit(**KERNEL_OPTIONS)
def cost_curve(volume, lo, count, disp, exclude, out_best, out_second, out_mean):
    """Per pixel, :func:`curve_at` of its cost curve ``volume[y, x, :]`` over the
    candidates of its band (``lo``, ``count``) inside the right view (d <= x) and the
    chosen disparity ``disp[y, x]``. The candidates outside the view hold the volume's
    largest cost: counting them would make a curve of few candidates look sharp. Zeros
    where there is no such candidate or the chosen one is outside the band."""
    height, width, _ = volume.shape
    for y in prange(height):
        for x in range(width):
            base = np.int64(lo[y, x])
            inside = min(np.int64(count[y, x]), x + 1 - base)
            k = np.int64(disp[y, x]) - base
            if inside <= 0 or k < 0 or k >= np.int64(count[y, x]):
                out_best[y, x] = out_second[y, x] = out_mean[y, x] = 0.0
                continue
            best, second, mean = curve_at(volume[y, x], k, inside, exclude)
            out_best[y, x] = best
            out_second[y, x] = second
            out_mean[y, x] = mean


@njit(**KERNEL_OPTIONS)
def logistic(features, weights, out):
    """out = 1 / (1 + exp(-clip(score, -30, 30))), the score the quadratic form
    sum_i f_i sum_(j >= i) weights[i, j] f_j of each pixel's features (the first a
    constant 1: that row holds the bias and the linear weights), in float32."""
    n, height, width = features.shape
    for y in prange(height):
        # A row at a time, each term a pass along it: the passes vectorise (7x faster
        # than a pixel's terms at a time, the same sums in the same order).
        score = np.zeros(width, np.float32)
        inner = np.empty(width, np.float32)
        for i in range(n):
            inner[:] = 0.0
            for j in range(i, n):
                w = weights[i, j]
                for x in range(width):
                    inner[x] += w * features[j, y, x]
            for x in range(width):
                score[x] += features[i, y, x] * inner[x]
        for x in range(width):
            clipped = min(np.float32(30.0), max(np.float32(-30.0), score[x]))
            out[y, x] = np.float32(1.0) / (np.float32(1.0) + np.exp(-clipped))
