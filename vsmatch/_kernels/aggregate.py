import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS
from .arms import DOWN, LEFT, RIGHT, UP
from .lanes import LANES, add_arm_in_lanes, add_in_lanes, copy_lanes, divide_lanes
from .rows import dealt


@njit(inline="always")
def _shorter(a, b):
    # A conditional expression, not min(): Numba's min stops LLVM vectorising the loop.
    a = np.int32(a)
    b = np.int32(b)
    return a if a < b else b


@njit(inline="always")
def _arms_across(arms_l, arms_r_rev, first_lo, first_hi, y, x, base):
    """The left pixel's two arms across the pass, and its right pixels' (over d, from
    disparity ``base`` on)."""
    start = arms_l.shape[2] - 1 - x + base  # width - 1 - x + base
    return (arms_l[first_lo, y, x], arms_l[first_hi, y, x],
            arms_r_rev[first_lo, y, start:], arms_r_rev[first_hi, y, start:])


@njit(**ROW_OPTIONS)
def _sum_over_arms_row(src, arms_l, arms_r_rev, along_rows, normalise, lo, count, counts_out,
                       counts_in, classes, out, height, width, depth, lo_arm, hi_arm, first_lo,
                       first_hi, step_y, step_x, count_here, counted, padded, narrow, i):
    """:func:`sum_over_arms` of the ``dealt`` row ``i``."""
    y = dealt(i, height, classes)
    total = np.zeros(max(depth, LANES), dtype=np.float32)
    size = np.ones(max(depth, LANES), dtype=np.float32)
    ones = np.ones(LANES, dtype=np.float32)  # each pixel counts as one
    for x in range(width):
        base = np.int64(lo[y, x])
        n = np.int64(count[y, x])
        if n <= 0:  # no candidates: nothing to sum
            continue
        lanes = narrow and n <= LANES
        centre = src[y, x]
        # With lanes every lane is written, those past the band too (finite, unused).
        span = LANES if lanes else n
        for d in range(span):
            total[d] = centre[d]
        if count_here:
            for d in range(span):
                size[d] = np.float32(1.0)
        elif counted:
            for d in range(span):
                size[d] = counts_in[y, x, d]
        elif normalise:
            f_lo, f_hi, g_lo, g_hi = _arms_across(arms_l, arms_r_rev, first_lo, first_hi,
                                                  y, x, base)
            for d in range(n):
                size[d] = np.float32(1 + _shorter(f_lo, g_lo[d]) + _shorter(f_hi, g_hi[d]))
        for side in range(2):
            arm = lo_arm if side == 0 else hi_arm
            sign = -1 if side == 0 else 1
            reach_r = arms_r_rev[arm, y, width - 1 - x + base:]
            for k in range(1, np.int64(arms_l[arm, y, x]) + 1):
                ny = y + sign * k * step_y
                nx = x + sign * k * step_x
                k32 = np.int32(k)
                # Candidate d of this pixel is candidate d + off of the neighbour's.
                off = base - np.int64(lo[ny, nx])
                n_here = np.int64(count[ny, nx])
                first = max(np.int64(0), -off)
                stop = min(n, n_here - off)
                if lanes and n_here <= LANES:
                    if off <= -LANES or off >= LANES:
                        continue  # the bands do not meet
                    # One vector (``_kernels.lanes``): a lane outside either band or
                    # past the right pixel's arm adds nothing.
                    at = (ny * width + nx) * depth + off
                    if 0 <= at <= src.size - LANES:
                        reach_at = (arm * height + y) * padded + width - 1 - x + base
                        if counted:
                            add_in_lanes(total, size, src, at, counts_in, at, first, stop,
                                         arms_r_rev, reach_at, k)
                        else:
                            add_in_lanes(total, size, src, at, ones, 0, first, stop,
                                         arms_r_rev, reach_at, k)
                        continue
                    # At the volume's ends the vector would be read past them: the
                    # candidates the two bands share one by one, below.
                if count_here:
                    for d in range(first, stop):
                        inside = k32 <= np.int32(reach_r[d])
                        total[d] += src[ny, nx, d + off] if inside else np.float32(0.0)
                        size[d] += np.float32(1.0) if inside else np.float32(0.0)
                    continue
                if counted:
                    for d in range(first, stop):
                        inside = k32 <= np.int32(reach_r[d])
                        total[d] += src[ny, nx, d + off] if inside else np.float32(0.0)
                        size[d] += counts_in[ny, nx, d + off] if inside else np.float32(0.0)
                    continue
                neighbour = src[ny, nx]
                for d in range(first, stop):
                    inside = k32 <= np.int32(reach_r[d])
                    total[d] += neighbour[d + off] if inside else np.float32(0.0)
                if normalise:
                    # The neighbour's first-pass region: its combined arms across.
                    f_lo, f_hi, g_lo, g_hi = _arms_across(arms_l, arms_r_rev, first_lo,
                                                          first_hi, ny, nx, base)
                    for d in range(n):
                        inside = k32 <= np.int32(reach_r[d])
                        s = np.float32(1 + _shorter(f_lo, g_lo[d]) + _shorter(f_hi, g_hi[d]))
                        size[d] += s if inside else np.float32(0.0)
        result = out[y, x]
        if count_here:
            sizes_out = counts_out[y, x]
            for d in range(span):
                sizes_out[d] = size[d]
        if (normalise or counted) and not count_here:
            for d in range(span):
                result[d] = total[d] / size[d]
        else:
            for d in range(span):
                result[d] = total[d]


