"""The whole method, stage by stage: :func:`match` reads like the algorithm."""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import cv2
import numpy as np

from . import (aggregation, confidence, cost, disparity, noise, optimization, photometric, planes,
               pyramid, refinement, sensitivity, volumes)
from .bands import Bands
from .config import Config, CostConfig, load_config
from .disparity import INVALID_DISPARITY
from .images import downsample, to_grey, upsample_nearest
from .tiles import stripe_layout


@dataclass
class MatchResult:
    """The left-view disparity and what was learnt on the way."""

    disparity: np.ndarray
    labels: np.ndarray | None = None
    seconds: dict[str, float] = field(default_factory=dict)
    config: Config | None = None  # as used, after any noise adaptation
    noise_sigma: float | None = None  # estimated, when noise.adapt is on
    levels: int = 0  # pyramid levels below the input where the full search ran
    stripes: int = 1  # stripes the full search ran in
    photometric: photometric.Correction | None = None  # the right view's colour map, if any
    search_range: tuple[int, int] | None = None  # (min_disp, max_disp) searched
    # How likely each disparity is right, in [0, 1] (vsmatch.confidence); float32 (H, W).
    confidence: np.ndarray | None = None
    # The cost-curve features the confidence is made from (vsmatch.confidence).
    curve: dict[str, np.ndarray] | None = None


def check_views(left: np.ndarray, right: np.ndarray, cfg: Config) -> None:
    """Refuse views the method cannot run on whatever the range (type, shape, size)."""
    for name, image in (("left", left), ("right", right)):
        if not isinstance(image, np.ndarray) or image.ndim not in (2, 3) or (
                image.ndim == 3 and image.shape[2] != 3):
            raise ValueError(f"{name} image must be an (H, W) or (H, W, 3) array, "
                             f"got shape {getattr(image, 'shape', None)}")
        if image.dtype != np.uint8:
            raise ValueError(f"{name} image must be uint8, got {image.dtype}")
    if left.shape[:2] != right.shape[:2]:
        raise ValueError(f"left and right images differ in size: {left.shape[1]}x{left.shape[0]}"
                         f" and {right.shape[1]}x{right.shape[0]}")
    if left.ndim != right.ndim:
        kinds = ["grey (H, W)" if image.ndim == 2 else "colour (H, W, 3)"
                 for image in (left, right)]
        raise ValueError(f"the left image is {kinds[0]} and the right {kinds[1]}: give "
                         "both grey or both colour")
    height, width = left.shape[:2]
    if width < cfg.cost.census_width or height < cfg.cost.census_height:
        raise ValueError(f"images of {width}x{height} are smaller than the census window "
                         f"{cfg.cost.census_width}x{cfg.cost.census_height}")


