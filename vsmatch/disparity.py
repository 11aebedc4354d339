"""Winner-takes-all, left-right consistency check, and filling of rejected pixels (§4)."""

from __future__ import annotations

import numpy as np

from ._kernels import disparity as _k
from ._kernels.rows import thread_classes
from .bands import Bands, of
from .config import FillConfig
from .images import as_channels

#: How vsmatch marks a pixel without a disparity estimate (also in PFM output).
INVALID_DISPARITY = np.float32(np.inf)

#: Labels of the left-right check.
VALID, OCCLUDED, MISMATCHED = _k.VALID, _k.OCCLUDED, _k.MISMATCHED
#: The winner of a pixel (either view) that has no candidate in its band.
NO_DISPARITY = _k.NO_DISPARITY


def labels_for_kernels(labels: np.ndarray | None) -> np.ndarray:
    """The check's ``labels`` as the kernels read them (uint8, C-contiguous); an empty
    array where there are none, which the kernels take as every pixel valid."""
    if labels is None:
        return np.empty((0, 0), np.uint8)
    return np.ascontiguousarray(labels, np.uint8)


def winner_takes_all(volume: np.ndarray, bands: Bands | None = None) -> np.ndarray:
    """Left-view disparity ``argmin_d C(p, d)`` over each pixel's band (default: the whole
    range) as int32 (H, W); ties take the smaller d; ``NO_DISPARITY`` without a band."""
    bands = of(volume, bands)
    out = np.empty(volume.shape[:2], dtype=np.int32)
    _k.winner_takes_all(volume, bands.lo, bands.count, out)
    return out


def winner_takes_all_both(volume: np.ndarray, bands: Bands | None = None
                          ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`winner_takes_all` of the left view and the right view's disparity
    ``argmin_d C((x + d, y), d)`` (over the left pixels' bands) in one pass."""
    bands = of(volume, bands)
    out_l = np.empty(volume.shape[:2], dtype=np.int32)
    out_r = np.empty(volume.shape[:2], dtype=np.int32)
    none = np.empty((0, 0), np.float32)
    _k.winner_takes_all_both(volume, bands.lo, bands.count, out_l, out_r, 1, none, none, none)
    return out_l, out_r


def winner_takes_all_with_curve(volume: np.ndarray, exclude: int = 1,
                                bands: Bands | None = None
                                ) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, ...]]:
    """:func:`winner_takes_all_both`, and the left winners' cost curves (best, second
    minimum at least ``exclude + 1`` away, mean; see ``vsmatch.confidence``) from the
    same pass."""
    bands = of(volume, bands)
    out_l = np.empty(volume.shape[:2], dtype=np.int32)
    out_r = np.empty(volume.shape[:2], dtype=np.int32)
    curve = tuple(np.empty(volume.shape[:2], np.float32) for _ in range(3))
    _k.winner_takes_all_both(volume, bands.lo, bands.count, out_l, out_r, int(exclude),
                             *curve)
    return out_l, out_r, curve


def left_right_check(disp_l: np.ndarray, disp_r: np.ndarray, *, n_disp: int,
                     tolerance: int) -> np.ndarray:
    """Labels (uint8, (H, W)): VALID where ``|d_L(p) - d_R(x - d_L(p))| <= tolerance``;
    otherwise OCCLUDED when no disparity would pass the check, else MISMATCHED."""
    labels = np.empty(disp_l.shape, dtype=np.uint8)
    _k.left_right_check(np.ascontiguousarray(disp_l, dtype=np.int32),
                        np.ascontiguousarray(disp_r, dtype=np.int32),
                        int(n_disp), int(tolerance), labels)
    return labels


def search_directions(count: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit steps ``(dy, dx)`` of ``count`` directions evenly spread over the circle.

    The largest component is 1 so a walk visits every row or column it crosses.
    """
    angles = np.arange(count) * (2.0 * np.pi / count)
    dy, dx = np.sin(angles), np.cos(angles)
    scale = np.maximum(np.abs(dy), np.abs(dx))
    return dy / scale, dx / scale


def fill_rejected(disp: np.ndarray, labels: np.ndarray, image: np.ndarray,
                  cfg: FillConfig) -> np.ndarray:
    """Give each rejected pixel a disparity from the valid pixels around it (float32).

    Occluded pixels take the lowest of the first valid disparities found along the search
    directions (the background); mismatched ones the one whose colour is most similar.
    """
    steps_y, steps_x = search_directions(cfg.directions)
    out = np.empty(disp.shape, dtype=np.float32)
    _k.fill_rejected(np.ascontiguousarray(disp, dtype=np.float32), labels,
                     as_channels(image), steps_y, steps_x, int(cfg.max_search),
                     INVALID_DISPARITY, thread_classes(), out)
    return out


def mark_rejected(disp: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """float32 disparity with rejected pixels set to :data:`INVALID_DISPARITY`."""
    out = disp.astype(np.float32)
    out[labels != VALID] = INVALID_DISPARITY
    return out
