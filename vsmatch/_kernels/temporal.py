import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS
from .bands import extremes_near as _extremes, placed


@njit(**KERNEL_OPTIONS)
def bands_from_previous(previous, anchor, confidence, moved, unsure, motion, band, n_disp,
                        max_band, lo, count, held):
    """Each pixel's band around the last frame's estimate (``vsmatch.temporal``'s
    :func:`bands_from_previous` says which): ``lo``, ``count`` (int32) and ``held``
    (float32: the value a pixel keeps unsearched, inf elsewhere)."""
    height, width = previous.shape
    for y in prange(height):
        for x in range(width):
            last = previous[y, x]
            was_moved = moved[y, x]
            is_unsure = confidence[y, x] < unsure and not was_moved
            if not was_moved and not is_unsure and np.isfinite(last):
                lo[y, x] = 0  # still and sure: kept, not searched
                count[y, x] = 0
                held[y, x] = last
                continue
            held[y, x] = np.inf
            low, high = _extremes(previous, y, x, 1)
            centre = last
            if is_unsure:
                anchor_low, anchor_high = _extremes(anchor, y, x, 1)
                if np.isfinite(anchor_low):
                    low, high = anchor_low, anchor_high
                    if np.isfinite(anchor[y, x]):
                        centre = anchor[y, x]
            if was_moved and motion > 0:
                low, high = _extremes(previous, y, x, motion)
            if not np.isfinite(centre):
                centre = (low + high) / np.float32(2)
            low = low - np.float32(band)
            high = high + np.float32(band)
            lo[y, x], count[y, x], _ = placed(low, high, centre, n_disp, max_band)