def check_pair(left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config,
               min_disp: int = 0) -> None:
    """Refuse inputs the method cannot run on, with a message naming the problem."""
    check_views(left, right, cfg)
    width = left.shape[1]
    for name, value in (("max_disp", max_disp), ("min_disp", min_disp)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise ValueError(f"{name} must be an integer, got {value!r}")
    if min_disp == 0 and not 0 < max_disp < width:
        raise ValueError(f"max_disp = {max_disp} must be between 1 and the image width "
                         f"minus one ({width - 1})")
    if max_disp <= min_disp:
        raise ValueError(f"max_disp = {max_disp} must be larger than min_disp = {min_disp}")
    # With an offset the views are cropped by |min_disp| columns (see run()).
    cropped = width - abs(min_disp)
    if max_disp - min_disp >= cropped or cropped < cfg.cost.census_width:
        raise ValueError(f"the range {min_disp}..{max_disp} is too wide for images "
                         f"{width} pixels wide")
    stripe_rows(*full_search_size(cropped, max_disp - min_disp, cfg, left.shape[0]),
                cfg)  # budget enough?


def full_search_size(width: int, max_disp: int, cfg: Config, height: int = 0
                     ) -> tuple[int, int]:
    """Width and disparity count of the pyramid level where the full search runs."""
    for _ in range(pyramid.coarse_levels(width, max_disp + 1, cfg.pyramid.max_row_cells,
                                          cfg.pyramid.min_levels, height,
                                          cfg.pyramid.max_cells)):
        width, max_disp = pyramid.level_down(width, max_disp)
    return width, max_disp + 1


def match(left: np.ndarray, right: np.ndarray, *, max_disp: int | None = None,
          min_disp: int | None = None, config: Config | str | None = None) -> np.ndarray:
    """Left-view disparity of a rectified stereo pair.

    Parameters
    ----------
    left, right : ndarray, (H, W, 3) uint8 in BGR order (as ``cv2.imread`` gives), or (H, W)
        uint8 grey. Both the same size.
    max_disp : int or None
        The largest disparity searched; disparities ``min_disp .. max_disp`` are considered.
        ``None`` finds the range from the pair, as ``vsmatch run`` without ``--max-disp``
        (:func:`vsmatch.estimate_disparity_range`; raises ValueError for a pair whose
        range cannot be found, or whose views are swapped or not rectified).
    min_disp : int, optional
        The smallest disparity searched (default 0, or the found range's bottom, which
        may be negative, when ``max_disp`` is None; may be negative). As with OpenCV's
        ``minDisparity``, left pixels with no candidate in the range are invalid: the
        first ``min_disp`` columns when it is positive; when negative, the pixels whose
        match lies beyond the right view's last column.
    config : Config, bundled config name or YAML path, optional
        The method's parameters; ``None`` uses the bundled ``default``.

    Returns
    -------
    ndarray, (H, W) float32
        Disparity in pixels, left view. A pixel without an estimate holds
        :data:`vsmatch.INVALID_DISPARITY` (``inf``).
    """
    return run(left, right, max_disp=max_disp, min_disp=min_disp, config=config).disparity


def run(left: np.ndarray, right: np.ndarray, *, max_disp: int | None = None,
        min_disp: int | None = None, config: Config | str | None = None) -> MatchResult:
    """:func:`match` with per-stage timings, the left-right labels and the range used."""
    cfg = load_config(config)
    if max_disp is None:
        from .search_range import resolve_range

        check_views(left, right, cfg)  # the views' own checks, before the features
        searched = resolve_range(left, right, min_disp=min_disp)
        min_disp, max_disp = searched.min_disp, searched.max_disp
    min_disp = 0 if min_disp is None else min_disp
    check_pair(left, right, max_disp, cfg, min_disp)
    if min_disp == 0:
        result = _run_from_zero(left, right, max_disp, cfg)
        result.search_range = (0, max_disp)
        return result
    if min_disp < 0:
        return _run_below_zero(left, right, max_disp, min_disp, cfg)
    # Disparities m .. max of the whole views are 0 .. max - m of views cropped by m
    # columns: the left view loses its first m columns (they have no right pixel at any
    # d >= m) and the right view its last m. Every stage then runs unchanged, and the
    # offset is added back at the end.
    keep, other = slice(min_disp, None), slice(None, left.shape[1] - min_disp)
    result = _run_from_zero(np.ascontiguousarray(left[:, keep]),
                            np.ascontiguousarray(right[:, other]), max_disp - min_disp, cfg)
    return _placed(result, left.shape[:2], keep, min_disp, max_disp)


def _run_below_zero(left: np.ndarray, right: np.ndarray, max_disp: int, min_disp: int,
                    cfg: Config) -> MatchResult:
    """Disparities ``min_disp .. max_disp`` with ``min_disp < 0`` (a verged rig's far
    scene): 0 .. max - min of the left view and the right view moved |min| columns left,
    its last |min| columns repeating its last one. Every left column keeps its candidates
    that lie in the right view; a winner that lands in the repeated columns (x - d beyond
    the right view's last column) is out of view, and marked invalid."""
    width, shift = left.shape[1], -min_disp
    moved = np.empty_like(right)
    moved[:, :width - shift] = right[:, shift:]
    moved[:, width - shift:] = right[:, -1:]
    result = _run_from_zero(left, moved, max_disp - min_disp, cfg)
    placed = _placed(result, left.shape[:2], slice(None), min_disp, max_disp)
    # In float64: a float32 difference rounds 419.500003 down to the limit itself.
    columns = np.arange(width, dtype=np.float64)[None, :]
    with np.errstate(invalid="ignore"):
        beyond = columns - placed.disparity > width - 0.5
    placed.disparity[beyond] = INVALID_DISPARITY
    placed.confidence[beyond] = 0.0
    if placed.labels is not None:
        placed.labels[beyond] = disparity.OCCLUDED
    return placed


def _placed(result: MatchResult, shape: tuple[int, int], keep: slice, min_disp: int,
            max_disp: int) -> MatchResult:
    """``result``, of the columns ``keep`` of views ``shape`` matched from 0, as the whole
    views' result for ``min_disp .. max_disp``: the offset added back, the columns outside
    ``keep`` invalid (no candidate there, no confidence)."""
    disp = np.full(shape, INVALID_DISPARITY, dtype=np.float32)
    disp[:, keep] = result.disparity + np.float32(min_disp)
    result.disparity = disp
    if result.labels is not None:
        labels = np.full(shape, disparity.OCCLUDED, dtype=np.uint8)
        labels[:, keep] = result.labels
        result.labels = labels
    confidence = np.zeros(shape, dtype=np.float32)
    confidence[:, keep] = result.confidence
    result.confidence = confidence
    result.curve = None  # it describes the views as matched, not as given
    result.search_range = (min_disp, max_disp)
    return result


def _run_from_zero(left: np.ndarray, right: np.ndarray, max_disp: int,
                   cfg: Config) -> MatchResult:
    """Disparities ``0 .. max_disp``: the exposure corrected when asked, then
    coarse-to-fine when a row is too wide a search."""
    seconds: dict[str, float] = {}
    correction = None
    if cfg.photometric.enabled:
        with _stage(seconds, "photometric"):
            right, cfg, correction = _correct_exposure(left, right, max_disp, cfg)
    levels = pyramid.coarse_levels(left.shape[1], max_disp + 1, cfg.pyramid.max_row_cells,
                                   cfg.pyramid.min_levels, left.shape[0], cfg.pyramid.max_cells)
    result = _coarse_to_fine(left, right, max_disp, cfg, levels)
    result.seconds = {**seconds, **result.seconds}
    adapted = result.config  # with the noise adaptation's changes
    if adapted.planes.enabled and result.labels is not None:
        with _stage(result.seconds, "planes"):
            result.disparity = planes.fit_planes(result.disparity, result.labels, left,
                                                 adapted.arms, adapted.planes)
    result.photometric = correction
    # A disparity outside the searched range is no estimate: a sub-pixel fit at the
    # range's end or a plane's fill stops at the end (the confidence marks such pixels).
    finite = np.isfinite(result.disparity)
    result.disparity[finite] = np.clip(result.disparity[finite], 0, max_disp)
    with _stage(result.seconds, "confidence"):
        result.confidence = confidence.confidence_map(result.disparity, result.labels, left,
                                                      result.curve, max_disp + 1)
    return result


def _correct_exposure(left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config
                      ) -> tuple[np.ndarray, Config, photometric.Correction | None]:
    """The right view mapped onto the left's colours and the config with the colour
    term's weight, learnt from a first match on small views (``vsmatch.photometric``)."""
    small_l, small_r, small_max = left, right, max_disp
    while True:  # at least one level down: only the statistics of the matches are used
        width, small_max = pyramid.level_down(small_l.shape[1], small_max)
        if width < 2 * cfg.cost.census_width or small_max < 1 or min(
                small_l.shape[:2]) < 2 * cfg.cost.census_height:
            return right, cfg, None
        small_l, small_r = downsample(small_l), downsample(small_r)
        if width <= cfg.photometric.max_width:
            break
    first_disp, matched = _first_match(small_l, small_r, small_max, cfg)
    correction = photometric.learn(small_l, small_r, first_disp, matched,
                                   cfg.photometric.field_sigma)
    if correction is None:
        return right, cfg, None
    weight = photometric.colour_weight(correction.excess, cfg.photometric)
    cfg = dataclasses.replace(cfg, cost=dataclasses.replace(
        cfg.cost, ad_weight=cfg.cost.ad_weight * weight))
    return photometric.apply(right, correction), cfg, correction


#: Channels ``cv2.blur`` filters at once: OpenCV 5 takes at most 128 (4.x took 512); each
#: channel is blurred on its own, so the chunk size does not change the result.
BLUR_MAX_CHANNELS = 128


def _first_match(left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config
                 ) -> tuple[np.ndarray, np.ndarray]:
    """A quick match for the photometric statistics: census and gradient costs (the colour
    term is what is in doubt) averaged over ``photometric.box`` square windows, winner
    takes all in both views, the exact left-right check. Returns the left disparity and
    the pixels that pass the check."""
    volume, _, _ = _matching_costs(left, right, max_disp + 1,
                                   dataclasses.replace(cfg.cost, lambda_ad=None),
                                   direction=False)
    box = (cfg.photometric.box, cfg.photometric.box)
    step = BLUR_MAX_CHANNELS
    for first in range(0, volume.shape[2], step):
        part = np.ascontiguousarray(volume[:, :, first:first + step])  # no copy if whole
        cv2.blur(part, box, dst=part)  # in place: no new volume to map
        if not np.shares_memory(part, volume):
            volume[:, :, first:first + step] = part
    disp_l, disp_r = disparity.winner_takes_all_both(volume)
    labels = disparity.left_right_check(disp_l, disp_r, n_disp=max_disp + 1, tolerance=0)
    return disp_l, labels == disparity.VALID


def _matching_costs(left: np.ndarray, right: np.ndarray, n_disp: int, cost_cfg: CostConfig,
                    direction: bool = True, bands: Bands | None = None
                    ) -> tuple[np.ndarray, tuple, tuple]:
    """The cost volume (ALGORITHM.md §1-2) and each view's gradient magnitude and
    direction (None unless ``direction``), which the arms need too."""
    grey_l, grey_r = to_grey(left), to_grey(right)
    sens_l = sensitivity.visual_sensitivity(grey_l, direction)
    sens_r = sensitivity.visual_sensitivity(grey_r, direction)
    volume = cost.cost_volume(left, right, cost.census_for(grey_l, cost_cfg),
                              cost.census_for(grey_r, cost_cfg), sens_l[0], sens_r[0],
                              n_disp=n_disp, cfg=cost_cfg, bands=bands)
    return volume, sens_l, sens_r


@contextmanager
def _stage(seconds: dict[str, float], name: str):
    """Add the time the block takes to ``seconds[name]``."""
    start = time.perf_counter()
    yield
    seconds[name] = seconds.get(name, 0.0) + time.perf_counter() - start


def _coarse_to_fine(left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config,
                    levels: int) -> MatchResult:
    """The full search ``levels`` pyramid levels down, then at each level up the same
    method over bands around twice the estimate below (``pyramid.bands_from_coarse``)."""
    if levels == 0:
        return _full_search_in_stripes(left, right, max_disp, cfg)
    small_l, small_r = downsample(left), downsample(right)
    _, coarse_max = pyramid.level_down(left.shape[1], max_disp)
    coarse = _coarse_to_fine(small_l, small_r, coarse_max, cfg, levels - 1)
    with _stage(coarse.seconds, "bands"):
        bands = pyramid.bands_from_coarse(coarse.disparity, coarse.labels, left.shape[:2],
                                          max_disp, cfg.pyramid)
    result = _full_search_in_stripes(left, right, max_disp, cfg, bands)
    seconds = dict(coarse.seconds)
    for name, value in result.seconds.items():
        seconds[name] = seconds.get(name, 0.0) + value
    # A band's cost curve is short: the coarse level's, over the whole range, stand for it
    # (the confidence is calibrated on whole-range curves).
    curve = {k: upsample_nearest(v, left.shape[:2]) for k, v in coarse.curve.items()}
    return MatchResult(disparity=result.disparity, labels=result.labels, seconds=seconds,
                       config=coarse.config, noise_sigma=coarse.noise_sigma,
                       levels=coarse.levels + 1, stripes=coarse.stripes, curve=curve)


#: Bytes per pixel of the full search besides its two float32 cost volumes (census, arms,
#: gradients, maps; measured: 2.2 x the cost volume on cones, 60 disparities).
PIXEL_BYTES = 64


def stripe_rows(width: int, n_disp: int, cfg: Config) -> int:
    """The most rows the full search may take at once within ``memory.max_mb``."""
    row_bytes = width * (8 * n_disp + PIXEL_BYTES)
    rows = cfg.memory.max_mb * 2**20 // row_bytes
    if rows < 2 * cfg.memory.overlap + 16:
        need = math.ceil((2 * cfg.memory.overlap + 16) * row_bytes / 2**20)
        raise ValueError(f"a memory budget of {cfg.memory.max_mb} MB is too small for "
                         f"stripes of 16 rows and twice memory.overlap = {cfg.memory.overlap} "
                         f"rows of {width} pixels x {n_disp} disparities; allow at least "
                         f"{need} MB" + (" or a smaller overlap" if cfg.memory.overlap > 64
                                         else ""))
    return int(rows)


def _full_search_in_stripes(left: np.ndarray, right: np.ndarray, max_disp: int,
                            cfg: Config, bands: Bands | None = None) -> MatchResult:
    """:func:`_full_search` on horizontal stripes that fit ``memory.max_mb``.

    The layout depends on the image size, the range and the config only, so results are
    the same on any machine; they differ from one piece near the seams (README).
    """
    height, width = left.shape[:2]
    depth = max_disp + 1 if bands is None else bands.width
    layout = stripe_layout(height, stripe_rows(width, depth, cfg), cfg.memory.overlap)
    if len(layout) == 1:
        return _full_search(left, right, max_disp, cfg, bands)
    noise_sigma = None
    if cfg.noise.adapt:  # once for the whole pair, as in one piece
        cfg, noise_sigma = noise.adapt_to_pair(cfg, left, right)
        cfg = dataclasses.replace(cfg, noise=dataclasses.replace(cfg.noise, adapt=False))
    disp = np.empty((height, width), dtype=np.float32)
    labels = None
    curve = {name: np.empty((height, width), np.float32) for name in confidence.CURVE_FEATURES}
    seconds: dict[str, float] = {}
    for first, stop, core_first, core_stop in layout:
        part = _full_search(left[first:stop], right[first:stop], max_disp, cfg,
                            None if bands is None else bands.rows(first, stop))
        core = slice(core_first - first, core_stop - first)
        disp[core_first:core_stop] = part.disparity[core]
        if part.labels is not None:
            if labels is None:
                labels = np.empty((height, width), dtype=np.uint8)
            labels[core_first:core_stop] = part.labels[core]
        for name, values in part.curve.items():
            curve[name][core_first:core_stop] = values[core]
        for name, value in part.seconds.items():
            seconds[name] = seconds.get(name, 0.0) + value
    return MatchResult(disparity=disp, labels=labels, seconds=seconds, config=cfg,
                       noise_sigma=noise_sigma, stripes=len(layout), curve=curve)


def _full_search(left: np.ndarray, right: np.ndarray, max_disp: int,
                 cfg: Config, bands: Bands | None = None) -> MatchResult:
    """The stages in order, every pixel searching its band of ``0 .. max_disp`` (default:
    the whole range)."""
    n_disp = int(max_disp) + 1
    seconds: dict[str, float] = {}
    stage = functools.partial(_stage, seconds)

    noise_sigma = None
    if cfg.noise.adapt:
        with stage("noise"):
            cfg, noise_sigma = noise.adapt_to_pair(cfg, left, right)
    if cfg.cost.presmooth_sigma > 0:
        with stage("presmooth"):
            left = sensitivity.presmooth(left, cfg.cost.presmooth_sigma)
            right = sensitivity.presmooth(right, cfg.cost.presmooth_sigma)

    with stage("cost"):
        volume, (grad_l, theta_l), (grad_r, theta_r) = _matching_costs(
            left, right, n_disp, cfg.cost, direction=cfg.arms.kappa != 0, bands=bands)

    arms_cfg = cfg.arms
    scanline = cfg.scanline.enabled
    if bands is not None and not bands.is_full:  # the finer levels' options
        scanline = scanline and cfg.pyramid.scanline
        support = cfg.pyramid.support
        arms_cfg = dataclasses.replace(arms_cfg, l1=min(arms_cfg.l1, support),
                                       l2=min(arms_cfg.l2, support))
    arms_l = arms_r = None
    if cfg.aggregation.iterations > 0 or cfg.voting.enabled:
        with stage("arms"):
            arms_l = aggregation.cross_arms(left, theta_l, grad_l, arms_cfg)
            if cfg.aggregation.iterations > 0:
                arms_r = aggregation.cross_arms(right, theta_r, grad_r, arms_cfg)
    # One work volume serves aggregation, then holds the scanline costs: the cost volume
    # is allocated twice, not three times (allocation is a measurable share of the time).
    work = volumes.volume("work", volume.shape)
    if cfg.aggregation.iterations > 0:
        with stage("aggregation"):
            volume = aggregation.aggregate_cross(volume, arms_l, arms_r, scratch=work,
                                                 iterations=cfg.aggregation.iterations,
                                                 bands=bands)

    aggregated = volume
    if scanline:
        with stage("scanline"):
            volume = optimization.scanline_optimise(volume, left, right, cfg.scanline,
                                                    out=work, bands=bands)

    with stage("wta"):  # with the winners' cost curves, for the confidence
        if cfg.consistency.enabled:
            disp_l, disp_r, curves = disparity.winner_takes_all_with_curve(volume,
                                                                           bands=bands)
        else:
            disp_l = disparity.winner_takes_all(volume, bands)
            curves = confidence.cost_curves(volume, disp_l, bands)
    with stage("confidence"):
        curve = confidence.curve_features(curves, arms_l)
        if aggregated is not volume:  # the same margin before the scanline optimisation
            raw = confidence.cost_curves(aggregated, disp_l, bands)
            curve["raw_margin"] = confidence.curve_features(raw, None)["margin"]
        else:
            curve["raw_margin"] = curve["margin"]

    labels = None
    if cfg.consistency.enabled:
        with stage("consistency"):
            labels = disparity.left_right_check(disp_l, disp_r, n_disp=n_disp,
                                                tolerance=cfg.consistency.tolerance)
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

    return MatchResult(disparity=result, labels=labels, seconds=seconds, config=cfg,
                       noise_sigma=noise_sigma, curve=curve)