@njit(**KERNEL_OPTIONS)
def sum_over_arms(src, arms_l, arms_r_rev, along_rows, normalise, lo, count, counts_out,
                  counts_in, classes, out):
    """:func:`sum_along_arms` by direct sums: each pixel adds its arm pixels' costs.

    The work is proportional to the arm lengths rather than to one running sum per pixel,
    and every loop runs over d, contiguous and branch-free, so LLVM vectorises it: faster
    than running sums where arms are short and the disparity range is wide.

    ``arms_r_rev`` is the right view's arms reversed along x and padded with 255:
    ``arms_r_rev[a, y, W - 1 - x + d]`` is arm ``a`` of right pixel (y, x - d), 255 (no
    limit) where x - d < 0, so the arms of the right pixels of x lie forward in memory.

    Bands: ``src[y, x, k]`` is disparity ``lo[y, x] + k`` for ``k < count[y, x]``; an arm
    pixel adds to the disparities its own band holds too. Where the bands differ, the
    regions' sizes are counted as the sums are taken: the first pass writes them to
    ``counts_out`` and the second divides by the sums of ``counts_in`` over its arms (empty
    arrays: the whole range everywhere, every region's size known from the arms). Rows are
    dealt into ``classes`` (``rows.dealt``): a stream's frame searches a few rows' pixels.
    """
    height, width, depth = src.shape
    lo_arm = LEFT if along_rows else UP
    hi_arm = RIGHT if along_rows else DOWN
    first_lo = UP if along_rows else LEFT
    first_hi = DOWN if along_rows else RIGHT
    step_y = 1 - along_rows
    step_x = along_rows
    count_here = counts_out.shape[0] > 0
    counted = counts_in.shape[0] > 0
    padded = arms_r_rev.shape[2]
    # Bands of at most LANES candidates in a volume at least as deep: summed LANES at a
    # time, the lanes past a band unused.
    narrow = (count_here or counted) and depth >= LANES
    for i in prange(height):
        _sum_over_arms_row(src, arms_l, arms_r_rev, along_rows, normalise, lo, count, counts_out,
                           counts_in, classes, out, height, width, depth, lo_arm, hi_arm,
                           first_lo, first_hi, step_y, step_x, count_here, counted, padded,
                           narrow, np.int64(i))


