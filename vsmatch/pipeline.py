"""The method over a known range, step by step (ALGORITHM.md): :func:`run` reads like the
algorithm; ``vsmatch.level`` holds one level's stages, ``vsmatch.scale`` the bookkeeping
around them. ``vsmatch.match`` and ``vsmatch.run`` (``vsmatch.api``) find the range first
when none is given."""

from __future__ import annotations

import functools

import numpy as np

from . import confidence, exposure, planes, pyramid, scale
from .checks import check_pair, check_views  # noqa: F401  (the inputs' checks, re-exported)
from .config import Config, load_config
from .level import solve
from .result import MatchResult, timed


def match(left: np.ndarray, right: np.ndarray, *, max_disp: int, min_disp: int = 0,
          config: Config | str | None = None) -> np.ndarray:
    """:func:`vsmatch.match` over the range ``min_disp .. max_disp``."""
    return run(left, right, max_disp=max_disp, min_disp=min_disp, config=config).disparity


def run(left: np.ndarray, right: np.ndarray, *, max_disp: int, min_disp: int = 0,
        config: Config | str | None = None) -> MatchResult:
    """The method over ``min_disp .. max_disp``, with per-stage timings, the left-right
    labels, the confidence and the range used (:func:`vsmatch.run` for the parameters)."""
    cfg = load_config(config)
    check_pair(left, right, max_disp, cfg, min_disp)
    return scale.with_offset(functools.partial(_run_from_zero, cfg=cfg), left, right,
                             min_disp, max_disp)


def _run_from_zero(left: np.ndarray, right: np.ndarray, max_disp: int,
                   cfg: Config) -> MatchResult:
    """Disparities ``0 .. max_disp``."""
    seconds: dict[str, float] = {}
    correction = None
    # 1. The right view's colours mapped onto the left's; how far the colour term holds.
    if cfg.photometric.enabled:
        with timed(seconds, "photometric"):
            right, cfg, correction = exposure.correct_exposure(left, right, max_disp, cfg)
    # 2. Costs, aggregation, scanline, winners, checks and refinement (vsmatch.level), on
    #    the whole range where a row fits, else a level down and in bands above it.
    levels = pyramid.coarse_levels(left.shape[1], max_disp + 1, cfg.pyramid.max_row_cells,
                                   cfg.pyramid.min_levels, left.shape[0], cfg.pyramid.max_cells)
    result = scale.coarse_to_fine(solve, left, right, max_disp, cfg, levels)
    result.seconds = {**seconds, **result.seconds}
    # 3. Slanted planes over depth-aware regions.
    adapted = result.config  # with the noise adaptation's changes
    if adapted.planes.enabled and result.labels is not None:
        with timed(result.seconds, "planes"):
            result.disparity = planes.fit_planes(result.disparity, result.labels, left,
                                                 adapted.arms, adapted.planes)
    result.photometric = correction
    # A disparity outside the searched range is no estimate: a sub-pixel fit at the
    # range's end or a plane's fill stops at the end (the confidence marks such pixels).
    finite = np.isfinite(result.disparity)
    result.disparity[finite] = np.clip(result.disparity[finite], 0, max_disp)
    # 4. How likely each disparity is right.
    with timed(result.seconds, "confidence"):
        result.confidence = confidence.confidence_map(result.disparity, result.labels, left,
                                                      result.curve, max_disp + 1)
    return result
