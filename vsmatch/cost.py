"""Matching cost: census Hamming distance, sensitivity difference, optional colour AD.

The cost volume has one layout everywhere in vsmatch: ``(H, W, D)`` float32, C-contiguous,
so the costs of one pixel over all disparities are adjacent in memory.
"""

from __future__ import annotations

import cv2
import numpy as np

from ._kernels.census import census_transform as _census_kernel, like_neighbours
from ._kernels.cost import matching_cost_volume, view_terms
from . import volumes
from .bands import Bands
from .config import CostConfig
from .images import as_channels, channel_planes


def census_transform(grey: np.ndarray, *, width: int = 9, height: int = 7,
                     band: float = 0.0) -> np.ndarray:
    """Census bit strings (uint64, (H, W)) over a ``width`` x ``height`` window.

    Bit order: window neighbours row by row, centre skipped, the first one in the highest
    used bit; a bit is set when the neighbour is darker than the centre by more than
    ``band`` grey levels (a dead band keeps noise from flipping bits in flat regions).
    """
    if width % 2 == 0 or height % 2 == 0 or width * height - 1 > 64:
        raise ValueError(f"census window {width}x{height} must be odd-sized with at most "
                         "64 neighbours")
    grey = np.ascontiguousarray(grey, dtype=np.float32)
    half_w, half_h = width // 2, height // 2
    padded = cv2.copyMakeBorder(grey, half_h, half_h, half_w, half_w, cv2.BORDER_REPLICATE)
    out = np.empty(grey.shape, dtype=np.uint64)
    _census_kernel(padded, half_w, half_h, np.float32(band), out)
    return out


def census_for(grey: np.ndarray, cfg: CostConfig) -> np.ndarray:
    """:func:`census_transform` with the config's window and dead band."""
    return census_transform(grey, width=cfg.census_width, height=cfg.census_height,
                            band=cfg.census_band)


def like_masks(colour: np.ndarray, cfg: CostConfig) -> np.ndarray:
    """Each pixel's census bits (uint64, (H, W), the census's order) of the neighbours whose
    every channel lies within ``cost.census_like`` grey levels of the pixel's."""
    half_w, half_h = cfg.census_width // 2, cfg.census_height // 2
    planes = channel_planes(cv2.copyMakeBorder(as_channels(colour), half_h, half_h, half_w,
                                               half_w, cv2.BORDER_REPLICATE))
    out = np.empty((planes.shape[1] - 2 * half_h, planes.shape[2] - 2 * half_w), np.uint64)
    like_neighbours(planes, half_w, half_h, np.int16(int(cfg.census_like)), out)
    return out


def like_table(cfg: CostConfig) -> np.ndarray:
    """``table[n]``: the census terms a pixel with n like neighbours looks up, in one row so
    that a cell takes one look-up: ``table[n, m]`` for m differing bits among its like
    neighbours (the term of m scaled to the whole window), ``table[n, N + 1 + h]`` for h
    differing bits in all N of the window (row 0, no like neighbour: the plain terms only)."""
    n_bits = cfg.census_width * cfg.census_height - 1
    like = np.arange(n_bits + 1, dtype=np.float64)[:, None]
    counted = np.arange(n_bits + 1, dtype=np.float64)[None, :]
    scaled = np.broadcast_to(rho(counted * n_bits / np.maximum(like, 1), cfg.lambda_census),
                             (n_bits + 1, n_bits + 1))
    plain = np.broadcast_to(rho(counted, cfg.lambda_census), (n_bits + 1, n_bits + 1))
    return np.ascontiguousarray(np.hstack([scaled, plain]), dtype=np.float32)


def rho(cost: np.ndarray | float, lam: float) -> np.ndarray | float:
    """Robust mapping into [0, 1): ``1 - exp(-cost / lam)``."""
    return 1.0 - np.exp(-np.asarray(cost, dtype=np.float64) / lam)


def max_cost(cfg: CostConfig, colour_weight: float = 1.0) -> float:
    """The cost given where the right pixel does not exist: every term at its limit 1
    (the colour term's, ``cost.ad_weight`` x ``colour_weight``)."""
    return (1.0 + (cfg.lambda_gradient is not None)
            + (cfg.lambda_ad is not None) * (cfg.ad_weight * colour_weight))


