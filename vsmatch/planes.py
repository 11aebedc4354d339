"""Slanted planes: each pixel's support region fits a plane to its consistent disparities.

Cross-based aggregation assumes the surface inside each cross is fronto-parallel, so a road
or a desk seen at a grazing angle comes out in steps, and pixels the left-right check
rejected are filled along their row with a constant. Here each pixel's cross region (arms
grown on the left view halved, as the band search's, longer than the aggregation's) gets the
least-squares plane
``d = a x + b y + c`` through the pixels the check kept: the moments of those pixels are
summed over the region by running sums along the rows, then down the columns, where the
plane is solved per pixel. Outliers leave the fit over a second pass. A rejected pixel takes
its plane's value; a kept one takes it when within ``snap`` pixels (sub-pixel values from
the plane rather than from a parabola through integer costs).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ._kernels.planes import (COLUMN_BLOCK, N_MOMENTS, cut_arms_at_jumps, fit_region_planes,
                              take_planes)
from .aggregation import keep_arms_inside
from .config import ArmsConfig, PlanesConfig
from .disparity import VALID
from .aggregation import arms_from_below
from .tiles import row_blocks

#: Least variance of a region's pixel coordinates along an axis for a slope along it
#: (a region one or two pixels wide fits a constant along that axis).
MIN_SPREAD = 1.0


#: Rows fitted at a time (with a margin of ``planes.l2`` rows on either side, which holds
#: every region of the block's rows): it bounds the row sums' memory (44 bytes a pixel).
#: A constant, so the result depends on the image and the config only.
PLANE_ROWS = 512


def fit_planes(disp: np.ndarray, labels: np.ndarray, left: np.ndarray,
               arms_cfg: ArmsConfig, cfg: PlanesConfig) -> np.ndarray:
    """``disp`` with each rejected pixel (``labels`` not VALID) set to its region's plane,
    and each kept one within ``cfg.snap`` of it too (float32; where no plane fits, or the
    region's disparities spread more than ``cfg.max_spread`` about it, nothing changes)."""
    # Grown on the views halved (a quarter of the work; as accurate here, measured).
    arms = arms_from_below(left, dataclasses.replace(arms_cfg, l2=cfg.l2, kappa=0.0))
    disp = np.ascontiguousarray(disp, dtype=np.float32)
    kept = (labels == VALID) & np.isfinite(disp)
    if cfg.jump > 0:
        cut_arms_at_jumps(arms, np.where(kept, disp, np.float32(np.nan)),
                          np.float32(cfg.jump))
    out = np.empty_like(disp)
    blocks = list(row_blocks(disp.shape[0], PLANE_ROWS, cfg.l2))
    # One room for every block's row sums: a camera-size view's block takes about 40 MB,
    # which the system would map and zero afresh for each block.
    room = moment_room((max(y1 - y0 for _, _, y0, y1 in blocks), disp.shape[1]))
    for top, bottom, y0, y1 in blocks:
        plane, spread = _block_planes(disp[y0:y1], kept[y0:y1],
                                      np.ascontiguousarray(arms[:, y0:y1]), cfg, room)
        core = slice(top - y0, bottom - y0)
        take_planes(disp[top:bottom], kept[top:bottom], plane[core], spread[core],
                    np.float32(cfg.max_spread), np.float32(cfg.snap), bool(cfg.fill),
                    out[top:bottom])
    return out


def _block_planes(disp: np.ndarray, kept: np.ndarray, arms: np.ndarray,
                  cfg: PlanesConfig, room: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's plane value and the spread of its region about it (NaN where none
    fits), ``cfg.iterations`` fits, each with the kept pixels near the last plane; the row
    sums in ``room`` (:func:`moment_room`)."""
    # The margin rows' own vertical arms may reach past the block: cut there (the core
    # rows' regions lie inside the margin, so theirs are whole).
    keep_arms_inside(arms)
    return region_planes(disp, kept, arms, cfg.iterations, cfg.min_share, cfg.inlier,
                         room=room)


def _moment_shape(shape: tuple[int, int]) -> tuple[int, int, int, int]:
    """The shape of :func:`moment_blocks` for an image of ``shape`` (H, W)."""
    height, width = shape
    return ((width + COLUMN_BLOCK - 1) // COLUMN_BLOCK, height, COLUMN_BLOCK, N_MOMENTS)


def moment_room(shape: tuple[int, int]) -> np.ndarray:
    """Flat float32 room for :func:`moment_blocks` of any image at most ``shape``."""
    return np.empty(int(np.prod(_moment_shape(shape))), np.float32)


def moment_blocks(shape: tuple[int, int], room: np.ndarray | None = None) -> np.ndarray:
    """Room for ``fit_region_planes``' row sums of an image of ``shape`` (H, W): float32
    (blocks, H, :data:`COLUMN_BLOCK`, :data:`N_MOMENTS`), a block a :data:`COLUMN_BLOCK`
    columns (the last one's columns past the image unused); the start of ``room``
    (:func:`moment_room`) when given, else new."""
    blocks = _moment_shape(shape)
    if room is None:
        return np.empty(blocks, np.float32)
    return room[:int(np.prod(blocks))].reshape(blocks)


def region_planes(disp: np.ndarray, kept: np.ndarray, arms: np.ndarray, iterations: int,
                  min_share: float, inlier: float, wanted: np.ndarray | None = None,
                  room: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's cross region's least-squares plane at the pixel, through the region's
    ``kept`` pixels, and their spread about it (NaN where they are fewer than ``min_share``
    of the region); ``iterations`` fits, each on the kept pixels within ``inlier`` of the
    last plane. ``wanted``: where the caller reads the result (None: everywhere); the last
    fit is solved only near those pixels, NaN elsewhere. ``room``: for the row sums
    (:func:`moment_room`; default: new)."""
    kept = np.ascontiguousarray(kept, dtype=bool)
    wanted = (np.ones(disp.shape, bool) if wanted is None
              else np.ascontiguousarray(wanted, dtype=bool))
    scratch = moment_blocks(disp.shape, room)
    # The planes of one fit are the next one's "last": two buffers, taken in turn.
    planes = [np.empty(disp.shape, np.float32) for _ in range(2)]
    last = np.empty((0, 0), np.float32)  # the first fit: every kept pixel
    spread = np.empty(disp.shape, np.float32)
    for fit in range(iterations):
        plane = planes[fit % 2]
        # A fit before the last is read at the kept pixels only (the next fit's inliers).
        solve_at = wanted if fit == iterations - 1 else kept
        fit_region_planes(disp, kept, last, np.float32(inlier), arms, np.float32(min_share),
                          np.float32(MIN_SPREAD), solve_at, scratch, plane, spread)
        last = plane
    return last, spread
