"""One pyramid level's solver: the method's stages in order over each pixel's band.

The full search is the band ``0 .. max_disp`` at every pixel; coarse-to-fine and video
give narrower bands (``vsmatch.bands``). Everything around a level (offsets, levels,
stripes) is ``vsmatch.scale``'s.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from . import (aggregation, confidence, cost, disparity, noise, optimization, refinement,
               sensitivity, volumes)
from .bands import Bands
from .config import Config, CostConfig
from .disparity import INVALID_DISPARITY
from .images import channel_planes, grey_levels, to_grey
from .result import Learnt, MatchResult, learn, timed


def matching_costs(left: np.ndarray, right: np.ndarray, n_disp: int, cost_cfg: CostConfig,
                    direction: bool = True, bands: Bands | None = None,
                    colour_weight: float = 1.0) -> tuple[np.ndarray, tuple, tuple]:
    """The cost volume (ALGORITHM.md §1-2) and each view's gradient magnitude and
    direction (None unless ``direction``), which the arms need too."""
    (census_l, census_r), sens_l, sens_r = _views_measured(left, right, cost_cfg, direction)
    volume = cost.cost_volume(left, right, census_l, census_r, sens_l[0], sens_r[0],
                              n_disp=n_disp, cfg=cost_cfg, bands=bands,
                              colour_weight=colour_weight)
    return volume, sens_l, sens_r


def pair_cost_terms(left: np.ndarray, right: np.ndarray, cost_cfg: CostConfig,
                    colour_weight: float = 1.0) -> tuple:
    """What :func:`matching_costs` prepares of the views (``cost.cost_terms``), for
    costing several sets of bands on one pair (``cost.banded_volume``)."""
    (census_l, census_r), (grad_l, _), (grad_r, _) = _views_measured(left, right, cost_cfg,
                                                                     False)
    return cost.cost_terms(left, right, census_l, census_r, grad_l, grad_r, cost_cfg,
                           colour_weight=colour_weight)


def _views_measured(left: np.ndarray, right: np.ndarray, cost_cfg: CostConfig,
                    direction: bool) -> tuple[tuple, tuple, tuple]:
    """Each view's census, and its gradient magnitude and direction (None unless
    ``direction``)."""
    grey_l, grey_r = to_grey(left), to_grey(right)
    return ((cost.census_for(grey_l, cost_cfg), cost.census_for(grey_r, cost_cfg)),
            sensitivity.visual_sensitivity(grey_l, direction),
            sensitivity.visual_sensitivity(grey_r, direction))


def solve(left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config,
          bands: Bands | None = None, learnt: Learnt | None = None) -> MatchResult:
    """One level's solver: the stages in order (ALGORITHM.md §1-5), every pixel searching
    its band of ``0 .. max_disp`` (default: the whole range, the full search). ``learnt``:
    what the pipeline learnt of the pair (its noise, the colour weight); default: the
    noise of these views."""
    n_disp = int(max_disp) + 1
    seconds: dict[str, float] = {}
    stage = functools.partial(timed, seconds)

    if learnt is None:
        with stage("noise"):
            learnt = learn(left, right, cfg)
    noise_sigma = learnt.noise_at(left.shape[1])
    if noise_sigma is not None:
        cfg = noise.adapt_to_noise(cfg, noise_sigma)
    if cfg.cost.presmooth_sigma > 0:
        with stage("presmooth"):
            left = sensitivity.presmooth(left, cfg.cost.presmooth_sigma)
            right = sensitivity.presmooth(right, cfg.cost.presmooth_sigma)

    finer = bands is not None and not bands.is_full  # a finer level: the bands' options
    cost_cfg = cfg.bands.cost_at_bands(cfg.cost) if finer else cfg.cost
    with stage("cost"):
        volume, (grad_l, theta_l), (grad_r, theta_r) = matching_costs(
            left, right, n_disp, cost_cfg, direction=cfg.arms.kappa != 0, bands=bands,
            colour_weight=learnt.colour_weight)

    arms_cfg = cfg.arms
    scanline = cfg.scanline.enabled
    aggregate = cfg.aggregation.iterations > 0
    if finer:
        scanline = scanline and cfg.bands.scanline
        aggregate = aggregate and cfg.bands.aggregation
        support = cfg.bands.support
        arms_cfg = dataclasses.replace(arms_cfg, l1=min(arms_cfg.l1, support),
                                       l2=min(arms_cfg.l2, support))
    arms_l = arms_r = None
    planes = None  # the views' int16 planes: the arms make them, the scanline reads them too
    if aggregate or cfg.voting.enabled:
        with stage("arms"):
            planes = channel_planes(left), channel_planes(right)
            arms_l = aggregation.cross_arms(left, theta_l, grad_l, arms_cfg, planes[0])
            if aggregate:
                arms_r = aggregation.cross_arms(right, theta_r, grad_r, arms_cfg, planes[1])
    # One work volume serves aggregation, then holds the scanline costs: the cost volume
    # is allocated twice, not three times (allocation is a measurable share of the time).
    work = volumes.volume("work", volume.shape)
    if aggregate:
        with stage("aggregation"):
            volume = aggregation.aggregate_cross(volume, arms_l, arms_r, scratch=work,
                                                 iterations=cfg.aggregation.iterations,
                                                 bands=bands)

    aggregated = volume
    if scanline:
        with stage("scanline"):
            volume = optimization.scanline_optimise(volume, left, right, cfg.scanline,
                                                    out=work, bands=bands, planes=planes)

    # The winners' cost curves feed the confidence; a band's curve is short, so the caller
    # brings whole-range ones (the coarse level's, the last full search's).
    whole_range = bands is None or bands.is_full
    curve = None
    with stage("wta"):
        if cfg.consistency.enabled and whole_range:
            disp_l, disp_r, curves = disparity.winner_takes_all_with_curve(volume)
        elif cfg.consistency.enabled:
            disp_l, disp_r = disparity.winner_takes_all_both(volume, bands)
        else:
            disp_l = disparity.winner_takes_all(volume, bands)
            curves = confidence.cost_curves(volume, disp_l) if whole_range else None
    if whole_range:
        with stage("confidence"):
            curve = confidence.curve_features(curves, arms_l)
            # The same margin before the scanline optimisation, and repeated texture there.
            if aggregated is not volume:
                raw, offsets = confidence.curves_and_rivals(aggregated, disp_l)
                curve["raw_margin"] = confidence.curve_features(raw, None)["margin"]
            else:
                curve["raw_margin"] = curve["margin"]
                offsets = confidence.rivals(aggregated, disp_l, curves)
            curve["repeated"], curve[confidence.RIVAL] = confidence.repeats_and_rivals(
                grey_levels(left), offsets)

    # Pixels searched no more keep the disparity they hold, and count as consistent.
    held = None if bands is None or bands.held is None else np.isfinite(bands.held)
    if held is not None:
        disp_l[held] = np.rint(bands.held[held])
    labels = None
    if cfg.consistency.enabled:
        with stage("consistency"):
            # A held pixel is not checked (it is VALID below): its right partner was not
            # searched, and the scan for any passing disparity would find none, slowly.
            checked = disp_l if held is None else np.where(held, -1, disp_l)
            labels = disparity.left_right_check(checked, disp_r, n_disp=n_disp,
                                                tolerance=cfg.consistency.tolerance)
        if held is not None:
            labels[held] = disparity.VALID
        if cfg.voting.enabled:
            with stage("voting"):
                disp_l, labels = refinement.region_vote(disp_l, labels, arms_l,
                                                        n_disp=n_disp, cfg=cfg.voting)
        with stage("fill"):
            if cfg.fill.enabled:
                result = disparity.fill_rejected(disp_l, labels, left, cfg.fill)
            else:
                result = disparity.mark_rejected(disp_l, labels)
    else:
        result = disp_l.astype(np.float32)
        result[disp_l < 0] = INVALID_DISPARITY  # no candidate in the pixel's band

    if cfg.discontinuity.enabled:
        with stage("discontinuity"):
            result = refinement.discontinuity_adjust(result, volume, cfg.discontinuity, bands)
    if cfg.subpixel.enabled:
        with stage("subpixel"):
            # The aggregated costs, not the scanline ones: the penalties flatten the cost
            # curve around the minimum (measured: fewer bad pixels at 0.5 and 1.0).
            result = refinement.subpixel(result, aggregated, cfg.subpixel.fit, bands)
    if cfg.subpixel.median:
        with stage("median"):
            result = refinement.median3(result)
    if held is not None:  # to the last bit: a whole-pixel copy would turn a floor to stairs
        result[held] = bands.held[held]

    return MatchResult(disparity=result, labels=labels, seconds=seconds, config=cfg,
                       noise_sigma=noise_sigma, colour_weight=learnt.colour_weight, curve=curve)
