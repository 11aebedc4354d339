import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS


@njit(**KERNEL_OPTIONS)
def scanline_pass(cost, change_l, change_r, p1s, p2s, along_rows, weight, out):
    """Add ``weight`` x the path costs of both directions along every row (or column).

    C_r(p, d) = C(p, d) + min(C_r(p-r, d), C_r(p-r, d+-1) + P1,
                              min_k C_r(p-r, k) + P2) - min_k C_r(p-r, k).

    ``change_l[y, x]`` is 1 where the left image's colour changes by ``tau`` or more
    between (y, x) and its predecessor along the axis ((y, x - 1) on rows, (y - 1, x) on
    columns; 1 where there is none), ``change_r`` the same on the right image; the right
    pixel of (y, x) at d is (y, x - d). ``p1s[k]``, ``p2s[k]`` are the penalties where
    ``k`` (0, 1 or 2) of the two images change.
    """
    height, width, n_disp = cost.shape
    n_lines = height * along_rows + width * (1 - along_rows)
    length = width * along_rows + height * (1 - along_rows)
    for line in prange(n_lines):
        prev = np.empty(n_disp, dtype=np.float32)
        cur = np.empty(n_disp, dtype=np.float32)
        for direction in (1, -1):
            start = 0 if direction == 1 else length - 1
            prev_min = np.float32(0.0)
            for step in range(length):
                i = start + direction * step
                y = line * along_rows + i * (1 - along_rows)
                x = i * along_rows + line * (1 - along_rows)
                if step == 0:
                    for d in range(n_disp):
                        cur[d] = cost[y, x, d]
                else:
                    # The edge crossed from the previous pixel: stored at the later of
                    # the two pixels along the axis.
                    ey = y if (direction == 1 or along_rows == 1) else y + 1
                    ex = x if (direction == 1 or along_rows == 0) else x + 1
                    cl = change_l[ey, ex]
                    for d in range(n_disp):
                        er = ex - d
                        k = cl + (change_r[ey, er] if er >= 0 else 1)
                        q1 = p1s[k]
                        best = min(prev[d], prev_min + p2s[k])
                        if d > 0:
                            best = min(best, prev[d - 1] + q1)
                        if d < n_disp - 1:
                            best = min(best, prev[d + 1] + q1)
                        cur[d] = cost[y, x, d] + best - prev_min
                new_min = cur[0]
                for d in range(n_disp):
                    out[y, x, d] += weight * cur[d]
                    new_min = min(new_min, cur[d])
                prev_min = new_min
                prev, cur = cur, prev
