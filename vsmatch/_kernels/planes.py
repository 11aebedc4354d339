import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS, SERIAL_OPTIONS
from .views import borrowed

#: The moments a plane's fit sums over a region: weight, then weight times u, v, u^2, u v,
#: v^2, d, u d, v d, d^2, and 1 (summed over a region: its pixel count).
N_MOMENTS = 11


@njit(**SERIAL_OPTIONS)
def take_planes(disp, kept, plane, spread, max_spread, snap, fill, out):
    """``out[y, x]``: the ``plane``'s value where it fits (finite, its region's ``spread``
    at most ``max_spread``) and the pixel is not ``kept`` (with ``fill``) or lies within
    ``snap`` of it; ``disp`` elsewhere."""
    height, width = disp.shape
    for y in range(height):
        for x in range(width):
            p = plane[y, x]
            d = disp[y, x]
            fitted = np.isfinite(p) and spread[y, x] <= max_spread
            take = fitted and ((fill and not kept[y, x]) or abs(d - p) <= snap)
            out[y, x] = p if take else d


@njit(inline="always")
def _pixel_moments(d, w, u, v, m):
    """``m`` = the pixel's moments (:data:`N_MOMENTS`), in float32: w (1, u, v, u^2, u v,
    v^2, d, u d, v d, d^2) and 1; w taken as 0 where ``d`` is not finite or w <= 0."""
    m[10] = 1.0
    if not np.isfinite(d) or w <= 0:
        for k in range(10):
            m[k] = 0.0
        return
    m[0] = w
    m[1] = w * u
    m[2] = w * v
    m[3] = w * u * u
    m[4] = w * u * v
    m[5] = w * v * v
    m[6] = w * d
    m[7] = w * u * d
    m[8] = w * v * d
    m[9] = w * d * d


@njit(inline="always")
def _region_moment(flat, hi, lo, j, k):
    """Moment ``k`` summed over the region of the block's pixel ``j``: the difference of the
    column's running sums (``flat``) at the region's ends (``hi[j]``, ``lo[j]``: flat
    offsets of its moments), through float32, as the sums were always kept before the
    solve."""
    return np.float64(np.float32(flat[hi[j] + np.uint32(k)] - flat[lo[j] + np.uint32(k)]))


@njit(inline="always")
def _solve_plane(flat, hi, lo, j, x, v0, cx, min_weight, min_spread):
    """The plane through the region of the block's pixel ``j`` (its summed moments read by
    :func:`_region_moment`), at pixel column ``x`` of a row ``v0`` from the centre: its
    value and the spread of the region's disparities about it (NaN, NaN where it does not
    fit). The cases are selects, not branches, so that a loop over ``j`` vectorises; the
    moments are read there, a vector of pixels at a time (as a pixel's line of moments
    written first and read across pixels, the stores and loads did not meet: the fit
    1.25-1.35x slower)."""
    w = _region_moment(flat, hi, lo, j, 0)
    # The threshold a float32 product, as the moments are float32.
    fits = (w > 0) & (not (w < min_weight * np.float32(_region_moment(flat, hi, lo, j, 10))))
    mu = _region_moment(flat, hi, lo, j, 1) / w
    mv = _region_moment(flat, hi, lo, j, 2) / w
    md = _region_moment(flat, hi, lo, j, 6) / w
    suu = _region_moment(flat, hi, lo, j, 3) / w - mu * mu
    suv = _region_moment(flat, hi, lo, j, 4) / w - mu * mv
    svv = _region_moment(flat, hi, lo, j, 5) / w - mv * mv
    sud = _region_moment(flat, hi, lo, j, 7) / w - mu * md
    svd = _region_moment(flat, hi, lo, j, 8) / w - mv * md
    det = suu * svv - suv * suv
    wide_u = suu >= min_spread
    wide_v = svv >= min_spread
    both = wide_u & wide_v & (det > 1e-6 * suu * svv)
    a_both = (sud * svv - svd * suv) / det
    b_both = (svd * suu - sud * suv) / det
    a_u = sud / suu
    b_v = svd / svv
    a = a_both if both else (a_u if wide_u else 0.0)
    b = b_both if both else (0.0 if wide_u else (b_v if wide_v else 0.0))
    value = np.float32(md + a * ((x - cx) - mu) + b * (v0 - mv))
    rest = _region_moment(flat, hi, lo, j, 9) / w - md * md - a * sud - b * svd
    rest = rest if rest > 0.0 else 0.0
    nan = np.float32(np.nan)
    return (value if fits else nan), (np.float32(np.sqrt(rest)) if fits else nan)


#: Columns the column pass of :func:`fit_region_planes` runs along at once: their running sums
#: side by side in memory (a column alone of the (H, W, C) rows is read with a stride of a
#: whole row). 16 was fastest of 8 to 64 (13.0 -> 8.5 ms on a 942 x 489 image, 11 channels).
COLUMN_BLOCK = 16