@njit(inline="always")
def _region_ends(i, a_lo, a_hi, r_lo, r_hi, n_disp, ends_lo, ends_hi):
    """Where line cell ``i``'s region at each d starts and ends in a flat array of running
    sums, one value a sum (``ends_hi[d]`` one past the end).

    Unsigned, so indexing takes no wrap-around branch (the ends are never negative), and
    worked out in a vector loop before the sums are read: the read then costs two loads a
    candidate (the row pass 1.45-1.65x faster than with the ends worked out as it reads).
    """
    base = np.int32(i * n_disp)
    for d in range(n_disp):
        near = base + np.int32(d) - _shorter(a_lo, r_lo[d]) * np.int32(n_disp)
        far = base + np.int32(d) + (_shorter(a_hi, r_hi[d]) + np.int32(1)) * np.int32(n_disp)
        ends_lo[d] = np.uint32(near)
        ends_hi[d] = np.uint32(far)


#: The second pass's running sums: each cell's cost sum (fixed point) and region size in one
#: int64, the size in the low :data:`SIZE_BITS` bits (a region holds at most 511 x 511 <
#: 2^20 pixels), so that a region's two totals come in one read an end.
SIZE_BITS = 20
#: A line's whole fixed-point cost sum stays below 2^SUM_BITS, so that the packed running
#: sums stay below 2^63 (:func:`vsmatch.aggregation.fixed_point_scale` picks the scale).
SUM_BITS = 42


