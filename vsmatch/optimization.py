"""Scanline optimisation between aggregation and winner-takes-all (ALGORITHM.md §5.1)."""

from __future__ import annotations

import numpy as np

from ._kernels.scanline import scanline_pass
from .config import ScanlineConfig
from .images import as_channels


def scanline_optimise(volume: np.ndarray, left: np.ndarray, right: np.ndarray,
                      cfg: ScanlineConfig) -> np.ndarray:
    """The mean of the four directional path costs (left, right, up, down), (H, W, D)."""
    out = np.zeros_like(volume)
    image_l, image_r = as_channels(left), as_channels(right)
    args = (np.float32(cfg.p1), np.float32(cfg.p2), float(cfg.tau),
            np.float32(cfg.reduce_one), np.float32(cfg.reduce_both))
    for along_rows in (1, 0):
        scanline_pass(volume, image_l, image_r, *args, along_rows, np.float32(0.25), out)
    return out