@njit(**ROW_OPTIONS)
def _row_moment_sums(disp, kept, last, inlier, arms, scratch, y, m, sums):
    """:func:`fit_region_planes`' row pass of row ``y``: each pixel's moments summed over its
    horizontal arms (left, right) into its block's ``scratch[x // COLUMN_BLOCK, y]``, by
    running sums in float64 (``m``: a pixel's moments, ``sums``: (W + 1,
    :data:`N_MOMENTS`), room for them). A pixel weighs 1 where ``kept`` and, given the
    ``last`` fit's planes, within ``inlier`` of its own; 0 elsewhere."""
    disp, kept, arms, scratch = borrowed(disp), borrowed(kept), borrowed(arms), \
        borrowed(scratch)
    last, m, sums = borrowed(last), borrowed(m), borrowed(sums)
    height, width = disp.shape
    # As float32, the centre the moments were always taken about.
    cx = np.float32((width - 1) / 2.0)
    cy = np.float32((height - 1) / 2.0)
    v = np.float32(y) - cy
    sums[0, :] = 0.0
    near_last = last.shape[0] > 0
    for x in range(width):
        d = disp[y, x]
        inside = kept[y, x] and (not near_last or np.abs(d - last[y, x]) <= inlier)
        _pixel_moments(d, np.float32(1.0) if inside else np.float32(0.0),
                       np.float32(x) - cx, v, m)
        for k in range(N_MOMENTS):
            sums[x + 1, k] = sums[x, k] + m[k]
    for x in range(width):
        lo = x - np.int64(arms[0, y, x])
        hi = x + np.int64(arms[1, y, x]) + 1
        block, j = x // COLUMN_BLOCK, x % COLUMN_BLOCK
        for k in range(N_MOMENTS):
            scratch[block, y, j, k] = sums[hi, k] - sums[lo, k]


@njit(**ROW_OPTIONS)
def _column_block_planes(scratch, arms, min_weight, min_spread, wanted, plane, spread, block,
                         sums, running, ends):
    """:func:`fit_region_planes`' column pass of columns ``block`` * :data:`COLUMN_BLOCK`
    on: the row sums (the block's ``scratch[block]``, its rows one after another in
    memory) summed over each pixel's vertical arms (up, down), by running sums in float64
    side by side in memory (``sums``: (H + 1) x the block's columns x :data:`N_MOMENTS`,
    flat, room for them; ``running``: room for a row of them), and each pixel's plane
    solved where a pixel of its row of the block is ``wanted`` (NaN, NaN elsewhere; ``ends``:
    (2, :data:`COLUMN_BLOCK`) uint32, room for a row's regions' ends)."""
    scratch, arms, plane, spread = borrowed(scratch), borrowed(arms), borrowed(plane), \
        borrowed(spread)
    wanted = borrowed(wanted)
    flat, running, ends = borrowed(sums), borrowed(running), borrowed(ends)
    height, width = plane.shape
    cx = (width - 1) / 2.0
    cy = (height - 1) / 2.0
    x0 = block * COLUMN_BLOCK
    n = min(width - x0, COLUMN_BLOCK)
    # A row of the block's running sums as one loop over its pixels' moments side by side,
    # added in a buffer of its own: read and written in one array (row y + 1 from row y),
    # the loop stayed scalar (a third of the column pass).
    line = n * N_MOMENTS
    rows = scratch[block].reshape(-1)  # a view of a borrowed array: no count either
    running[:line] = 0.0
    flat[:line] = 0.0
    for y in range(height):
        # Views (of borrowed arrays: no counts) indexed from 0: a flat index that Numba
        # cannot tell is >= 0 takes a wrap-around test, and the stores became a scatter.
        src = rows[y * COLUMN_BLOCK * N_MOMENTS:]
        dest = flat[(y + 1) * line:]
        for i in range(line):
            total = running[i] + src[i]
            running[i] = total
            dest[i] = total
    # Each pixel's region: where its moments' running sums start and end, flat (offsets
    # of 32 bits: a block's sums hold (H + 1) x 16 x 11 values; unsigned, so that the
    # solve's reads take no wrap-around test).
    lo, hi = ends[0], ends[1]
    nan = np.float32(np.nan)
    for y in range(height):
        asked = False
        for j in range(n):
            asked |= wanted[y, x0 + j]
        if not asked:  # the solve is over a quarter of the fit: none where no one reads it
            for j in range(n):
                plane[y, x0 + j] = nan
                spread[y, x0 + j] = nan
            continue
        for j in range(n):
            lo[j] = np.uint32(((y - np.int32(arms[2, y, x0 + j])) * n + j) * N_MOMENTS)
            hi[j] = np.uint32(((y + np.int32(arms[3, y, x0 + j]) + 1) * n + j) * N_MOMENTS)
        v0 = y - cy
        for j in range(n):
            value, off = _solve_plane(flat, hi, lo, j, x0 + j, v0, cx, min_weight, min_spread)
            plane[y, x0 + j] = value
            spread[y, x0 + j] = off


