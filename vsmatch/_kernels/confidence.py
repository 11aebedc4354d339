import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS
from .rows import dealt
from .views import borrowed
from .sobel import mirrored_index, sobel_at


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


@njit(**ROW_OPTIONS)
def _logistic_of_row(features, weights, out, y):
    """out = 1 / (1 + exp(-clip(score, -30, 30))) along row ``y``, the score the quadratic
    form sum_i f_i sum_(j >= i) weights[i, j] f_j of each pixel's features (the first a
    constant 1: that row holds the bias and the linear weights), in float32."""
    n, width = features.shape[0], features.shape[2]
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


@njit(**ROW_OPTIONS)
def _gated_logistic_of_row(features, weights, margins, ramps, disparity, out, y):
    """:func:`gated_logistic` of row ``y``."""
    _logistic_of_row(features, weights, out, y)
    first_from, first_span, second_from, second_span = ramps
    for x in range(out.shape[1]):
        # As the NumPy expressions did it: float32 throughout, the two ramps multiplied
        # first.
        first = _unit((margins[0, y, x] - first_from) / first_span)
        second = _unit((margins[1, y, x] - second_from) / second_span)
        value = out[y, x] * (first * second)
        d = disparity[y, x]
        if not np.isfinite(d) or np.float32(x) - d < np.float32(-0.5):
            value = np.float32(0.0)  # no estimate, or its match left of the right view
        out[y, x] = value


@njit(**KERNEL_OPTIONS)
def gated_logistic(features, weights, margins, ramps, disparity, out):
    """The logistic model of each pixel's features (:func:`_logistic_of_row`) times the
    matchability gate: the product
    of the ramps (m - from) / span clipped to 0 .. 1 of the two ``margins`` (2, H, W) with
    ``ramps`` = (from, span, from, span), float32; 0 where ``disparity`` is not finite or
    x - disparity < -0.5."""
    for y in prange(features.shape[1]):
        _gated_logistic_of_row(features, weights, margins, ramps, disparity, out,
                               np.int64(y))


@njit(**KERNEL_OPTIONS)
def rival_offsets(volume, disp, best, second, mean, hump, level, floor, reach, out):
    """Per pixel, :func:`rival_offset` of its whole-range cost curve ``volume[y, x, :]``
    at the chosen ``disp[y, x]``; ``best``, ``second``, ``mean``: the curve's
    :func:`cost_curve` maps."""
    height, width, depth = volume.shape
    for y in prange(height):
        for x in range(width):
            out[y, x] = rival_offset(volume[y, x], disp[y, x], min(depth, x + 1),
                                     best[y, x], second[y, x], mean[y, x], hump, level,
                                     floor, reach)


@njit(**ROW_OPTIONS)
def _curves_and_rivals_of_row(volume, disp, exclude, hump, level, floor, reach, out_best,
                              out_second, out_mean, out_offset, y):
    """:func:`cost_curve_and_rivals` of row ``y``."""
    width, depth = volume.shape[1], volume.shape[2]
    for x in range(width):  # the row's curves, then its rivals (the row still in cache)
        inside = min(depth, x + 1)
        d1 = np.int64(disp[y, x])
        if d1 < 0 or d1 >= depth:  # as cost_curve: a winner out of view has a curve
            out_best[y, x] = out_second[y, x] = out_mean[y, x] = 0.0
            continue
        best, second, mean = curve_at(volume[y, x], d1, inside, exclude)
        out_best[y, x] = best
        out_second[y, x] = second
        out_mean[y, x] = mean
    for x in range(width):
        out_offset[y, x] = rival_offset(volume[y, x], disp[y, x], min(depth, x + 1),
                                        out_best[y, x], out_second[y, x],
                                        out_mean[y, x], hump, level, floor, reach)


