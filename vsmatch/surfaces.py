"""Planes carried across wide regions, for the pixels the match is unsure of.

The slanted planes (``vsmatch.planes``) are fitted within crosses of at most ``planes.l2``
pixels; a blank wall or panel is wider, its crosses reach texture only at its edges, and
its pixels take a wrong, flat disparity that the left-right check passes (the confidence
marks them low). Here the crosses are grown on the left view reduced ``levels`` times, with
a wider colour threshold, so that one region spans the wall; each region fits the
least-squares plane through its confident, left-right consistent pixels (refitted on the
inliers, as the planes stage does), and a pixel whose confidence is below ``take`` takes its
region's plane, where the region's disparities lie close about the plane and where the
plane explains the views as well as the match did: the matching cost of the plane's
disparities, averaged over a window around the pixel, is at most ``tolerance`` above that
of the disparities found.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from .aggregation import arms_grown_below
from .bands import Bands
from .config import ArmsConfig, Config, SurfacesConfig
from .disparity import VALID
from .level import matching_costs
from .planes import region_planes


def spread_planes(disp: np.ndarray, confidence: np.ndarray, labels: np.ndarray,
                  left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config,
                  colour_weight: float = 1.0) -> np.ndarray:
    """``disp`` with the unsure pixels' values replaced by their wide region's plane where
    it holds (float32, a new array). ``right``: the view as matched (after any exposure
    correction), ``colour_weight`` the colour term's weight it was matched with."""
    s = cfg.surfaces
    arms = arms_grown_below(left, _wide_arms(cfg.arms, s), s.levels)
    disp = np.ascontiguousarray(disp, dtype=np.float32)
    sure = (labels == VALID) & np.isfinite(disp) & (confidence >= s.fit)
    plane, spread = region_planes(disp, sure, arms, s.iterations, s.min_share, s.inlier)
    with np.errstate(invalid="ignore"):
        take = np.isfinite(plane) & (spread <= s.max_spread) & (confidence < s.take)
    if not take.any():
        return disp.copy()
    proposed = np.where(take, plane, disp)
    found_cost = _window_cost(left, right, disp, max_disp, cfg, colour_weight)
    plane_cost = _window_cost(left, right, proposed, max_disp, cfg, colour_weight)
    with np.errstate(invalid="ignore"):
        take &= plane_cost <= found_cost + s.tolerance
    out = disp.copy()
    out[take] = plane[take]
    return np.clip(out, 0, max_disp, out=out)


def _wide_arms(arms: ArmsConfig, s: SurfacesConfig) -> ArmsConfig:
    """The arms config of the wide regions, its lengths in pixels of the reduced view."""
    l2 = max(2, s.l2 >> s.levels)
    return dataclasses.replace(arms, tau1=s.tau, tau2=s.tau, l2=l2, l1=min(arms.l1, l2 - 1),
                               kappa=0.0, shrink=False)


def _window_cost(left: np.ndarray, right: np.ndarray, disp: np.ndarray, max_disp: int,
                 cfg: Config, colour_weight: float) -> np.ndarray:
    """The matching cost (census, gradient, colour) of each pixel at its rounded disparity
    in ``disp``, averaged over the ``surfaces.window`` square around it (over the pixels
    with a disparity)."""
    n_disp = max_disp + 1
    known = np.isfinite(disp)
    lo = np.clip(np.rint(np.where(known, disp, 0)), 0, max_disp).astype(np.int32)
    bands = Bands(lo, known.astype(np.int32), 1, n_disp)
    volume, _, _ = matching_costs(left, right, n_disp, cfg.cost, direction=False, bands=bands,
                                  colour_weight=colour_weight)
    cost = np.where(known, volume[:, :, 0], 0).astype(np.float32)
    box = (cfg.surfaces.window, cfg.surfaces.window)
    total = cv2.blur(cost, box)
    count = cv2.blur(known.astype(np.float32), box)
    with np.errstate(invalid="ignore", divide="ignore"):
        return total / count
