import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS


@njit(inline="always")
def _extremes(values, y, x, radius):
    """Smallest and largest finite value of ``values`` within ``radius`` of (y, x) (the
    window cut at the image's edges); inf and -inf where there is none."""
    height, width = values.shape
    low, high = np.float32(np.inf), np.float32(-np.inf)
    for v in range(max(y - radius, 0), min(y + radius + 1, height)):
        for u in range(max(x - radius, 0), min(x + radius + 1, width)):
            value = values[v, u]
            if np.isfinite(value):
                low = min(low, value)
                high = max(high, value)
    return low, high


@njit(**KERNEL_OPTIONS)
def bands_from_previous(previous, anchor, confidence, moved, unsure, motion, band, n_disp,
                        max_band, lo, count, held):
    """Each pixel's band around the last frame's estimate (``vsmatch.temporal``'s
    :func:`bands_from_previous` says which): ``lo``, ``count`` (int32) and ``held``
    (float32: the value a pixel keeps unsearched, inf elsewhere)."""
    height, width = previous.shape
    width_band = min(max_band, n_disp)
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
            if not (np.isfinite(low) and np.isfinite(high) and np.isfinite(centre)):
                lo[y, x] = 0
                count[y, x] = 0
                continue
            # Placed as vsmatch.bands.around places a band (keep the two alike).
            first = min(max(np.floor(low), 0), n_disp - 1)
            last_d = min(max(np.ceil(high), 0), n_disp - 1)
            n = last_d - first + 1
            if n > max_band:
                middle = np.rint(centre) - max_band // 2
                first = min(max(middle, 0), max(n_disp - max_band, 0))
                n = width_band
            lo[y, x] = np.int32(first)
            count[y, x] = np.int32(n)
