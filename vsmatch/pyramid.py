"""Coarse-to-fine search: the full search on a reduced image, a narrow band per pixel above.

Work and memory of the full search grow as width x height x disparities. Where a row holds
more than ``pyramid.max_row_cells`` width x disparity cells, the views are halved
(``cv2.pyrDown``) until it does not; the whole method runs there, and each finer level
searches only the disparities around the upsampled coarser estimate: from twice the
smallest to twice the largest coarse disparity of the 3 x 3 coarse neighbourhood, widened
by ``pyramid.band`` (so both sides of a depth edge stay candidates). The cost of a
candidate is summed over the pixel's cross (arms capped at ``pyramid.support`` pixels of
its level), from census, gradient and colour terms computed on the fly. Every parameter is
measured in pixels of the level it runs on.
"""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np

from . import aggregation, cost, noise, optimization, refinement, sensitivity
from ._kernels.band import RUN, band_aggregate, band_costs, band_winners, search_band
from .config import Config
from .disparity import VALID
from .images import to_grey, upsample_nearest
from .tiles import row_blocks, stripe_layout

#: Rows refined at a time at a fine level. The result does not depend on it (every pixel
#: reads only its cross, inside the margin); it bounds the memory of the per-pixel arrays.
REFINE_ROWS = 256


#: Disparities the level below must keep for ``pyramid.min_levels`` to go down to it.
MIN_FORCED_DISPARITIES = 10


def coarse_levels(width: int, n_disp: int, max_row_cells: int, min_levels: int = 0,
                  height: int = 0, max_cells: int = 0) -> int:
    """How many times to halve a pair before the full search: while a row holds more
    than ``max_row_cells`` cells; at least once if the pair of ``height`` rows holds more
    than ``max_cells`` (> 0) cells (a camera-size pair: the bands above a halved full search
    keep its accuracy, where a second level down loses it); never below 64 columns or 16
    disparities; and at least ``min_levels`` times (the ``fast`` config's coarse-to-fine at
    every size) while the level below keeps :data:`MIN_FORCED_DISPARITIES` (a small range
    halved leaves too little to choose from: tsukuba's 16 went to 8, bad 1.0 3.2 -> 7.4;
    venus's 20 to 10 did not hurt)."""
    levels = 0
    while ((width * n_disp > max_row_cells
            or (levels == 0 and 0 < max_cells < width * height * n_disp)
            or (levels < min_levels and n_disp >= 2 * MIN_FORCED_DISPARITIES))
           and width >= 64 and n_disp >= 16):
        width, max_disp = level_down(width, n_disp - 1)
        n_disp = max_disp + 1
        height = (height + 1) // 2
        levels += 1
    return levels


def level_down(width: int, max_disp: int) -> tuple[int, int]:
    """Width and largest disparity one level down (as :func:`downsample` halves the width),
    the range kept below the width."""
    width = (width + 1) // 2
    return width, min(int(math.ceil(max_disp / 2)), width - 1)


