"""Scanline optimisation between aggregation and winner-takes-all (ALGORITHM.md §5.1)."""

from __future__ import annotations

import numpy as np

from ._kernels.scanline import scanline_diagonal_pass, scanline_pass
from .config import ScanlineConfig
from .images import as_channels, colour_change, mirrored

#: Columns walked side by side in the column passes. One: each walk goes down the image
#: and back up, and one column's strip of costs and sums is still in cache for the way
#: back; eight columns' strips are not. ``python scripts/column_blocks.py``: one column
#: 0.34 s, two 0.74, four 0.68, eight 0.67 over the twelve standard pairs (this machine,
#: 1 MB of L2 per core). The result does not depend on it.
COLUMN_BLOCK = 1


def scanline_optimise(volume: np.ndarray, left: np.ndarray, right: np.ndarray,
                      cfg: ScanlineConfig, out: np.ndarray | None = None) -> np.ndarray:
    """The mean of the directional path costs, (H, W, D): left, right, up, down, and with
    ``directions: 8`` the four diagonals.

    P1 and P2 are divided by ``reduce_one`` where the colour changes by ``tau`` or more
    between a pixel and the previous one on the path in one image (left pixel, or its
    match at d in the right image), by ``reduce_both`` where it does in both.
    ``out``, if given, is a work volume of the same shape to write the result into.
    """
    if out is None:
        out = np.empty_like(volume)  # the first pass writes every cell
    n_disp = volume.shape[2]
    divisors = np.array([1.0, cfg.reduce_one, cfg.reduce_both])
    p1s = (cfg.p1 / divisors).astype(np.float32)
    p2s = (cfg.p2 / divisors).astype(np.float32)
    weight = np.float32(1.0 / cfg.directions)
    for along_rows in (1, 0):
        change_l = colour_change(left, cfg.tau, along_rows=bool(along_rows))
        change_r = colour_change(right, cfg.tau, along_rows=bool(along_rows))
        change_r_rev = mirrored(change_r, pad=n_disp, fill=1)  # no right pixel: a change
        scanline_pass(volume, change_l, change_r_rev, p1s, p2s, along_rows, weight,
                      1 if along_rows else COLUMN_BLOCK, bool(along_rows), out)
    if cfg.directions == 8:
        for step_x in (1, -1):
            change_l = diagonal_colour_change(left, cfg.tau, step_x)
            change_r_rev = mirrored(diagonal_colour_change(right, cfg.tau, step_x),
                                    pad=n_disp, fill=1)
            scanline_diagonal_pass(volume, change_l, change_r_rev, p1s, p2s, step_x, weight,
                                   out)
    return out


def diagonal_colour_change(image: np.ndarray, threshold: float, step_x: int) -> np.ndarray:
    """uint8 (H, W): 1 where the largest channel difference between (y, x) and
    (y - 1, x - step_x) is ``threshold`` or more, and where there is no such pixel."""
    image = as_channels(image).astype(np.int16)
    out = np.ones(image.shape[:2], dtype=np.uint8)
    if step_x == 1:
        diff = np.abs(image[1:, 1:] - image[:-1, :-1]).max(axis=2)
        out[1:, 1:] = diff >= threshold
    else:
        diff = np.abs(image[1:, :-1] - image[:-1, 1:]).max(axis=2)
        out[1:, :-1] = diff >= threshold
    return out
