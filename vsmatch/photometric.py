"""Exposure and lighting differences between the views (docs/results.md, "Exposure and lighting").

Census and the gradient direction do not mind a change of exposure; the colour term
(absolute differences) and the gradient magnitude do. Middlebury 2014's ``E`` and ``L``
scenes differ by up to 43 grey levels at matching pixels. The views' global histograms
cannot tell exposure from content (what one view sees and the other does not), so the
correction is learnt from pixels matched by a quick first match: each channel of the right
view is mapped onto the left's by matching the quantiles of the two views' colours over
those pixels. What the map cannot explain (a light that moved) is left as the residual:
the median colour difference of the matched pixels after the map, in grey levels, less
what the image noise alone explains. The colour term fades out as it grows.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ._kernels.photometric import corrected_colours, map_colours, matched_colours
from .config import PhotometricConfig
from .images import as_channels
from .noise import estimate_noise

#: Fewer matched pixels than this and the views are left as they are.
MIN_MATCHES = 1000
#: The residual that noise alone leaves, per grey level of the views' estimated noise
#: (``noise.estimate_noise`` on the small views the map is learnt on). Measured on
#: middlebury2 with 2-15 % noise: residual / noise estimate 3.0-3.3.
NOISE_RESIDUAL = 3.0


#: Differences of matched pixels are clipped to this many grey levels before they are
#: spread (a wrong match's would pull the field), and the field's first FIELD_DEAD_BAND
#: grey levels are dropped.
FIELD_CLIP = 24.0
FIELD_DEAD_BAND = 0.5


@dataclass(frozen=True)
class Correction:
    """The right view's per-channel map onto the left's colours, and what it leaves."""

    table: np.ndarray  # (256, channels) uint8: new value of each grey level
    residual: float  # median mean-over-channels |left - mapped right| at matched pixels
    before: float  # the same without the map
    matches: int  # pixels it was learnt from
    noise: float  # the part of the residual the views' noise explains
    # (h, w, channels) float32 at the views' size learnt on, or None: what is still to be
    # added to the mapped right view there, smooth over the image (vignetting, a colour
    # response that differs across the field of view).
    field: np.ndarray | None = None

    @property
    def excess(self) -> float:
        """The residual beyond what the noise explains (as if they added in quadrature)."""
        return float(np.sqrt(max(0.0, self.residual ** 2 - self.noise ** 2)))


def learn(left: np.ndarray, right: np.ndarray, disp: np.ndarray,
          matched: np.ndarray, field_sigma: float = 0.0) -> Correction | None:
    """The right view's map onto the left's from left pixels ``matched`` at ``disp``;
    ``None`` with fewer than :data:`MIN_MATCHES` usable pixels. With ``field_sigma`` > 0,
    also the smooth field of what the map leaves (:func:`difference_field`, a Gaussian of
    ``field_sigma`` x the width), and the residual after it."""
    ys, xr, at_left, at_right = _matched_colours(left, right, disp, matched)
    if len(ys) < MIN_MATCHES:
        return None
    width = left.shape[1]
    levels = np.arange(256)
    table = np.empty((256, at_left.shape[1]), dtype=np.uint8)
    for c in range(at_left.shape[1]):
        # Histogram matching by mid-ranks: each right grey level goes to the left level at
        # the same place in the matched pixels' distribution (counts are exact on uint8).
        ranks_l = _mid_ranks(at_left[:, c])
        present = np.bincount(at_left[:, c], minlength=256) > 0
        matched_levels = np.interp(_mid_ranks(at_right[:, c]), ranks_l[present],
                                   levels[present])
        table[:, c] = np.clip(np.rint(_one_to_one_beyond_matches(matched_levels, at_right[:, c])),
                              0, 255)
    mapped = np.empty_like(at_right)
    for c in range(at_right.shape[1]):
        mapped[:, c] = table[at_right[:, c], c]
    field = None
    if field_sigma > 0:
        field = difference_field(at_left, mapped, ys, xr, right.shape[:2],
                                 field_sigma * width)
        corrected = np.empty_like(mapped)
        corrected_colours(mapped, field, ys, xr, corrected)
        residual = _median_channel_difference(at_left, corrected)
    else:
        residual = _median_channel_difference(at_left, mapped)
    before = _median_channel_difference(at_left, at_right)
    noise = NOISE_RESIDUAL * (estimate_noise(left) + estimate_noise(right)) / 2
    return Correction(table=table, residual=residual, before=before, matches=len(ys),
                      noise=noise, field=field)


def _matched_colours(left: np.ndarray, right: np.ndarray, disp: np.ndarray,
                     matched: np.ndarray) -> tuple[np.ndarray, ...]:
    """The rows, right columns, left and right colours ((N, channels) uint8) of the
    ``matched`` left pixels whose right pixel at ``disp`` is in view, in row-major order."""
    left, right = as_channels(left), as_channels(right)
    matched = np.ascontiguousarray(matched)
    disp = np.ascontiguousarray(disp, dtype=np.float32)
    room = int(np.count_nonzero(matched))
    ys, xr = np.empty(room, np.int64), np.empty(room, np.int64)
    at_left = np.empty((room, left.shape[2]), np.uint8)
    at_right = np.empty_like(at_left)
    n = matched_colours(left, right, matched, disp, ys, xr, at_left, at_right)
    return ys[:n], xr[:n], at_left[:n], at_right[:n]


def difference_field(at_left: np.ndarray, mapped: np.ndarray, ys: np.ndarray,
                     xr: np.ndarray, shape: tuple[int, int], sigma: float) -> np.ndarray:
    """The left minus the mapped right colours of the matched pixels, placed at their
    right pixels and spread smoothly over the right view: a Gaussian-weighted mean of the
    nearby differences (normalised convolution), float32 (h, w, channels). It is smooth
    over ``sigma`` pixels, so it is summed and blurred on cells of about a quarter of that
    and resized back (a Gaussian of a tenth of the width is a large kernel)."""
    height, width = shape
    channels = at_left.shape[1]
    differences = np.clip(at_left.astype(np.float32) - mapped.astype(np.float32),
                          -FIELD_CLIP, FIELD_CLIP)  # a wrong match's difference is bounded
    cell = max(1, int(sigma // 4))
    grid_h, grid_w = -(-height // cell), -(-width // cell)
    where = (ys // cell) * grid_w + xr // cell
    counts = np.bincount(where, minlength=grid_h * grid_w).reshape(grid_h, grid_w)
    sums = np.stack([np.bincount(where, differences[:, c], minlength=grid_h * grid_w)
                     for c in range(channels)], axis=-1).reshape(grid_h, grid_w, channels)
    blur = dict(ksize=(0, 0), sigmaX=sigma / cell, borderType=cv2.BORDER_REPLICATE)
    weight = cv2.GaussianBlur(counts.astype(np.float32), **blur)
    spread = cv2.GaussianBlur(sums.astype(np.float32), **blur).reshape(grid_h, grid_w,
                                                                       channels)
    field = spread / np.maximum(weight, 1e-3)[:, :, None]
    field = cv2.resize(field, (width, height), interpolation=cv2.INTER_LINEAR)
    field = field.reshape(height, width, channels)
    # What noise and the map's rounding leave is no field: only its excess is added.
    return (np.sign(field) * np.maximum(np.abs(field) - FIELD_DEAD_BAND, 0)).astype(np.float32)


def _one_to_one_beyond_matches(mapped: np.ndarray, right_levels: np.ndarray) -> np.ndarray:
    """``mapped`` (each grey level's new value, float (256,)) in steps of one level beyond
    the lowest and the highest of the matched ``right_levels``, from its value there. The
    quantiles put every level the matches do not hold onto the left's extreme: a thin
    bright wire, unmatched a level down, lost its texture (200-240 all mapped to 201) and
    the wires their match. An exposure change moves levels; it does not merge them."""
    low, high = int(right_levels.min()), int(right_levels.max())
    out = mapped.astype(np.float64)
    out[high + 1:] = out[high] + np.arange(1, 256 - high)
    out[:low] = out[low] - np.arange(low, 0, -1)
    return out


def _mid_ranks(values: np.ndarray) -> np.ndarray:
    """For each grey level, the middle of its share of ``values`` in the sorted order
    (0..1): the empirical distribution at that level."""
    counts = np.bincount(values, minlength=256).astype(np.float64)
    return (np.cumsum(counts) - counts / 2) / len(values)


def _median_channel_difference(a: np.ndarray, b: np.ndarray) -> float:
    """Median over pixels of the mean over channels of |a - b| (uint8 arrays (N, C))."""
    # Channel by channel: numpy's sum along a short last axis is several times slower.
    total = np.zeros(len(a), np.int32)
    for c in range(a.shape[1]):
        total += np.abs(a[:, c].astype(np.int16) - b[:, c].astype(np.int16))
    counts = np.cumsum(np.bincount(total))
    return float(np.searchsorted(counts, len(total) / 2) / a.shape[1])


def apply(right: np.ndarray, correction: Correction) -> np.ndarray:
    """The right view with each channel passed through the correction's table, and its
    field (resized to the view) added."""
    if correction.field is None:
        table = correction.table.reshape(256, 1, -1)  # a column a channel, as cv2.LUT takes
        return cv2.LUT(right, table).reshape(right.shape)
    field = cv2.resize(correction.field, right.shape[1::-1], interpolation=cv2.INTER_LINEAR)
    out = np.empty(right.shape, np.uint8)
    map_colours(as_channels(right), correction.table, field.reshape(out.shape[:2] + (-1,)),
                as_channels(out))
    return out


def colour_weight(residual: float, cfg: PhotometricConfig) -> float:
    """Weight of the colour term: 1 up to ``fade_from`` grey levels of (excess) residual,
    falling linearly to 0 at ``fade_to``."""
    if residual <= cfg.fade_from:
        return 1.0
    if residual >= cfg.fade_to:
        return 0.0
    return (cfg.fade_to - residual) / (cfg.fade_to - cfg.fade_from)
