"""Refinement of the disparity map (ALGORITHM.md §5.2, 5.4, 5.5)."""

from __future__ import annotations

import cv2
import numpy as np

from ._kernels import refine as _k
from ._kernels.rows import thread_classes
from .bands import Bands, of
from .config import DiscontinuityConfig, VotingConfig


def region_vote(disp: np.ndarray, labels: np.ndarray, arms: np.ndarray, *, n_disp: int,
                cfg: VotingConfig) -> tuple[np.ndarray, np.ndarray]:
    """Iterative region voting: rejected pixels take their support region's consensus.

    Returns the new integer disparity and labels; pixels still rejected keep their label.
    """
    disp = np.ascontiguousarray(disp, dtype=np.int32)
    labels = labels.copy()
    next_disp, next_labels = np.empty_like(disp), np.empty_like(labels)
    votes, run_end = np.empty_like(disp), np.empty(disp.shape, dtype=np.int32)
    for _ in range(cfg.iterations):
        _k.vote_runs(disp, labels, votes, run_end)
        _k.region_vote(disp, labels, votes, run_end, arms, int(n_disp), int(cfg.min_votes),
                       float(cfg.min_share), thread_classes(), next_disp, next_labels)
        disp, next_disp = next_disp, disp
        labels, next_labels = next_labels, labels
    return disp, labels


def discontinuity_adjust(disp: np.ndarray, volume: np.ndarray,
                         cfg: DiscontinuityConfig, bands: Bands | None = None) -> np.ndarray:
    """Move disparity edges to where the matching cost puts them (float32); ``volume``
    holds the candidates of ``bands`` (default: the whole range)."""
    bands = of(volume, bands)
    out = np.empty(disp.shape, dtype=np.float32)
    _k.discontinuity_adjust(np.ascontiguousarray(disp, dtype=np.float32), volume, bands.lo,
                            bands.count, float(cfg.jump), out)
    return out


def subpixel(disp: np.ndarray, volume: np.ndarray, fit: str = "parabola",
             bands: Bands | None = None) -> np.ndarray:
    """Sub-pixel disparity by a fit through the costs around each integer disparity:
    ``parabola`` or ``equiangular`` (:data:`SUBPIXEL_FITS`); ``volume`` holds the
    candidates of ``bands`` (default: the whole range)."""
    bands = of(volume, bands)
    out = np.empty(disp.shape, dtype=np.float32)
    _k.subpixel_fit(np.ascontiguousarray(disp, dtype=np.float32), volume, bands.lo,
                    bands.count, fit_code(fit), out)
    return out


#: The sub-pixel fits by name, as the kernels know them.
SUBPIXEL_FITS = {"parabola": _k.FIT_PARABOLA, "equiangular": _k.FIT_EQUIANGULAR,
                 "blend": _k.FIT_BLEND}


def fit_code(fit: str) -> int:
    return SUBPIXEL_FITS[fit]


def median3(disp: np.ndarray) -> np.ndarray:
    """3x3 median; invalid (non-finite) pixels stay invalid and do not spread."""
    valid = np.isfinite(disp)
    if valid.all():
        return cv2.medianBlur(disp.astype(np.float32), 3)
    filled = np.where(valid, disp, 0).astype(np.float32)
    out = cv2.medianBlur(filled, 3)
    out[~valid] = disp[~valid]
    return out
