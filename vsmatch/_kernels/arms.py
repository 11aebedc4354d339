import math

import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS, SERIAL_OPTIONS

# Arm order in the first axis of an arms array, (4, H, W).
LEFT, RIGHT, UP, DOWN = 0, 1, 2, 3


@njit(inline="always")
def colour_distance(image, y0, x0, y1, x1):
    """Largest absolute difference over the colour channels (an integer)."""
    if image.shape[2] == 3:  # written out: the common case, and the hot one
        return max(abs(np.int32(image[y0, x0, 0]) - np.int32(image[y1, x1, 0])),
                   abs(np.int32(image[y0, x0, 1]) - np.int32(image[y1, x1, 1])),
                   abs(np.int32(image[y0, x0, 2]) - np.int32(image[y1, x1, 2])))
    best = np.int32(0)
    for k in range(image.shape[2]):
        best = max(best, abs(np.int32(image[y0, x0, k]) - np.int32(image[y1, x1, k])))
    return best


@njit(inline="always")
def _step(here, before, x):
    """|here[x] - before[x]| of 8-bit grey levels held in 16 bits."""
    v = np.int16(here[x] - before[x])
    return v if v >= 0 else -v


@njit(**ROW_OPTIONS)
def _colour_change_of_row(planes, threshold, along_rows, out, y):
    """:func:`colour_change` of row ``y``: the previous pixels as a slice a pixel behind (no
    index Numba must check for a wrap-around), the distances in 16-bit lanes against the
    threshold rounded up (an integer distance d is >= t where it is >= ceil(t))."""
    channels = planes.shape[0]
    limit = np.int16(min(max(math.ceil(threshold), -32768), 32767))
    row = out[y]
    if along_rows:
        row[0] = 1
        target, first, previous = row[1:], np.int64(1), y
    elif y == 0:
        row[:] = 1
        return
    else:
        target, first, previous = row, np.int64(0), y - 1
    count = target.shape[0]
    if channels == 3 or channels == 1:  # written out: colour or grey views, the hot cases
        mid, top = min(1, channels - 1), channels - 1  # grey: channel 0 three times
        here_a, before_a = planes[0, y, first:], planes[0, previous, :count]
        here_b, before_b = planes[mid, y, first:], planes[mid, previous, :count]
        here_c, before_c = planes[top, y, first:], planes[top, previous, :count]
        for x in range(count):
            a = _step(here_a, before_a, x)
            b = _step(here_b, before_b, x)
            c = _step(here_c, before_c, x)
            d = a if a > b else b
            d = d if d > c else c
            target[x] = d >= limit
        return
    for x in range(count):
        d = np.int16(0)
        for c in range(channels):
            v = _step(planes[c, y, first:], planes[c, previous, :count], x)
            d = v if v > d else d
        target[x] = d >= limit


@njit(**SERIAL_OPTIONS)
def colour_change(planes, threshold, along_rows, out):
    """out[y, x] = 1 where the colour distance between (y, x) and its predecessor along the
    axis is ``threshold`` or more, and where there is none. ``planes``: the view as (C, H,
    W) int16 planes (``channel_planes``): each channel's pixels side by side, the loop
    vectorises (10-14x the interleaved (H, W, C) view's time on a 640 x 480 view). On one
    core: a map takes a tenth of a millisecond, and a parallel kernel a second more to
    compile."""
    height = out.shape[0]
    for y in range(height):
        _colour_change_of_row(planes, threshold, along_rows, out, np.int64(y))


@njit(inline="always")
def _thresholds(theta, strength, y, tau1, tau3, kappa, horizontal, th1, th3):
    """The integer colour thresholds of row ``y``'s pixels for arms along one axis
    (``horizontal``: left and right): tau1 and tau3 scaled by
    f = 1 + kappa * |cos(theta - phi)| * s_p (phi = 0 for horizontal arms, pi/2 for
    vertical ones) and rounded up, as the colour distances are integers."""
    for x in range(th1.shape[0]):
        f = 1.0
        if kappa != 0.0:
            c = abs(np.cos(theta[y, x])) if horizontal else abs(np.sin(theta[y, x]))
            f = max(0.0, 1.0 + kappa * c * strength[y, x])
        th1[x] = math.ceil(tau1 * f)
        th3[x] = math.ceil(tau3 * f)