#: Gradient magnitudes are quantised to this many steps per grey level for the table
#: lookup of their cost term (an error of at most 1/8, negligible against lambda).
GRADIENT_STEPS = 4


def cost_terms(colour_l: np.ndarray, colour_r: np.ndarray,
               census_l: np.ndarray, census_r: np.ndarray,
               grad_l: np.ndarray, grad_r: np.ndarray, cfg: CostConfig,
               colour_weight: float = 1.0) -> tuple:
    """The arguments the cost kernels take after the output: each view's census, quantised
    gradient and colour planes (C, H, W) (the right view's reversed along x), the left view's
    like neighbours (:func:`like_masks`, with ``cost.census_like``), the four lookup tables
    (an empty one switches its term off) and the maximum cost.
    ``colour_weight``: what the exposure correction leaves of the colour term (times
    ``cost.ad_weight``)."""
    n_bits = cfg.census_width * cfg.census_height - 1
    census_table = rho(np.arange(n_bits + 1), cfg.lambda_census).astype(np.float32)
    colour_l, colour_r = as_channels(colour_l), as_channels(colour_r)
    height, width, channels = colour_l.shape
    planes_l = np.empty((channels, height, width), np.int16)
    planes_r_rev = np.empty_like(planes_l)
    census_r_rev = np.empty_like(census_r)
    q_l = np.empty((height, width), np.int32)
    q_r_rev = np.empty_like(q_l)
    row_max = np.zeros(height, np.int64)
    view_terms(colour_l, colour_r, census_r,
               *(np.ascontiguousarray(g, dtype=np.float32) for g in (grad_l, grad_r)),
               np.float32(GRADIENT_STEPS), planes_l, planes_r_rev, census_r_rev, q_l,
               q_r_rev, row_max)
    if cfg.lambda_gradient is None:
        grad_table = np.empty(0, np.float32)
    else:
        steps = np.arange(int(row_max.max(initial=0)) + 1) / GRADIENT_STEPS
        grad_table = rho(steps, cfg.lambda_gradient).astype(np.float32)
    ad_weight = cfg.ad_weight * colour_weight
    if cfg.lambda_ad is None or ad_weight == 0:
        ad_table = np.empty(0, np.float32)
    else:
        ad_table = (ad_weight * rho(np.arange(255 * channels + 1) / channels,
                                    cfg.lambda_ad)).astype(np.float32)
    if cfg.census_like > 0:
        like_l, like_by_count = like_masks(colour_l, cfg), like_table(cfg)
    else:
        like_l, like_by_count = np.empty((0, 0), np.uint64), np.empty((0, 0), np.float32)
    return (census_l, census_r_rev, q_l, q_r_rev, planes_l, planes_r_rev, like_l, census_table,
            like_by_count, grad_table, ad_table, np.float32(max_cost(cfg, colour_weight)))


def cost_volume(colour_l: np.ndarray, colour_r: np.ndarray,
                census_l: np.ndarray, census_r: np.ndarray,
                grad_l: np.ndarray, grad_r: np.ndarray,
                *, n_disp: int, cfg: CostConfig, bands: Bands | None = None,
                colour_weight: float = 1.0) -> np.ndarray:
    """The matching cost volume ``(H, W, B)`` float32 (ALGORITHM.md §2) of each pixel's
    candidates in ``bands`` (default: all ``n_disp`` of them, B = ``n_disp``), the colour
    term weighted by ``colour_weight`` besides ``cost.ad_weight``."""
    if bands is None:
        bands = Bands.full(census_l.shape, n_disp)
    return banded_volume(cost_terms(colour_l, colour_r, census_l, census_r, grad_l, grad_r,
                                    cfg, colour_weight=colour_weight), bands)


def banded_volume(terms: tuple, bands: Bands) -> np.ndarray:
    """The cost volume ``(H, W, B)`` of ``bands``' candidates from the views' prepared
    :func:`cost_terms` (made once where several bands are costed on one pair)."""
    out = volumes.volume("cost", bands.lo.shape + (bands.width,))
    matching_cost_volume(*terms, bands.lo, bands.count, out)
    return out
