import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS


@njit(**KERNEL_OPTIONS)
def mirror_rows(src, fill, out):
    """``out[p, y, :W]`` = ``src[p, y]`` reversed, the rest of the row ``fill`` (planes
    ``p`` of (P, H, W) uint8 maps)."""
    planes, height, width = src.shape
    stop = out.shape[2]
    for line in prange(planes * height):
        p = line // height
        y = line % height
        for x in range(width):
            out[p, y, width - 1 - x] = src[p, y, x]
        for x in range(width, stop):
            out[p, y, x] = fill


@njit(**KERNEL_OPTIONS)
def gradient_magnitude(gx, gy, out):
    """``out`` = sqrt(gx^2 + gy^2), float32 as NumPy takes it (no fused multiply-add)."""
    height, width = gx.shape
    for y in prange(height):
        for x in range(width):
            a = gx[y, x]
            b = gy[y, x]
            out[y, x] = np.sqrt(a * a + b * b)


@njit(**KERNEL_OPTIONS)
def gradient_sum(gx, gy, out):
    """``out`` = |gx| + |gy| (float32)."""
    height, width = gx.shape
    for y in prange(height):
        for x in range(width):
            out[y, x] = abs(gx[y, x]) + abs(gy[y, x])