@njit(inline="always")
def _grow_row(planes, y_n, y, shift, first, stop, brk_row, brk_shift, lim1, lim3, dist,
              alive, arm):
    """One step of the arms of row ``y``'s pixels ``first .. stop - 1`` at once: pixel x
    against its neighbour ``x + shift`` of row ``y_n``, whose break flag is
    ``brk_row[x + brk_shift]``. An arm grows while the colour distance stays below
    ``lim1[x]`` and ``lim3[x]``. Each loop runs over contiguous slices (whose indexes
    Numba knows are >= 0) without branches, so LLVM vectorises it, in 16-bit lanes: the
    grey levels' differences (of 8-bit views), the thresholds (at most 255 x 11) and the
    lengths (at most 255) all fit, and twice the lanes of 32 bits fit a vector (the kernel
    1.8-2.2x faster than with int32 buffers, whose distances LLVM took in 64-bit lanes).
    Returns the range of pixels whose arms still grow."""
    count = stop - first
    anchor = planes[0, y, first:stop]
    near = planes[0, y_n, first + shift:stop + shift]
    for i in range(count):
        dist[i] = _step(near, anchor, i)
    for c in range(1, planes.shape[0]):
        anchor = planes[c, y, first:stop]
        near = planes[c, y_n, first + shift:stop + shift]
        for i in range(count):
            v = _step(near, anchor, i)
            d = dist[i]
            dist[i] = v if v > d else d
    brk = brk_row[first + brk_shift:stop + brk_shift]
    low, high = lim1[first:stop], lim3[first:stop]
    live, length = alive[first:stop], arm[first:stop]
    for i in range(count):
        a = dist[i]
        ok = np.int16(brk[i] == 0) & np.int16(a < low[i]) & np.int16(a < high[i])
        still = live[i] & ok
        live[i] = still
        length[i] += still
    while first < stop and alive[first] == 0:
        first += 1
    while stop > first and alive[stop - 1] == 0:
        stop -= 1
    return first, stop


@njit(**ROW_OPTIONS)
def _arms_of_row(planes, theta, strength, breaks_h, breaks_v, tau1, tau3, l1, l2, kappa,
                 shrink_over, y, out):
    """:func:`cross_arms` of row ``y``'s pixels (``shrink_over``: l2 where the threshold
    shrinks, else 0)."""
    height, width = planes.shape[1], planes.shape[2]
    th1 = np.empty(width, np.int16)
    th3 = np.empty(width, np.int16)
    faded = np.empty(width, np.int16)
    dist = np.empty(width, np.int16)
    alive = np.empty(width, np.int16)
    arm = np.empty(width, np.int16)
    for axis in range(2):  # 0: left and right arms, 1: up and down
        _thresholds(theta, strength, y, tau1, tau3, kappa, axis == 0, th1, th3)
        for side in range(2):
            arm[:] = 0
            alive[:] = 1
            first, stop = 0, width
            for k in range(1, l2 + 1):
                # Integer distances: a < t (real) is a < ceil(t).
                lim1 = th1
                if shrink_over > 0:
                    fade = 1.0 - k / shrink_over
                    for x in range(width):
                        faded[x] = min(th1[x], math.ceil(th1[x] * fade))
                    lim1 = faded
                lim3 = th3 if k > l1 else lim1
                # One call site of the inlined step: four would compile four copies.
                if axis == 0:
                    # Pixels within k of the border have no k-th neighbour.
                    y_n = y
                    brk = breaks_h[y]
                    if side == 0:  # left: x - k; the break between x-k and x-k+1
                        first = max(first, k)
                        shift, brk_shift = np.int64(-k), np.int64(1 - k)
                    else:  # right: x + k; the break at x + k
                        stop = min(stop, width - k)
                        shift, brk_shift = np.int64(k), np.int64(k)
                else:
                    y_n = np.int64(y) - k if side == 0 else np.int64(y) + k
                    if y_n < 0 or y_n >= height:
                        break
                    # The break between rows y_n and y_n + 1 (up) or y_n - 1 (down) is
                    # stored at the later row.
                    brk = breaks_v[y_n + 1] if side == 0 else breaks_v[y_n]
                    shift, brk_shift = np.int64(0), np.int64(0)
                first, stop = _grow_row(planes, y_n, y, shift, first, stop, brk, brk_shift,
                                        lim1, lim3, dist, alive, arm)
                if first >= stop:
                    break
            for x in range(width):
                out[2 * axis + side, y, x] = arm[x]  # LEFT, RIGHT, UP, DOWN


@njit(**KERNEL_OPTIONS)
def cross_arms(planes, theta, strength, breaks_h, breaks_v, tau1, tau3, l1, l2, kappa, shrink,
               out):
    """Arm lengths (left, right, up, down) of every pixel, as in ALGORITHM.md §3.

    ``planes``: the image as (C, H, W) int16, 8-bit grey levels. ``strength`` is s_p =
    min(1, G / G_sat), ``theta`` the gradient direction (read only where ``kappa`` != 0).
    ``breaks_h``, ``breaks_v``: 1 where the colour changes by tau2 or more from the previous
    pixel along the row, along the column. ``shrink``: the colour threshold falls linearly
    to 0 at l2 pixels (the authors' published code).

    A row at a time: step k tests the k-th neighbour of every pixel of the row at once,
    between the first and the last pixel whose arm still grows. The tests vectorise and no
    branch depends on where an arm ends: on the twelve standard left views 3.2x faster
    than growing one arm after another (l2 20; 2.4x at l2 40).
    """
    height = planes.shape[1]
    shrink_over = float(l2) if shrink else 0.0
    for y in prange(height):
        _arms_of_row(planes, theta, strength, breaks_h, breaks_v, tau1, tau3, l1, l2, kappa,
                     shrink_over, np.int64(y), out)