@njit(**KERNEL_OPTIONS)
def cost_curve_and_rivals(volume, disp, exclude, hump, level, floor, reach, out_best,
                          out_second, out_mean, out_offset):
    """:func:`cost_curve` over the whole range (no bands) and :func:`rival_offset` in
    one pass: the curve is walked for a rival while it is in cache."""
    height = volume.shape[0]
    for y in prange(height):
        _curves_and_rivals_of_row(volume, disp, exclude, hump, level, floor, reach, out_best,
                                  out_second, out_mean, out_offset, np.int64(y))


@njit(inline="always")
def rival_offset(costs, d1, inside, best, second, mean, hump, level, floor, reach):
    """The offset (disparities, signed) from the chosen ``d1`` to the lowest *separated*
    rival on the cost curve ``costs[:inside]`` (at most ``reach`` from the winner): a
    candidate with a rise of at least ``hump`` x (mean - best) between it and the winner,
    so another valley, not the winner's own slope. 0 unless the rival is within
    ``level`` x (mean - best + ``floor``) of the winner's cost. ``best``, ``second``,
    ``mean``: the curve's :func:`curve_at`; a second minimum (at least 2 away) above that
    already rules out a rival, so most curves are not walked."""
    d1 = np.int64(d1)
    if d1 < 0 or d1 >= inside:
        return 0
    spread = mean - best
    near = np.float32(level) * (spread + np.float32(floor))
    if second - best >= near:
        return 0
    rise = np.float32(hump) * spread
    first, last = max(0, d1 - reach), min(inside, d1 + reach + 1)
    # The rival's cost first, without branches (most curves have none); where to find it
    # only for the few that do.
    rival = min(_lowest_separated(costs, d1, first - 1, -1, rise),
                _lowest_separated(costs, d1, last, 1, rise))
    if rival - costs[d1] < near:
        return _offset_of(costs, d1, first, last, rise, rival)
    return 0


@njit(inline="always")
def _lowest_separated(costs, d1, stop, step, rise):
    """The lowest cost walking from ``d1`` by ``step`` to ``stop`` (excluded) with a rise
    of at least ``rise`` between it and ``d1``; inf where there is none."""
    lowest = np.float32(np.inf)
    peak = costs[d1]
    for d in range(d1 + step, stop, step):
        c = costs[d]
        peak = max(peak, c)
        lowest = min(lowest, c if peak - c >= rise else np.float32(np.inf))
    return lowest


@njit(inline="always")
def _offset_of(costs, d1, first, last, rise, rival):
    """The offset from ``d1`` of the nearest separated candidate of cost ``rival``, on
    the left if both sides have one (0 if none)."""
    best_offset = 0
    for step, stop in ((-1, first - 1), (1, last)):
        peak = costs[d1]
        for d in range(d1 + step, stop, step):
            c = costs[d]
            peak = max(peak, c)
            if peak - c >= rise and c == rival:
                if best_offset == 0:
                    best_offset = d - d1
                break
    return best_offset


#: The repeats :func:`repeats_at` tells from the rest: a rival 1, 2 or 3 periods away
#: (a level down the nearest valley can be a period or two off; its lag at the larger view
#: is then 2 or 4 periods).
REPEATS_LOOKED_AT = 3