@njit(**ROW_OPTIONS)
def _sum_line(src, arms_l, arms_r_rev, along_rows, normalise, scale, line, line_max, out):
    """:func:`sum_along_arms` along row or column ``line``."""
    height, width, n_disp = src.shape
    length = width * along_rows + height * (1 - along_rows)
    lo_arm = LEFT if along_rows else UP
    hi_arm = RIGHT if along_rows else DOWN
    first_lo = UP if along_rows else LEFT
    first_hi = DOWN if along_rows else RIGHT
    ends_lo = np.empty(n_disp, np.uint32)
    ends_hi = np.empty(n_disp, np.uint32)
    # Running sums in float64: a float32 sum over a long line would lose the low bits
    # that separate close costs.
    if not normalise:
        sums = np.empty((length + 1, n_disp))
        sums[0, :] = 0.0
        for i in range(length):
            y = line * along_rows + i * (1 - along_rows)
            x = i * along_rows + line * (1 - along_rows)
            for d in range(n_disp):
                sums[i + 1, d] = sums[i, d] + src[y, x, d]
        flat = sums.reshape(-1)
        # Four maxima, each over every fourth candidate: one chain of comparisons held
        # the loop to its latency.
        t0 = t1 = t2 = t3 = np.float32(0.0)
        quads = n_disp // 4
        for i in range(length):
            y = line * along_rows + i * (1 - along_rows)
            x = i * along_rows + line * (1 - along_rows)
            a_lo, a_hi, r_lo, r_hi = _arms_across(arms_l, arms_r_rev, lo_arm, hi_arm, y,
                                                  x, 0)
            _region_ends(i, a_lo, a_hi, r_lo, r_hi, n_disp, ends_lo, ends_hi)
            result = out[y, x]
            for q in range(quads):
                d = 4 * q
                v0 = np.float32(flat[ends_hi[d]] - flat[ends_lo[d]])
                v1 = np.float32(flat[ends_hi[d + 1]] - flat[ends_lo[d + 1]])
                v2 = np.float32(flat[ends_hi[d + 2]] - flat[ends_lo[d + 2]])
                v3 = np.float32(flat[ends_hi[d + 3]] - flat[ends_lo[d + 3]])
                result[d] = v0
                result[d + 1] = v1
                result[d + 2] = v2
                result[d + 3] = v3
                t0 = v0 if v0 > t0 else t0
                t1 = v1 if v1 > t1 else t1
                t2 = v2 if v2 > t2 else t2
                t3 = v3 if v3 > t3 else t3
            for d in range(4 * quads, n_disp):
                v = np.float32(flat[ends_hi[d]] - flat[ends_lo[d]])
                result[d] = v
                t0 = v if v > t0 else t0
        t01 = t0 if t0 > t1 else t1
        t23 = t2 if t2 > t3 else t3
        top = t01 if t01 > t23 else t23
        # A cost that is not a finite number leaves the line's total so: named by a NaN
        # maximum (tested apart, as a NaN-aware maximum stopped LLVM vectorising the loop).
        total = 0.0
        for d in range(n_disp):
            total += sums[length, d]
        line_max[line] = top if np.isfinite(total) else np.float32(np.nan)
        return
    # Fixed point: each of the first pass's sums times ``scale`` (a power of two), packed
    # with its region's size (:data:`SIZE_BITS`): integer running sums are exact whatever
    # the line's length, and a region's two totals come in one read an end (the pass
    # 1.5-1.65x faster than with float64 (sum, size) pairs, two reads an end).
    packed = np.empty((length + 1, n_disp), np.int64)
    packed[0, :] = 0
    for i in range(length):
        y = line * along_rows + i * (1 - along_rows)
        x = i * along_rows + line * (1 - along_rows)
        f_lo, f_hi, g_lo, g_hi = _arms_across(arms_l, arms_r_rev, first_lo, first_hi,
                                              y, x, 0)
        for d in range(n_disp):
            v = src[y, x, d]
            v = v if v > np.float32(0.0) else np.float32(0.0)
            size = np.int64(1 + _shorter(f_lo, g_lo[d]) + _shorter(f_hi, g_hi[d]))
            fixed = np.int64(np.float64(v) * scale)
            packed[i + 1, d] = packed[i, d] + ((fixed << SIZE_BITS) | size)
    flat = packed.reshape(-1)
    size_mask = np.int64((1 << SIZE_BITS) - 1)
    unit = 1.0 / scale
    for i in range(length):
        y = line * along_rows + i * (1 - along_rows)
        x = i * along_rows + line * (1 - along_rows)
        a_lo, a_hi, r_lo, r_hi = _arms_across(arms_l, arms_r_rev, lo_arm, hi_arm, y, x, 0)
        _region_ends(i, a_lo, a_hi, r_lo, r_hi, n_disp, ends_lo, ends_hi)
        result = out[y, x]
        for d in range(n_disp):
            region = flat[ends_hi[d]] - flat[ends_lo[d]]
            result[d] = np.float64(region >> SIZE_BITS) * unit / \
                np.float64(region & size_mask)


@njit(**KERNEL_OPTIONS)
def sum_along_arms(src, arms_l, arms_r_rev, along_rows, normalise, scale, line_max, out):
    """One pass of cross-region aggregation over a (H, W, D) volume, by 1-D running sums.

    ``arms_l``: (4, H, W) arm lengths; ``arms_r_rev``: the right view's, reversed and
    padded as :func:`sum_over_arms` takes them. ``along_rows``: sum ``src`` over each
    pixel's combined horizontal arm (else vertical); at disparity d an arm is the shorter
    of the left pixel's and of the right pixel (y, x - d)'s. The first pass (not
    ``normalise``) writes each line's largest sum to ``line_max`` (one a line). The second
    (``normalise``) divides by the number of pixels of the whole region, i.e. the running
    sum of the first pass's arm lengths; it sums in fixed point, ``scale`` (float64) to a
    cost unit (:func:`vsmatch.aggregation.fixed_point_scale`, from the first pass's
    ``line_max``), its ``src`` non-negative (a negative sum counts as 0).
    """
    height, width = src.shape[:2]
    # Lines are rows or columns; plain int arithmetic keeps Numba's parfor typing integral.
    n_lines = height * along_rows + width * (1 - along_rows)
    for line in prange(n_lines):
        _sum_line(src, arms_l, arms_r_rev, along_rows, normalise, scale, np.int64(line),
                  line_max, out)