def coarse_extremes(coarse: np.ndarray, coarse_labels: np.ndarray | None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest valid coarse disparity of each pixel's 3 x 3 neighbourhood
    (float32; inf and -inf where there is none).

    Where the coarse level rejected the pixel (occluded or mismatched, then filled), its
    own filled value only: the neighbours' disparities there are mostly the occluder's.
    """
    valid = np.isfinite(coarse)
    kernel = np.ones((3, 3), np.uint8)
    low = cv2.erode(np.where(valid, coarse, np.inf).astype(np.float32), kernel,
                    borderType=cv2.BORDER_REPLICATE)
    high = cv2.dilate(np.where(valid, coarse, -np.inf).astype(np.float32), kernel,
                      borderType=cv2.BORDER_REPLICATE)
    if coarse_labels is not None:
        unsure = (coarse_labels != VALID) & valid
        low[unsure] = coarse[unsure]
        high[unsure] = coarse[unsure]
    low[~valid], high[~valid] = np.inf, -np.inf
    return low, high


def search_bands(low: np.ndarray, high: np.ndarray, max_disp: int, band: int
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Disparities to search at fine pixels whose coarse pixel's extremes
    (:func:`coarse_extremes`, upsampled) are ``low`` and ``high``: from twice ``low`` to
    twice ``high``, widened by ``band``; int32, ``lo > hi`` where there is no estimate."""
    none = ~(low <= high)
    # Twice a float32 is exact in float32, and so are floor and ceil of it.
    lo = np.clip(np.floor(2 * np.where(none, 0, low)) - band, 0, max_disp).astype(np.int32)
    hi = np.clip(np.ceil(2 * np.where(none, 0, high)) + band, 0, max_disp).astype(np.int32)
    lo[none], hi[none] = 1, 0
    return lo, hi


def refine(left: np.ndarray, right: np.ndarray, coarse: np.ndarray,
           coarse_labels: np.ndarray | None, max_disp: int, cfg: Config) -> np.ndarray:
    """Disparity at this level (float32), searched in the bands (:func:`search_bands`)
    around ``coarse``, the disparity one level down, with its left-right labels.

    Noise is estimated and adapted to at this level, as at the coarse one. The work runs
    in blocks of :data:`REFINE_ROWS` rows with a margin that holds every cross and census
    window of the block, so the result is the same as in one piece. With
    ``pyramid.scanline`` (and the scanline stage on), the blocks keep every band's
    aggregated costs and the scanline optimisation runs over them before the winners are
    taken (``optimization.band_scanline``), in stripes within ``memory.max_mb``
    (:func:`band_stripe_rows`).
    """
    if cfg.noise.adapt:
        cfg, _ = noise.adapt_to_pair(cfg, left, right)
    if cfg.cost.presmooth_sigma > 0:
        left = sensitivity.presmooth(left, cfg.cost.presmooth_sigma)
        right = sensitivity.presmooth(right, cfg.cost.presmooth_sigma)
    support = cfg.pyramid.support
    arms_cfg = dataclasses.replace(cfg.arms, l2=min(cfg.arms.l2, support),
                                   l1=min(cfg.arms.l1, support))
    # + 1: the Sobel row; the colour term's mean box reaches half its width further.
    margin = support + max(cfg.cost.census_height // 2 + 1, cfg.cost.ad_mean_box // 2)
    height, width = left.shape[:2]
    low, high = (upsample_nearest(v, (height, width))
                 for v in coarse_extremes(coarse, coarse_labels))
    arms_all = aggregation.arms_from_below(left, arms_cfg)
    n_disp = int(max_disp) + 1
    out = np.empty((height, width), dtype=np.float32)
    lo_all, hi_all = search_bands(low, high, max_disp, cfg.pyramid.band)
    del low, high
    blocks = _BandBlocks(left, right, arms_all, lo_all, hi_all, n_disp, cfg, margin)
    if cfg.pyramid.scanline and cfg.scanline.enabled:
        _refine_with_scanline(blocks, left, right, cfg, out)
        return out
    for top, bottom, y0, y1 in row_blocks(height, REFINE_ROWS, margin):
        terms, arms, lo_block, hi_block = blocks.block(top, bottom, y0, y1)
        block = search_in_bands(terms, arms, lo_block, hi_block, n_disp, support,
                                subpixel_fit(cfg))
        out[top:bottom] = block[top - y0:bottom - y0]
    return out


class _BandBlocks:
    """What the band search of rows ``top .. bottom`` needs: the cost terms and arms of
    rows ``y0 .. y1`` (:func:`vsmatch.tiles.row_blocks` with a margin that holds every
    cross and census window), and the bands, empty on the margin rows (they are searched
    with their own block)."""

    def __init__(self, left, right, arms_all, lo_all, hi_all, n_disp, cfg, margin):
        self.left, self.right, self.arms_all = left, right, arms_all
        self.lo_all, self.hi_all, self.n_disp = lo_all, hi_all, n_disp
        self.cfg, self.margin = cfg, margin

    def block(self, top: int, bottom: int, y0: int, y1: int):
        views = self.left[y0:y1], self.right[y0:y1]
        grey = [to_grey(v) for v in views]
        # The magnitude for the cost; the arms come from below (arms_from_below).
        grads = [sensitivity.visual_sensitivity(g, direction=False)[0] for g in grey]
        census = [cost.census_for(g, self.cfg.cost) for g in grey]
        # The margin keeps the core rows' arms inside the block.
        arms = np.ascontiguousarray(self.arms_all[:, y0:y1])
        terms = cost.cost_terms(views[0], views[1], census[0], census[1], grads[0], grads[1],
                                self.cfg.cost)
        # Only the core rows are searched: margin rows get an empty band.
        lo_block, hi_block = self.lo_all[y0:y1].copy(), self.hi_all[y0:y1].copy()
        for rows in (slice(0, top - y0), slice(bottom - y0, None)):
            lo_block[rows], hi_block[rows] = 1, 0
        return terms, arms, lo_block, hi_block


#: Bytes a row of a band-scanline stripe takes per pixel besides its candidates' 8 (the
#: aggregated cost and the path sum, float32): the candidate range, sizes and offsets
#: (int64).
BAND_PIXEL_BYTES = 32


def band_stripe_rows(lo: np.ndarray, hi: np.ndarray, n_disp: int, cfg: Config) -> int:
    """The most rows a stripe of the band scanline may take within ``memory.max_mb``
    (its fullest rows' candidates counted); at least enough for two overlaps and 16 rows."""
    first, last = candidate_range(lo, hi, n_disp)
    cells = np.maximum(last - first + 1, 0).sum(axis=1).max()
    row_bytes = 8 * int(cells) + BAND_PIXEL_BYTES * lo.shape[1]
    return max(cfg.memory.max_mb * 2**20 // row_bytes, 2 * cfg.memory.overlap + 16)


def _refine_with_scanline(blocks: _BandBlocks, left: np.ndarray, right: np.ndarray,
                          cfg: Config, out: np.ndarray) -> None:
    """The band search with the scanline optimisation over the bands, in horizontal
    stripes that fit ``memory.max_mb`` (``tiles.stripe_layout``: each stripe's core
    kept, ``memory.overlap`` rows on either side dropped): a stripe's bands aggregated
    block by block, the scanline over the whole stripe, then the winners. One stripe when
    the level fits, the same as the whole level in one piece."""
    height, width = left.shape[:2]
    lo_all, hi_all, n_disp = blocks.lo_all, blocks.hi_all, blocks.n_disp
    rows = band_stripe_rows(lo_all, hi_all, n_disp, cfg)
    for first_row, stop, core_first, core_stop in stripe_layout(height, rows,
                                                                cfg.memory.overlap):
        lo, hi = lo_all[first_row:stop], hi_all[first_row:stop]
        first, last = candidate_range(lo, hi, n_disp)
        sizes = np.maximum(last - first + 1, 0)
        agg_at = (np.cumsum(sizes) - sizes.ravel()).reshape(sizes.shape)
        agg = np.empty(int(sizes.sum()), dtype=np.float32)
        for top, bottom, y0, y1 in row_blocks(height, REFINE_ROWS, blocks.margin,
                                              first_row, stop):
            terms, arms, lo_block, hi_block = blocks.block(top, bottom, y0, y1)
            store, starts = band_store(terms, lo_block, hi_block, n_disp, cfg.pyramid.support)
            first_block, last_block = candidate_range(lo_block, hi_block, n_disp)
            # Offsets of the core rows in this stripe's store; the margin rows have none.
            at_block = np.zeros(lo_block.shape, dtype=np.int64)
            at_block[top - y0:bottom - y0] = agg_at[top - first_row:bottom - first_row]
            band_aggregate(store, starts, arms, first_block, last_block, at_block, agg)
            del store, starts
        sums = optimization.band_scanline(agg, agg_at, first, lo, hi, n_disp,
                                          left[first_row:stop], right[first_row:stop],
                                          cfg.scanline)
        part = np.empty(lo.shape, dtype=np.float32)
        band_winners(agg, sums, agg_at, first, last, lo, hi, subpixel_fit(cfg),
                     part)
        out[core_first:core_stop] = part[core_first - first_row:core_stop - first_row]
        del agg, sums


def subpixel_fit(cfg: Config) -> int:
    """The band kernels' sub-pixel fit: 0 (none) or the config's (``refinement``'s code)."""
    return refinement.fit_code(cfg.subpixel.fit) if cfg.subpixel.enabled else 0


def search_in_bands(terms: tuple, arms: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                    n_disp: int, support: int, subpixel: int) -> np.ndarray:
    """Each pixel's best disparity in ``lo .. hi`` (float32, inf where ``lo > hi``), its
    candidates' costs summed over its cross (arms of at most ``support`` pixels);
    ``subpixel``: the fit's code (:func:`subpixel_fit`), 0 for whole disparities.

    ``terms`` are :func:`vsmatch.cost.cost_terms`' for the views.
    """
    store, starts = band_store(terms, lo, hi, n_disp, support)
    out = np.empty(lo.shape, dtype=np.float32)
    search_band(store, starts, arms, lo, hi, n_disp, int(subpixel), out)
    return out


def candidate_range(lo: np.ndarray, hi: np.ndarray, n_disp: int
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The candidates whose costs a pixel's band needs: ``lo - 1 .. hi + 1`` within the
    range (the neighbours for the parabola), int64; ``first > last`` where there is no
    band."""
    has_band = lo <= hi
    first = np.where(has_band, np.maximum(lo - 1, 0), n_disp).astype(np.int64)
    last = np.where(has_band, np.minimum(hi + 1, n_disp - 1), -1).astype(np.int64)
    return first, last


def band_store(terms: tuple, lo: np.ndarray, hi: np.ndarray, n_disp: int, support: int
               ) -> tuple[np.ndarray, np.ndarray]:
    """Every matching cost the crosses (arms of at most ``support`` pixels) of the pixels
    with bands ``lo .. hi`` (widened by one, for the parabola) will ask for, each computed
    once: C(q, d) at ``store[starts[q] + d]``. A pixel's costs are needed for the bands
    within ``support`` pixels along its row and its column."""
    first, last = (v.astype(np.float32) for v in candidate_range(lo, hi, n_disp))
    across = np.ones((1, 2 * support + 1), np.uint8)
    along = np.ones((2 * support + 1, 1), np.uint8)
    # Outside the image erode sees +inf and dilate -inf (OpenCV's morphology borders).
    need_lo = np.minimum(cv2.erode(first, across), cv2.erode(first, along)).astype(np.int32)
    need_hi = np.maximum(cv2.dilate(last, across), cv2.dilate(last, along)).astype(np.int32)
    sizes = np.maximum(need_hi - need_lo + 1, 0).astype(np.int64)
    offsets = (np.cumsum(sizes) - sizes.ravel()).reshape(sizes.shape)
    store = np.empty(int(sizes.sum()) + RUN, dtype=np.float32)
    store[-RUN:] = 0.0  # read, never used, by the last pixel's short runs
    band_costs(*terms, need_lo, need_hi, offsets, store)
    return store, offsets - need_lo
