import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS
from .arms import colour_distance


@njit(**KERNEL_OPTIONS)
def scanline_pass(cost, image_l, image_r, p1, p2, tau, reduce_one, reduce_both,
                  along_rows, weight, out):
    """Add ``weight`` x the path costs of both directions along every row (or column).

    C_r(p, d) = C(p, d) + min(C_r(p-r, d), C_r(p-r, d+-1) + P1,
                              min_k C_r(p-r, k) + P2) - min_k C_r(p-r, k).
    P1, P2 are divided by ``reduce_one`` when the colour changes by ``tau`` or more from
    p - r to p in one of the two images, by ``reduce_both`` when it does in both.
    """
    height, width, n_disp = cost.shape
    n_lines = height * along_rows + width * (1 - along_rows)
    length = width * along_rows + height * (1 - along_rows)
    for line in prange(n_lines):
        prev = np.empty(n_disp, dtype=np.float32)
        cur = np.empty(n_disp, dtype=np.float32)
        for direction in (1, -1):
            start = 0 if direction == 1 else length - 1
            for step in range(length):
                i = start + direction * step
                y = line * along_rows + i * (1 - along_rows)
                x = i * along_rows + line * (1 - along_rows)
                if step == 0:
                    for d in range(n_disp):
                        cur[d] = cost[y, x, d]
                else:
                    # The previous pixel on the path.
                    py = y - direction * (1 - along_rows)
                    px = x - direction * along_rows
                    prev_min = prev[0]
                    for d in range(1, n_disp):
                        if prev[d] < prev_min:
                            prev_min = prev[d]
                    change_l = colour_distance(image_l, y, x, py, px) >= tau
                    for d in range(n_disp):
                        xr, pxr = x - d, px - d
                        change_r = True
                        if xr >= 0 and pxr >= 0:
                            change_r = colour_distance(image_r, y, xr, py, pxr) >= tau
                        if change_l and change_r:
                            q1, q2 = p1 / reduce_both, p2 / reduce_both
                        elif change_l or change_r:
                            q1, q2 = p1 / reduce_one, p2 / reduce_one
                        else:
                            q1, q2 = p1, p2
                        best = min(prev[d], prev_min + q2)
                        if d > 0:
                            best = min(best, prev[d - 1] + q1)
                        if d < n_disp - 1:
                            best = min(best, prev[d + 1] + q1)
                        cur[d] = cost[y, x, d] + best - prev_min
                for d in range(n_disp):
                    out[y, x, d] += weight * cur[d]
                prev, cur = cur, prev
