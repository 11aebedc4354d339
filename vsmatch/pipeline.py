"""The method over a known range, step by step (ALGORITHM.md): :func:`run` reads like the
algorithm; ``vsmatch.level`` holds one level's stages, ``vsmatch.scale`` the bookkeeping
around them. ``vsmatch.match`` and ``vsmatch.run`` (``vsmatch.api``) find the range first
when none is given."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from . import (confidence, edges, exposure, photometric, planes, pyramid, scale,
               surfaces)
from . import temporal as video
from .checks import check_pair, check_views  # noqa: F401  (the inputs' checks, re-exported)
from .config import Config, load_config
from .forking import check_not_forked
from .bands import Bands
from .images import downsample, to_grey, upsample_nearest
from .level import solve
from .result import Learnt, MatchResult, learn, timed
from .temporal import Temporal
from .threads import opencv_on_this_thread


def match(left: np.ndarray, right: np.ndarray, *, max_disp: int, min_disp: int = 0,
          config: Config | str | None = None) -> np.ndarray:
    """:func:`vsmatch.match` over the range ``min_disp .. max_disp``."""
    return run(left, right, max_disp=max_disp, min_disp=min_disp, config=config).disparity


def run(left: np.ndarray, right: np.ndarray, *, max_disp: int, min_disp: int = 0,
        config: Config | str | None = None, temporal: Temporal | None = None) -> MatchResult:
    """The method over ``min_disp .. max_disp``, with per-stage timings, the left-right
    labels, the confidence and the range used (:func:`vsmatch.run` for the parameters).
    ``temporal``: the memory of a stream's earlier frames (``vsmatch.temporal``), used and
    updated; this frame then searches near the last one's disparities."""
    check_not_forked()
    cfg = load_config(config)
    check_pair(left, right, max_disp, cfg, min_disp)
    if temporal is not None:
        temporal.follow(left, right, min_disp, max_disp)
    with opencv_on_this_thread():
        return scale.with_offset(functools.partial(_run_from_zero, cfg=cfg, temporal=temporal),
                                 left, right, min_disp, max_disp)


def _run_from_zero(left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config,
                   temporal: Temporal | None = None) -> MatchResult:
    """Disparities ``0 .. max_disp``: near the last frame's when a stream's memory allows."""
    if temporal is None:
        return _search_whole_range(left, right, max_disp, cfg)
    grey, grey_right = to_grey(left), to_grey(right)
    memory, planning = temporal.memory, {}
    if memory is None:
        temporal.reason, near = temporal.first_reason(), None
    else:
        with timed(planning, "bands"):
            temporal.reason, near = video.plan(memory, grey, grey_right, max_disp,
                                               cfg.temporal)
    if near is not None:
        result = _search_near_last(left, right, max_disp, near)
        result.seconds = {**planning, **result.seconds}
        if result.confidence.mean() >= cfg.temporal.collapse * memory.full_confidence:
            temporal.memory = video.remember(result, grey, grey_right, max_disp, near)
            return result
        temporal.reason = "confidence collapsed"
    result = _search_whole_range(left, right, max_disp, cfg)
    temporal.memory = video.remember(result, grey, grey_right, max_disp, config=cfg)
    return result


def _search_whole_range(left: np.ndarray, right: np.ndarray, max_disp: int,
                        cfg: Config) -> MatchResult:
    """Disparities ``0 .. max_disp``, every one a candidate at every pixel."""
    seconds: dict[str, float] = {}
    correction, weight = None, 1.0
    # 1. The right view's colours mapped onto the left's; how far the colour term holds.
    if cfg.photometric.enabled:
        with timed(seconds, "photometric"):
            right, correction, weight = exposure.correct_exposure(left, right, max_disp, cfg)
    # 2. The views' noise, which every level's thresholds adapt to.
    learnt = _learn(left, right, cfg, weight, seconds)
    # 3. Costs, aggregation, scanline, winners, checks and refinement (vsmatch.level), on
    #    the whole range where a row fits, else a level down and in bands above it.
    levels = scale.search_levels(left.shape[1], left.shape[0], max_disp, cfg)
    result = scale.coarse_to_fine(functools.partial(solve, learnt=learnt), left, right,
                                  max_disp, cfg, levels)
    result.seconds = {**seconds, **result.seconds}
    result.photometric = correction
    _fit_planes(result, left, max_disp)
    result = _with_confidence(result, left, max_disp)
    # 6. Unsure pixels take the plane of a wide region (a blank wall) where it holds, or
    #    the line between sure pixels on either side (a shelf's board).
    if cfg.surfaces.enabled and result.labels is not None:
        with timed(result.seconds, "surfaces"):
            result.disparity, result.confidence = surfaces.spread_planes(
                result.disparity, result.confidence, result.labels, left, right, max_disp,
                result.config, result.colour_weight, result.curve["margin"])
    # 7. A pixel just before a step back may belong to the surface behind it: aggregation
    #    spills a surface's disparity a few pixels past its edge.
    if cfg.edges.enabled:
        with timed(result.seconds, "edges"):
            result.disparity, result.confidence = edges.weigh_edges(
                result.disparity, result.confidence, left, right, result.config.edges)
    return result


