import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS, SERIAL_OPTIONS


#: Rows of a volume that :func:`box_mean` slides one window sum down (a band's first row
#: sums its window afresh): fixed, so the sums do not depend on the threads; few, so a
#: small view's rows still make a job for every core.
BOX_BAND_ROWS = 8


@njit(**ROW_OPTIONS)
def _box_mean_of_band(volume, box, rows_at, columns_at, out, band):
    """:func:`box_mean` of the rows of band ``band``."""
    height, width, depth = volume.shape
    first, stop = band * BOX_BAND_ROWS, min(height, (band + 1) * BOX_BAND_ROWS)
    scale = 1.0 / (box * box)
    rows = np.zeros((width, depth))  # each column's sums over the window's rows
    for k in range(box):
        src = volume[rows_at[first + k]]
        for x in range(width):
            for d in range(depth):
                rows[x, d] += src[x, d]
    window = np.empty(depth)
    for y in range(first, stop):
        if y > first:
            enter = volume[rows_at[y + box - 1]]
            leave = volume[rows_at[y - 1]]
            for x in range(width):
                for d in range(depth):
                    rows[x, d] += np.float64(enter[x, d]) - np.float64(leave[x, d])
        window[:] = 0.0
        for k in range(box):
            column = rows[columns_at[k]]
            for d in range(depth):
                window[d] += column[d]
        for x in range(width):
            if x > 0:
                enter_x = rows[columns_at[x + box - 1]]
                leave_x = rows[columns_at[x - 1]]
                for d in range(depth):
                    window[d] += enter_x[d] - leave_x[d]
            for d in range(depth):
                out[y, x, d] = window[d] * scale


@njit(**KERNEL_OPTIONS)
def box_mean(volume, box, rows_at, columns_at, out):
    """The mean of each (H, W, D) volume slice over ``box`` x ``box`` windows, as
    ``cv2.blur`` takes it, in float64 sums: down bands of :data:`BOX_BAND_ROWS` rows the
    window's rows are summed once and then slid (a row in, a row out), and along each row
    the window slides. ``rows_at[y + k]`` and ``columns_at[x + k]`` are the rows and
    columns the window's k-th line reads (the borders mirrored). Summed afresh for every
    row, with its sums allocated a row at a time, the quick first match's blur gained 1.4x
    from 1 thread to 2."""
    bands = (volume.shape[0] + BOX_BAND_ROWS - 1) // BOX_BAND_ROWS
    for band in prange(bands):
        _box_mean_of_band(volume, box, rows_at, columns_at, out, np.int64(band))


#: Rows of a plane that :func:`plane_box_mean` slides one window sum down (a band's first
#: row sums its window afresh): fixed, so the sums do not depend on the threads.
BLUR_BAND_ROWS = 16


@njit(**ROW_OPTIONS)
def _plane_box_mean_of_band(planes, box, rows_at, columns_at, out, job):
    """:func:`plane_box_mean` of one band of rows of one plane (``job`` = plane x bands +
    band)."""
    height, width = planes.shape[1], planes.shape[2]
    bands = (height + BLUR_BAND_ROWS - 1) // BLUR_BAND_ROWS
    k, band = job // bands, job % bands
    first, stop = band * BLUR_BAND_ROWS, min(height, (band + 1) * BLUR_BAND_ROWS)
    scale = 1.0 / (box * box)
    columns = np.zeros(width)  # each column's sum over the window's rows
    for i in range(box):
        src = planes[k, rows_at[first + i]]
        for x in range(width):
            columns[x] += src[x]
    for y in range(first, stop):
        if y > first:
            enter, leave = planes[k, rows_at[y + box - 1]], planes[k, rows_at[y - 1]]
            for x in range(width):
                columns[x] += np.float64(enter[x]) - np.float64(leave[x])
        window = 0.0
        for i in range(box):
            window += columns[columns_at[i]]
        for x in range(width):
            if x > 0:
                window += columns[columns_at[x + box - 1]] - columns[columns_at[x - 1]]
            out[k, y, x] = window * scale


@njit(**KERNEL_OPTIONS)
def plane_box_mean(planes, box, rows_at, columns_at, out):
    """:func:`box_mean` of each (H, W) plane of ``planes`` (K, H, W), in float64 sums that
    slide down bands of :data:`BLUR_BAND_ROWS` rows and along each row (exact for sums of
    whole numbers; on other float32 values within float64 rounding of cv2.blur's)."""
    bands = (planes.shape[1] + BLUR_BAND_ROWS - 1) // BLUR_BAND_ROWS
    for job in prange(planes.shape[0] * bands):
        _plane_box_mean_of_band(planes, box, rows_at, columns_at, out, np.int64(job))


@njit(**SERIAL_OPTIONS)
def matched_colours(left, right, matched, disp, ys, xr, at_left, at_right):
    """The rows, right columns and colours (left and right) of the ``matched`` left pixels
    whose right pixel x - round(d) is in view, in row-major order; returns how many (the
    outputs hold room for every matched pixel)."""
    height, width, channels = left.shape
    i = 0
    for y in range(height):
        for x in range(width):
            if not matched[y, x]:
                continue
            x_r = x - np.int64(np.rint(disp[y, x]))
            if x_r < 0:
                continue
            ys[i] = y
            xr[i] = x_r
            for c in range(channels):
                at_left[i, c] = left[y, x, c]
                at_right[i, c] = right[y, x_r, c]
            i += 1
    return i


@njit(**SERIAL_OPTIONS)
def corrected_colours(mapped, field, ys, xr, out):
    """out = clip(rint(mapped + field at (ys, xr)), 0, 255) as uint8, (N, channels): the
    matched pixels of the small views, on one core (parallel, 0.7x the time)."""
    n, channels = mapped.shape
    for i in range(n):
        for c in range(channels):
            v = np.rint(np.float32(mapped[i, c]) + field[ys[i], xr[i], c])
            out[i, c] = np.uint8(min(np.float32(255.0), max(np.float32(0.0), v)))


@njit(**KERNEL_OPTIONS)
def map_colours(view, table, field, out):
    """out = clip(rint(table[view] + field), 0, 255) as uint8 for (H, W, C) ``view``,
    ``table`` (256, C) and float32 ``field`` (H, W, C)."""
    height, width, channels = view.shape
    for y in prange(height):
        for x in range(width):
            for c in range(channels):
                v = np.rint(np.float32(table[view[y, x, c], c]) + field[y, x, c])
                out[y, x, c] = np.uint8(min(np.float32(255.0), max(np.float32(0.0), v)))
