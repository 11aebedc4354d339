"""The exposure correction of a pair (``vsmatch.photometric``): a quick first match on
small views gives the pixels the right view's colour map is learnt from, and how far the
colour term can be trusted."""

from __future__ import annotations

import dataclasses

import numpy as np

from . import disparity, photometric, pyramid
from .config import Config
from .images import box_blur, downsample
from .level import matching_costs


def correct_exposure(left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config
                      ) -> tuple[np.ndarray, photometric.Correction | None, float]:
    """The right view mapped onto the left's colours, the map, and the weight the colour
    term keeps (1: fully trusted), learnt from a first match on small views
    (``vsmatch.photometric``)."""
    small_l, small_r, small_max = left, right, max_disp
    while True:  # at least one level down: only the statistics of the matches are used
        width, small_max = pyramid.level_down(small_l.shape[1], small_max)
        if width < 2 * cfg.cost.census_width or small_max < 1 or min(
                small_l.shape[:2]) < 2 * cfg.cost.census_height:
            return right, None, 1.0
        small_l, small_r = downsample(small_l), downsample(small_r)
        if width <= cfg.photometric.max_width:
            break
    first_disp, matched = first_match(small_l, small_r, small_max, cfg)
    correction = photometric.learn(small_l, small_r, first_disp, matched,
                                   cfg.photometric.field_sigma)
    if correction is None:
        return right, None, 1.0
    weight = photometric.colour_weight(correction.excess, cfg.photometric)
    return photometric.apply(right, correction), correction, weight


def first_match(left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config
                 ) -> tuple[np.ndarray, np.ndarray]:
    """A quick match for the photometric statistics: census and gradient costs (the colour
    term is what is in doubt) averaged over ``photometric.box`` square windows, winner
    takes all in both views, the exact left-right check. Returns the left disparity and
    the pixels that pass the check."""
    volume, _, _ = matching_costs(left, right, max_disp + 1,
                                   dataclasses.replace(cfg.cost, lambda_ad=None),
                                   direction=False)
    averaged = box_blur(volume, cfg.photometric.box)
    disp_l, disp_r = disparity.winner_takes_all_both(averaged)
    labels = disparity.left_right_check(disp_l, disp_r, n_disp=max_disp + 1, tolerance=0)
    return disp_l, labels == disparity.VALID
