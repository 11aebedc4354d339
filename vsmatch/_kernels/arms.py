import math

import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS

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


@njit(**KERNEL_OPTIONS)
def colour_change(image, threshold, along_rows, out):
    """out[y, x] = 1 where the colour distance between (y, x) and its predecessor along the
    axis is ``threshold`` or more, and where there is none."""
    height, width = out.shape
    for y in prange(height):
        for x in range(width):
            if (x == 0) if along_rows else (y == 0):
                out[y, x] = 1
            else:
                out[y, x] = colour_distance(image, y, x, y - 1 + along_rows,
                                            x - along_rows) >= threshold


@njit(inline="always")
def _grow_arm(image, breaks, y, x, step_y, step_x, limit, tau1_dir, tau3_dir, l1,
              shrink_over):
    """Length of the arm from (y, x) along (step_y, step_x), at most ``limit`` pixels.

    ``breaks`` marks the steps across which the colour changes by tau2 or more, stored at
    the later pixel of the two in image order. The thresholds are integers (the distances
    are), rounded up from the scaled ones. With ``shrink_over`` > 0 the colour threshold
    falls linearly with the arm's length, tau1 (1 - k / shrink_over) at its k-th pixel.
    """
    k = 0
    while k < limit:
        ny = y + (k + 1) * step_y
        nx = x + (k + 1) * step_x
        if breaks[ny - min(step_y, 0), nx - min(step_x, 0)]:
            break
        to_anchor = colour_distance(image, ny, nx, y, x)
        if to_anchor >= tau1_dir:
            break
        if shrink_over > 0 and to_anchor >= tau1_dir * (1.0 - (k + 1) / shrink_over):
            break
        if k + 1 > l1 and to_anchor >= tau3_dir:
            break
        k += 1
    return k


@njit(**KERNEL_OPTIONS)
def cross_arms(image, theta, strength, breaks_h, breaks_v, tau1, tau3, l1, l2, kappa, shrink,
               out):
    """Arm lengths (left, right, up, down) of every pixel, as in ALGORITHM.md §3.

    ``strength`` is s_p = min(1, G / G_sat). The colour thresholds tau1 and tau3 are scaled
    by f = 1 + kappa * |cos(theta - phi)| * s_p, phi = 0 for horizontal arms and pi/2 for
    vertical ones. ``breaks_h``, ``breaks_v``: 1 where the colour changes by tau2 or more
    from the previous pixel along the row, along the column. ``shrink``: the colour
    threshold falls linearly to 0 at l2 pixels (the authors' published code).
    """
    height, width = strength.shape
    shrink_over = float(l2) if shrink else 0.0
    for y in prange(height):
        for x in range(width):
            fh = 1.0
            fv = 1.0
            if kappa != 0.0:  # the cosine and sine cost as much as the arms themselves
                s = strength[y, x]
                fh = max(0.0, 1.0 + kappa * abs(np.cos(theta[y, x])) * s)
                fv = max(0.0, 1.0 + kappa * abs(np.sin(theta[y, x])) * s)
            th1, th3 = math.ceil(tau1 * fh), math.ceil(tau3 * fh)
            tv1, tv3 = math.ceil(tau1 * fv), math.ceil(tau3 * fv)
            out[LEFT, y, x] = _grow_arm(image, breaks_h, y, x, 0, -1, min(l2, x),
                                        th1, th3, l1, shrink_over)
            out[RIGHT, y, x] = _grow_arm(image, breaks_h, y, x, 0, 1, min(l2, width - 1 - x),
                                         th1, th3, l1, shrink_over)
            out[UP, y, x] = _grow_arm(image, breaks_v, y, x, -1, 0, min(l2, y),
                                      tv1, tv3, l1, shrink_over)
            out[DOWN, y, x] = _grow_arm(image, breaks_v, y, x, 1, 0, min(l2, height - 1 - y),
                                        tv1, tv3, l1, shrink_over)