@njit(**ROW_OPTIONS)
def _repeats_of_row(grey, offset, step, radius, reach, similar, spread, out, row):
    """:func:`repeats_at` of output row ``row``."""
    grey, offset, out = borrowed(grey), borrowed(offset), borrowed(out)
    height, width = grey.shape
    y = row * step
    for j in range(out.shape[1]):
        out[row, j] = 0.0
        lag = abs(np.int64(offset[row, j]))
        if lag == 0:
            continue
        x = j * step
        columns = max(radius, min(reach, lag))
        first = max(lag + spread, x - columns)
        rows = (max(0, y - radius), min(height, y + radius + 1))
        cols = (first, min(width, x + columns + 1))
        worst = np.int32(0)
        for periods in range(1, REPEATS_LOOKED_AT + 1):
            half = max(1, lag // (2 * periods))
            if periods > 1 and half == max(1, lag // (2 * periods - 2)):
                break  # the same shift as the last: no more to look at
            worst = max(worst, _shifted_difference(grey, rows, cols, half))
        for shift in range(max(1, lag - spread), lag + spread + 1):
            if _shifted_difference(grey, rows, cols, shift) < similar * (worst + 1.0):
                out[row, j] = 1.0
                break


@njit(**KERNEL_OPTIONS)
def repeats_at(grey, offset, step, radius, reach, similar, spread, classes, out):
    """out[i, j] = 1 where the view's ``grey`` levels (uint8) repeat themselves at
    ``offset[i, j]`` along the row, or within ``spread`` pixels of it, at pixel (``step``
    i, ``step`` j): over the window of rows +-``radius`` and columns +-min(``reach``,
    |offset|) (at least +-``radius``), the mean absolute difference between the view and
    itself shifted by |offset| (+- up to ``spread``) is below ``similar`` x the largest at
    half a period, for |offset| one, two or three periods (:data:`REPEATS_LOOKED_AT`): a
    repeat's worst phase, where a texture that does not repeat differs about as much. 0
    elsewhere and where ``offset`` is 0. (Half the shift alone, tested before, is itself a
    repeat when the offset is two periods: such rivals went unseen.) ``step`` 2 looks at
    every other row and column only (a level's pixels on the larger view): each output row
    has work, so the threads share it."""
    for i in prange(out.shape[0]):  # rows dealt out: only pixels with a rival are looked at
        _repeats_of_row(grey, offset, np.int64(step), radius, reach, similar, spread, out,
                        dealt(i, out.shape[0], classes))


@njit(inline="always")
def _shifted_difference(grey, rows, cols, shift):
    """The summed absolute difference between ``grey`` (uint8, borrowed) and itself
    ``shift`` columns to the left over the window of ``rows`` and ``cols`` (first, stop
    each; the first column at least ``shift``). Whole numbers, so the sums are exact in any
    order and vectorise, and read through views indexed from 0: as one float64 sum indexed
    by ``xx - shift`` (a wrap-around test each), an addition's latency a pixel held the
    repeat test (4 % of `fast`)."""
    total = np.int32(0)
    count = cols[1] - cols[0]
    for yy in range(rows[0], rows[1]):
        line = grey[yy]
        here, there = line[cols[0]:], line[cols[0] - shift:]
        for i in range(count):
            total += abs(np.int32(here[i]) - np.int32(there[i]))
    return total


@njit(inline="always")
def _unit(value):
    """``value`` clipped to 0 .. 1, NaN kept (as ``np.clip``)."""
    if value > 1:
        return np.float32(1.0)
    if value < 0:
        return np.float32(0.0)
    return value


@njit(**ROW_OPTIONS)
def _pixel_terms_of_row(margin, below_mean, raw_margin, support, labels, valid, mismatched,
                        disparity, grey, max_distance, out_margin, out_margin_sq,
                        out_below_mean, out_raw_margin, out_support, out_valid,
                        out_mismatched, targets, inside, gradient, y):
    """:func:`pixel_terms` of row ``y``."""
    height, width = disparity.shape
    labelled = labels.shape[0] > 0
    above, below = mirrored_index(y - 1, height), mirrored_index(y + 1, height)
    for x in range(width):
        m = _unit(margin[y, x])
        out_margin[y, x] = m
        out_margin_sq[y, x] = m * m
        out_below_mean[y, x] = _unit(below_mean[y, x])
        out_raw_margin[y, x] = _unit(raw_margin[y, x])
        out_support[y, x] = support[y, x]
        is_valid = not labelled or labels[y, x] == valid
        out_valid[y, x] = 1.0 if is_valid else 0.0
        out_mismatched[y, x] = 1.0 if labelled and labels[y, x] == mismatched else 0.0
        targets[0, y, x] = is_valid
        d = disparity[y, x]
        here = d if np.isfinite(d) else np.float32(0.0)
        step = False
        if x > 0:
            left = disparity[y, x - 1]
            step = abs(here - (left if np.isfinite(left) else np.float32(0.0))) > 1
        if y > 0:
            up = disparity[y - 1, x]
            step = step or abs(here - (up if np.isfinite(up) else np.float32(0.0))) > 1
        targets[1, y, x] = step
        room = np.float32(x) - here
        inside[y, x] = min(max(room, np.float32(0.0)), max_distance)
    # The 3 x 3 Sobel derivatives (borders mirrored as OpenCV's BORDER_REFLECT_101): whole
    # numbers, so the same float32 values as cv2.Sobel's.
    up, here, down = grey[above], grey[y], grey[below]
    for x in range(1, width - 1):
        gradient[0, y, x] = _sobel_sum(up, here, down, x - 1, x, x + 1)
    for x in (0, width - 1):
        gradient[0, y, x] = _sobel_sum(up, here, down, mirrored_index(x - 1, width), x,
                                       mirrored_index(x + 1, width))


@njit(inline="always")
def _sobel_sum(up, here, down, west, x, east):
    """|gx| + |gy| of the 3 x 3 Sobel derivatives at column ``x`` of the row ``here``."""
    gx, gy = sobel_at(up, here, down, west, x, east)
    return abs(gx) + abs(gy)


@njit(**KERNEL_OPTIONS)
def pixel_terms(margin, below_mean, raw_margin, support, labels, valid, mismatched, disparity,
                grey, max_distance, out_margin, out_margin_sq, out_below_mean, out_raw_margin,
                out_support, out_valid, out_mismatched, targets, inside, gradient):
    """The features a pixel's own values give, in one pass: the margins clipped to 0 .. 1
    (and the first squared), the support copied, VALID and MISMATCHED from ``labels`` (an
    empty array: every pixel valid), and for the neighbourhood features: ``targets[0]``
    where the pixel is valid and ``targets[1]`` where the disparity (0 where not finite)
    changes by more than 1 from the pixel left of or above it (what the distances are
    measured to), ``inside`` = x - that disparity clipped to 0 .. ``max_distance``, and
    ``gradient[0]`` = |gx| + |gy| of the 3 x 3 Sobel derivatives of ``grey``.
    ``valid``, ``mismatched``: the labels' values (``vsmatch.disparity``'s)."""
    for y in prange(disparity.shape[0]):
        _pixel_terms_of_row(margin, below_mean, raw_margin, support, labels, valid,
                            mismatched, disparity, grey, max_distance, out_margin,
                            out_margin_sq, out_below_mean, out_raw_margin, out_support,
                            out_valid, out_mismatched, targets, inside, gradient,
                            np.int64(y))


#: The 3 x 3 chamfer steps of OpenCV's DIST_L2 mask 3 (Borgefors): along a row or column,
#: and diagonal.
CHAMFER_STEP, CHAMFER_DIAGONAL = 0.955, 1.3693


@njit(**ROW_OPTIONS)
def _chamfer_band(targets, cap, band_rows, halo, job, out):
    """:func:`chamfer_distances` of one band of rows of one map (``job`` = band x maps +
    map): the two passes over the band and ``halo`` rows either side."""
    count, height, width = targets.shape
    # The maps of a band side by side: a thread's share of the jobs holds each map's
    # bands alike (map by map, one thread took the sparse map's, where every pixel is
    # walked, and the other the dense one's: 1.23x from 1 to 2 threads).
    band, k = job // count, job % count
    first, stop = band * band_rows, min(height, (band + 1) * band_rows)
    y0, y1 = max(0, first - halo), min(height, stop + halo)
    rows = y1 - y0
    step, diagonal = np.float32(CHAMFER_STEP), np.float32(CHAMFER_DIAGONAL)
    far = np.float32(1e30)  # outside the image and not yet reached: no target
    t = np.full((rows + 2, width + 2), far, np.float32)
    for i in range(rows):  # forward: from the row above and the pixel to the left
        line = targets[k, y0 + i]
        for x in range(width):
            if line[x]:
                t[i + 1, x + 1] = 0.0
            else:
                a = min(t[i, x] + diagonal, t[i, x + 1] + step)
                a = min(a, t[i, x + 2] + diagonal)
                t[i + 1, x + 1] = min(a, t[i + 1, x] + step)
    for i in range(rows - 1, -1, -1):  # backward: from the row below and the pixel right
        y = y0 + i
        for x in range(width - 1, -1, -1):
            a = t[i + 1, x + 1]
            if a > step:
                a = min(a, t[i + 2, x + 2] + diagonal)
                a = min(a, t[i + 2, x + 1] + step)
                a = min(a, t[i + 2, x] + diagonal)
                a = min(a, t[i + 1, x + 2] + step)
                t[i + 1, x + 1] = a
            if y >= first and y < stop:
                out[k, y, x] = min(a, cap)


@njit(**KERNEL_OPTIONS)
def chamfer_distances(targets, cap, band_rows, halo, out):
    """``out[k]``: each pixel's 3 x 3 chamfer distance (float32, at most ``cap``) to the
    nearest pixel where ``targets[k]`` holds, by the two passes of Borgefors' algorithm
    (OpenCV's distanceTransform with DIST_L2 and mask 3). Bands of ``band_rows`` rows run
    in parallel, each with ``halo`` rows either side: a path of length ``cap`` or less
    spans fewer rows than that, so every band's distances up to ``cap`` are those of the
    whole image, and the result does not depend on the bands."""
    count, height = targets.shape[0], targets.shape[1]
    bands = (height + band_rows - 1) // band_rows
    for job in prange(count * bands):
        _chamfer_band(targets, cap, band_rows, halo, np.int64(job), out)


@njit(**ROW_OPTIONS)
def _cap_flat_of_row(disparity, texture, radius, spread, flat_texture, cap, confidence, y):
    """:func:`cap_flat` of row ``y``: the largest and smallest disparity of each column
    over rows ``y - radius .. y + radius`` (those the image has), then of the square."""
    height, width = disparity.shape
    far = np.float32(1e9)  # what stands for a disparity that is not finite
    high = np.full(width, -far, np.float32)
    low = np.full(width, far, np.float32)
    for yy in range(max(0, y - radius), min(height, y + radius + 1)):
        line = disparity[yy]
        for x in range(width):
            d = line[x]
            finite = np.isfinite(d)
            high[x] = max(high[x], d if finite else -far)
            low[x] = min(low[x], d if finite else far)
    for x in range(width):
        if texture[y, x] >= flat_texture:
            continue
        top, bottom = high[x], low[x]
        for xx in range(max(0, x - radius), min(width, x + radius + 1)):
            top = max(top, high[xx])
            bottom = min(bottom, low[xx])
        if top - bottom <= spread:
            confidence[y, x] = min(confidence[y, x], cap)


@njit(**KERNEL_OPTIONS)
def cap_flat(disparity, texture, radius, spread, flat_texture, cap, confidence):
    """``confidence`` at most ``cap`` (in place) where every finite disparity of the
    (2 radius + 1) square around a pixel lies within ``spread`` of the others and
    ``texture`` is below ``flat_texture`` (float32 throughout; pixels that are not finite
    are left out of the extents, and a square of nothing but them counts as flat): the
    extents of cv2.dilate and cv2.erode, a column's first, then along the row."""
    for y in prange(disparity.shape[0]):
        _cap_flat_of_row(disparity, texture, radius, spread, flat_texture, cap, confidence,
                         np.int64(y))