@njit(**KERNEL_OPTIONS)
def fit_region_planes(disp, kept, last, inlier, arms, min_weight, min_spread, wanted, scratch,
                      plane, spread):
    """The least-squares plane d = a u + b v + c through each pixel's cross region (the
    horizontal arms (left, right) of the pixels on its vertical arm (up, down)), through the
    region's ``kept`` pixels with a finite ``disp`` (given the ``last`` fit's planes, (H, W),
    those within ``inlier`` of their own; an empty (0, 0) array: every kept pixel),
    evaluated at the pixel (``plane``), and the standard deviation of the region's
    disparities about it (``spread``); NaN where the region's weight is below ``min_weight``
    of its pixels. Where its pixels do not span a plane (the variance along u or v below
    ``min_spread``) a constant is fitted along that axis. u, v are the pixel's coordinates
    from the image centre. Solved only in the rows of a block of :data:`COLUMN_BLOCK`
    columns that hold a ``wanted`` pixel (NaN elsewhere).

    The region's moments (:data:`N_MOMENTS`) are summed by running sums along each row
    into ``scratch`` (blocks, H, :data:`COLUMN_BLOCK`, N_MOMENTS; ``planes.moment_blocks``),
    then down each block of columns, and solved there: no volume of moments or of their
    sums is stored. The row sums are kept by block so that a block's column pass reads
    them in the order of memory (from rows of the whole width it read 16 pixels' moments a
    row apart: 2-4 % of the fit)."""
    height, width = disp.shape
    for y in prange(height):
        m = np.empty(N_MOMENTS, np.float32)
        sums = np.empty((width + 1, N_MOMENTS))
        _row_moment_sums(disp, kept, last, inlier, arms, scratch, np.int64(y), m, sums)
    for block in prange((width + COLUMN_BLOCK - 1) // COLUMN_BLOCK):
        sums = np.empty((height + 1) * COLUMN_BLOCK * N_MOMENTS)
        running = np.empty(COLUMN_BLOCK * N_MOMENTS)
        ends = np.empty((2, COLUMN_BLOCK), np.uint32)
        _column_block_planes(scratch, arms, min_weight, min_spread, wanted, plane, spread,
                             np.int64(block), sums, running, ends)


@njit(**ROW_OPTIONS)
def _cut_line_arms(arms, disp, jump, line, along_rows):
    """:func:`cut_arms_at_jumps`' two arms along row ``line`` (``along_rows``: left and
    right) or column ``line`` (up and down): each walk from one end of the line keeps, for
    every pixel, how far back it may reach without a step of more than ``jump`` between
    consecutive finite disparities (non-finite ones are walked over and compared with
    nothing), and cuts the arm pointing back to that. One body for rows and columns and
    both ends, by index: a quarter of the compiling of four inlined copies over views."""
    height, width = disp.shape
    n = width if along_rows else height
    for side in range(2):  # 0: from the start (the left or up arm), 1: from the end
        arm = (0 if side == 0 else 1) + (0 if along_rows else 2)
        start = 0  # the first step reachable from the current place
        last = np.float32(np.nan)
        last_at = -1
        for step in range(n):
            i = step if side == 0 else n - 1 - step
            y = line if along_rows else i
            x = i if along_rows else line
            v = disp[y, x]
            if np.isfinite(v):
                if last_at >= 0 and not (np.abs(v - last) <= jump):
                    start = last_at + 1
                last = v
                last_at = step
            reach = step - start
            if reach < arms[arm, y, x]:
                arms[arm, y, x] = reach


@njit(**KERNEL_OPTIONS)
def cut_arms_at_jumps(arms, disp, jump):
    """Shorten each arm (left, right, up, down) to end before the first step of more than
    ``jump`` between the disparities of the kept pixels along it: a support region then
    stays on one surface however alike its colours. Pixels without a kept disparity (NaN:
    rejected by the left-right check) neither end an arm nor count in a step. One scan
    each way per row and per column."""
    height, width = disp.shape
    # Rows cut the left and right arms, columns the up and down ones: no line writes
    # another's. Rows and columns interleaved in proportion (before line i come
    # i x H / (H + W) rows), so that each thread's run of lines holds as many pixels: all
    # rows first gave the first thread the rows, longer than columns on a wide view.
    lines = height + width
    for i in prange(lines):
        rows_before = (i * height) // lines
        if ((i + 1) * height) // lines > rows_before:
            _cut_line_arms(arms, disp, jump, np.int64(rows_before), True)
        else:
            _cut_line_arms(arms, disp, jump, np.int64(i - rows_before), False)
