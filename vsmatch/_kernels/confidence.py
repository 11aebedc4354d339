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


@njit(inline="always")
def _clip01(v):
    # np.clip's order (a NaN stays NaN), as selects that vectorise.
    v = np.float32(0.0) if v < 0 else v
    return np.float32(1.0) if v > 1 else v


@njit(inline="always")
def _finite_row(disp_row, out):
    for x in range(out.shape[0]):
        d = disp_row[x]
        out[x] = d if np.isfinite(d) else np.float32(0.0)


@njit(**KERNEL_OPTIONS)
def pixel_features(disp, labels, valid_label, mismatched_label, margin, below_mean,
                   raw_margin, support, max_distance, rows, not_valid, not_jump, counts):
    """The pixel-by-pixel features into ``rows`` (the model's feature planes in the order
    of ``confidence.FEATURES``): the constant, the clipped margins, the check's labels
    (``labels`` empty: every pixel valid), the support, and 1 + the distance to the right
    view's edge (its logarithm is taken after); ``not_valid`` and ``not_jump`` (uint8: 1
    where a pixel is not valid, is no disparity jump) for the distance transforms, and
    ``counts[y]`` the valid pixels and the jumps of row y. A plane at a time along each
    row, so that each loop vectorises."""
    height, width = disp.shape
    labelled = labels.shape[0] > 0
    for y in prange(height):
        finite = np.empty(width, np.float32)
        above = np.empty(width, np.float32)
        _finite_row(disp[y], finite)
        for x in range(width):
            rows[0, y, x] = 1.0
        for x in range(width):
            m = _clip01(margin[y, x])
            rows[1, y, x] = m
            rows[2, y, x] = m * m
        for x in range(width):
            rows[3, y, x] = _clip01(below_mean[y, x])
        for x in range(width):
            rows[7, y, x] = support[y, x]
        for x in range(width):
            rows[11, y, x] = _clip01(raw_margin[y, x])
        valid_count = width
        if labelled:
            valid_count = 0
            for x in range(width):
                valid = labels[y, x] == valid_label
                rows[4, y, x] = np.float32(1.0) if valid else np.float32(0.0)
                rows[5, y, x] = np.float32(1.0) if labels[y, x] == mismatched_label \
                    else np.float32(0.0)
                not_valid[y, x] = np.uint8(0) if valid else np.uint8(1)
                valid_count += 1 if valid else 0
        else:
            for x in range(width):
                rows[4, y, x] = 1.0
                rows[5, y, x] = 0.0
                not_valid[y, x] = 0
        for x in range(width):
            inside = np.float32(x) - finite[x]
            inside = np.float32(0.0) if inside < 0 else inside
            inside = max_distance if inside > max_distance else inside
            rows[10, y, x] = inside + np.float32(1.0)
        # A jump: a step of more than 1 to the left or upper neighbour.
        if y > 0:
            _finite_row(disp[y - 1], above)
        jump_count = 0
        for x in range(width):
            left = finite[x - 1] if x > 0 else finite[x]
            up = above[x] if y > 0 else finite[x]
            jump = (np.abs(finite[x] - left) > 1) | (np.abs(finite[x] - up) > 1)
            not_jump[y, x] = np.uint8(0) if jump else np.uint8(1)
            jump_count += 1 if jump else 0
        counts[y, 0] = valid_count
        counts[y, 1] = jump_count


@njit(**KERNEL_OPTIONS)
def finish(confidence, local_margin, local_raw, gates, disp, texture, high, low, n_disp,
           range_end, blob_spread, blob_texture, no_texture, textureless):
    """In place, the logistic model's ``confidence`` times the matchability gate (from the
    margins' local means and ``gates`` = (from, to, raw from, raw to)), 0 out of view,
    then capped at the range's ends, on blobs of one value (``high`` - ``low``: the
    window's spread, dilated and eroded) and where there is no texture."""
    height, width = confidence.shape
    span = np.float32(gates[1] - gates[0])
    raw_span = np.float32(gates[3] - gates[2])
    start = np.float32(gates[0])
    raw_start = np.float32(gates[2])
    top = np.float32(n_disp - 1.5)
    for y in prange(height):
        for x in range(width):
            gate = _clip01((local_margin[y, x] - start) / span)
            gate = gate * _clip01((local_raw[y, x] - raw_start) / raw_span)
            c = confidence[y, x] * gate
            d = disp[y, x]
            if not np.isfinite(d) or np.float32(x) - d < np.float32(-0.5):
                c = np.float32(0.0)
            # Caps as np.minimum takes them: a NaN stays NaN.
            if (d < np.float32(0.5) or d > top) and c > range_end:
                c = range_end
            t = texture[y, x]
            if high[y, x] - low[y, x] <= blob_spread and t < blob_texture and c > range_end:
                c = range_end
            if t < no_texture and c > textureless:
                c = textureless
            confidence[y, x] = c