@njit(**KERNEL_OPTIONS)
def sum_over_lanes(src, arms_l, arms_r_rev, along_rows, lo, count, counts_out, counts_in,
                   out):
    """:func:`sum_over_arms` over bands of at most :data:`LANES` candidates in a volume
    exactly that deep (the coarse-to-fine search's), the same sums in the same order.

    Each neighbour adds one vector of LANES (``_kernels.lanes``) whatever the two bands'
    offsets: candidate d reads the neighbour's d + off, a lane outside either band or past
    the right pixel's arm adding zero (measured on `fast`'s 13 standard pairs: 0.69 s as
    scalar lanes, 0.29 s as vectors, one thread), a whole arm in one call with the sums in
    registers (``add_arm_in_lanes``: 276 -> 173 ms on four pairs' calls, one thread), the
    volume's first and last pixel a neighbour at a time. Kept apart from the general kernel,
    whose band bookkeeping is in the loops' way. ``counts_in`` in the first pass: LANES
    ones, (1, 1, LANES), each pixel counting as one.
    """
    height, width, depth = src.shape
    lo_arm = LEFT if along_rows else UP
    hi_arm = RIGHT if along_rows else DOWN
    step_y = 1 - along_rows
    step_x = along_rows
    first_pass = counts_out.shape[0] > 0
    padded = arms_r_rev.shape[2]
    stride = step_y * width + step_x  # from a pixel to the next along the pass, flat
    last = height * width - 1
    for y in prange(height):
        total = np.empty(LANES, np.float32)
        size = np.empty(LANES, np.float32)
        for x in range(width):
            base = np.int64(lo[y, x])
            n = np.int64(count[y, x])
            if n <= 0:  # no candidates: nothing to sum
                continue
            here = (y * width + x) * LANES
            copy_lanes(total, 0, src, here)
            copy_lanes(size, 0, counts_in, 0 if first_pass else here)
            reach = width - 1 - x + base  # the right pixels' arms from disparity base on
            pixel = y * width + x
            for side in range(2):
                arm = lo_arm if side == 0 else hi_arm
                sign = -1 if side == 0 else 1
                reach_at = (arm * height + y) * padded + reach
                length = np.int64(arms_l[arm, y, x])
                far = pixel + sign * length * stride
                if min(pixel, far) > 0 and max(pixel, far) < last:
                    # Every neighbour's vector lies inside the volume: the whole arm at once.
                    add_arm_in_lanes(total, size, src, counts_in, first_pass, lo, count,
                                     arms_r_rev, reach_at, base, n, pixel, sign * stride,
                                     length)
                    continue
                for k in range(1, length + 1):
                    ny = y + sign * k * step_y
                    nx = x + sign * k * step_x
                    off = base - np.int64(lo[ny, nx])
                    if off <= -LANES or off >= LANES:
                        continue  # the bands do not meet
                    # This pixel's candidates from ``first`` to ``stop`` are the neighbour's.
                    first = max(np.int64(0), -off)
                    stop = min(n, np.int64(count[ny, nx]) - off)
                    at = (ny * width + nx) * LANES + off
                    if 0 <= at <= src.size - LANES:
                        add_in_lanes(total, size, src, at, counts_in, 0 if first_pass else at,
                                     first, stop, arms_r_rev, reach_at, k)
                        continue
                    # The volume's first or last pixel, read past its end: lane by lane.
                    for d in range(first, stop):
                        if k <= np.int64(arms_r_rev[arm, y, reach + d]):
                            total[d] += src[ny, nx, d + off]
                            size[d] += np.float32(1.0) if first_pass else \
                                counts_in[ny, nx, d + off]
            if first_pass:
                copy_lanes(counts_out, here, size, 0)
                copy_lanes(out, here, total, 0)
            else:
                divide_lanes(out, here, total, size)