def _search_near_last(left: np.ndarray, right: np.ndarray, max_disp: int,
                      near: video.Plan) -> MatchResult:
    """Disparities near the last frame's (``vsmatch.temporal``), held where the image
    held still; the exposure correction and colour weight the last full search learnt."""
    memory = near.memory
    cfg = memory.config
    if not cfg.temporal.planes:
        cfg = dataclasses.replace(cfg, planes=dataclasses.replace(cfg.planes, enabled=False))
    cfg = dataclasses.replace(cfg, bands=dataclasses.replace(
        cfg.bands, scanline=cfg.bands.scanline and cfg.temporal.scanline,
        aggregation=cfg.bands.aggregation and cfg.temporal.aggregation))
    seconds: dict[str, float] = {}
    if memory.correction is not None:
        with timed(seconds, "photometric"):
            right = photometric.apply(right, memory.correction)
    # The noise the last full search measured: a stream's noise changes with its light,
    # which a jump in exposure or a refresh searches again for (2.7 ms a frame at 640x480).
    learnt = Learnt(noise_sigma=memory.noise_sigma, width=left.shape[1],
                    colour_weight=memory.colour_weight)
    coarse_curve = None  # the coarse look's cost-curve features over its rows
    if near.look is not None:
        with timed(seconds, "coarse look"):
            coarse_bands, coarse_curve = _coarse_look(left, right, max_disp, cfg, learnt,
                                                      near.look)
            near = video.looked_again(near, coarse_bands)
    result = scale.in_stripes(functools.partial(solve, learnt=learnt), left, right, max_disp,
                              cfg, near.bands)
    result.seconds = {**seconds, **result.seconds}
    result.photometric = memory.correction
    # The last full search's cost-curve features (a band's curve is short); where the
    # coarse look searched a moved pixel's whole range, that curve's (what it shows now).
    result.curve = memory.curve
    if coarse_curve is not None:
        result.curve = video.looked_curve(memory.curve, coarse_curve, near.look[0], near.moved)
    _fit_planes(result, left, max_disp)
    result.disparity = video.hold(near, result.disparity, cfg.temporal)
    return _with_confidence(result, left, max_disp)


def _coarse_look(left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config,
                 learnt: Learnt, rows: tuple[int, int]
                 ) -> tuple[Bands, dict[str, np.ndarray] | None]:
    """A search of the whole range one pyramid level down (an eighth of the full search's
    cells a row) over ``rows`` (first, stop): the bands at this size around it (none in the
    other rows), and its cost-curve features at this size over those rows."""
    first, stop = rows
    _, coarse_max = pyramid.level_down(left.shape[1], max_disp)
    small_l = downsample(left[first:stop])
    coarse = scale.in_stripes(functools.partial(solve, learnt=learnt), small_l,
                              downsample(right[first:stop]), coarse_max, cfg.a_level_down())
    shape = (stop - first, left.shape[1])
    bands = pyramid.bands_from_coarse(coarse.disparity, coarse.labels, shape, max_disp,
                                      cfg.bands, views=(left[first:stop], small_l))
    curve = None if coarse.curve is None else {
        name: upsample_nearest(values, shape) for name, values in coarse.curve.items()}
    return bands.placed(first, left.shape[0]), curve


def _learn(left: np.ndarray, right: np.ndarray, cfg: Config, colour_weight: float,
           seconds: dict[str, float]) -> Learnt:
    """What every level's solver is given of the pair (its noise measured once, here)."""
    if not cfg.noise.adapt:
        return learn(left, right, cfg, colour_weight)
    with timed(seconds, "noise"):
        return learn(left, right, cfg, colour_weight)


def _fit_planes(result: MatchResult, left: np.ndarray, max_disp: int) -> None:
    """Slanted planes (when on) and the range's limits, into ``result``."""
    # 4. Slanted planes over depth-aware regions.
    adapted = result.config  # with the noise adaptation's changes
    if adapted.planes.enabled and result.labels is not None:
        with timed(result.seconds, "planes"):
            result.disparity = planes.fit_planes(result.disparity, result.labels, left,
                                                 adapted.arms, adapted.planes)
    # A disparity outside the searched range is no estimate: a sub-pixel fit at the
    # range's end or a plane's fill stops at the end (the confidence marks such pixels).
    np.clip(result.disparity, 0, max_disp, out=result.disparity,
            where=np.isfinite(result.disparity))


def _with_confidence(result: MatchResult, left: np.ndarray, max_disp: int) -> MatchResult:
    """``result`` with how likely each disparity is right."""
    # 5. How likely each disparity is right.
    with timed(result.seconds, "confidence"):
        result.confidence = confidence.confidence_map(result.disparity, result.labels, left,
                                                      result.curve, max_disp + 1)
    return result
