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


@njit(inline="always")
def _grow_arm(image, y, x, step_y, step_x, limit, tau1_dir, tau2, tau3_dir, l1):
    """Length of the arm from (y, x) along (step_y, step_x), at most ``limit`` pixels."""
    k = 0
    while k < limit:
        ny = y + (k + 1) * step_y
        nx = x + (k + 1) * step_x
        to_anchor = colour_distance(image, ny, nx, y, x)
        if to_anchor >= tau1_dir:
            break
        if colour_distance(image, ny, nx, ny - step_y, nx - step_x) >= tau2:
            break
        if k + 1 > l1 and to_anchor >= tau3_dir:
            break
        k += 1
    return k


@njit(**KERNEL_OPTIONS)
def cross_arms(image, theta, strength, tau1, tau2, tau3, l1, l2, kappa, out):
    """Arm lengths (left, right, up, down) of every pixel, as in ALGORITHM.md §3.

    ``strength`` is s_p = min(1, G / G_sat). The colour thresholds tau1 and tau3 are scaled
    by f = 1 + kappa * |cos(theta - phi)| * s_p, phi = 0 for horizontal arms and pi/2 for
    vertical ones.
    """
    height, width = theta.shape
    for y in prange(height):
        for x in range(width):
            s = strength[y, x]
            fh = max(0.0, 1.0 + kappa * abs(np.cos(theta[y, x])) * s)
            fv = max(0.0, 1.0 + kappa * abs(np.sin(theta[y, x])) * s)
            th1, th3 = tau1 * fh, tau3 * fh
            out[LEFT, y, x] = _grow_arm(image, y, x, 0, -1, min(l2, x), th1, tau2, th3, l1)
            out[RIGHT, y, x] = _grow_arm(image, y, x, 0, 1, min(l2, width - 1 - x),
                                         th1, tau2, th3, l1)
            tv1, tv3 = tau1 * fv, tau3 * fv
            out[UP, y, x] = _grow_arm(image, y, x, -1, 0, min(l2, y), tv1, tau2, tv3, l1)
            out[DOWN, y, x] = _grow_arm(image, y, x, 1, 0, min(l2, height - 1 - y),
                                        tv1, tau2, tv3, l1)
