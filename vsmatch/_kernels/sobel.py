import numpy as np
from numba import njit

from . import SERIAL_OPTIONS


@njit(inline="always")
def sobel_at(up, here, down, west, x, east):
    """The 3 x 3 Sobel derivatives (gx, gy) at column ``x`` of the row ``here``, float32,
    ``west`` and ``east`` the columns either side. On whole numbers (grey levels) every sum
    is exact, so any order of the additions gives cv2.Sobel's values."""
    gx = ((np.float32(up[east]) + 2 * np.float32(here[east]) + np.float32(down[east]))
          - (np.float32(up[west]) + 2 * np.float32(here[west]) + np.float32(down[west])))
    gy = ((np.float32(down[west]) + 2 * np.float32(down[x]) + np.float32(down[east]))
          - (np.float32(up[west]) + 2 * np.float32(up[x]) + np.float32(up[east])))
    return gx, gy


@njit(inline="always")
def mirrored_index(i, n):
    """Index ``i`` mirrored into 0 .. n - 1 about the edge lines (BORDER_REFLECT_101),
    for ``i`` at most one step outside."""
    if n == 1:
        return 0
    if i < 0:
        return -i
    if i >= n:
        return 2 * n - 2 - i
    return i


@njit(**SERIAL_OPTIONS)
def gradient_magnitude(grey, out):
    """``out`` = sqrt(gx^2 + gy^2) of the 3 x 3 Sobel derivatives of ``grey`` (float32,
    borders mirrored as OpenCV's BORDER_REFLECT_101). One core: one pass where two Sobel
    filters and NumPy's three took five (0.64 against 1.76 ms on a 718 x 496 view; 0.41
    on two threads, for four times the compiling)."""
    height, width = grey.shape
    for y in range(height):
        up, here = grey[mirrored_index(y - 1, height)], grey[y]
        down = grey[mirrored_index(y + 1, height)]
        row = out[y]
        for x in range(1, width - 1):
            gx, gy = sobel_at(up, here, down, x - 1, x, x + 1)
            row[x] = np.sqrt(gx * gx + gy * gy)
        for x in (0, width - 1):
            gx, gy = sobel_at(up, here, down, mirrored_index(x - 1, width), x,
                              mirrored_index(x + 1, width))
            row[x] = np.sqrt(gx * gx + gy * gy)
