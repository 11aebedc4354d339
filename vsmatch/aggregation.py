"""Cost aggregation on cross-shaped support regions with direction-guided arms (§3)."""

from __future__ import annotations

import numpy as np

from ._kernels.aggregate import sum_along_arms
from ._kernels.arms import cross_arms as _cross_arms_kernel
from .config import ArmsConfig
from .images import as_channels, colour_change


def cross_arms(image: np.ndarray, theta: np.ndarray, sensitivity: np.ndarray,
               cfg: ArmsConfig) -> np.ndarray:
    """Arm lengths ``(4, H, W)`` uint8 in the order left, right, up, down.

    ``image`` is the colour (or grey) image the colour distances are measured on;
    ``theta`` and ``sensitivity`` are the direction and magnitude of its gradient.
    """
    image = as_channels(image)
    strength = np.minimum(1.0, sensitivity / cfg.g_sat).astype(np.float32)
    out = np.empty((4,) + theta.shape, dtype=np.uint8)  # l2 <= 255 (config range)
    _cross_arms_kernel(image, np.ascontiguousarray(theta, dtype=np.float32), strength,
                       colour_change(image, cfg.tau2, along_rows=True),
                       colour_change(image, cfg.tau2, along_rows=False),
                       float(cfg.tau1), float(cfg.tau3), int(cfg.l1), int(cfg.l2),
                       float(cfg.kappa), out)
    return out


def aggregate_cross(volume: np.ndarray, arms_l: np.ndarray, arms_r: np.ndarray,
                    *, iterations: int, scratch: np.ndarray | None = None) -> np.ndarray:
    """Average the cost over each pixel's cross support region, ``iterations`` times.

    The first iteration sums rows then columns, the next columns then rows, and so on.
    At disparity d each arm is the shorter of the left pixel's and the right pixel
    (x - d)'s. ``volume`` is used as a work buffer and overwritten, as is ``scratch``, a
    float32 volume of the same shape, if given.
    """
    current = np.ascontiguousarray(volume, dtype=np.float32)
    # One scratch volume: the first pass of each iteration writes it, the second writes
    # the result back over ``current``, so aggregation holds two volumes at most.
    if scratch is None:
        scratch = np.empty_like(current)
    for it in range(iterations):
        rows_first = it % 2 == 0
        sum_along_arms(current, arms_l, arms_r, rows_first, False, scratch)
        sum_along_arms(scratch, arms_l, arms_r, not rows_first, True, current)
    return current
