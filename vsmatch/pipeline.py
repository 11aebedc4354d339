"""The whole method, stage by stage: :func:`match` reads like the algorithm."""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from . import aggregation, cost, disparity, noise, optimization, refinement, sensitivity
from .config import Config, load_config
from .images import to_grey


@dataclass
class MatchResult:
    """The left-view disparity and what was learnt on the way."""

    disparity: np.ndarray
    labels: np.ndarray | None = None
    seconds: dict[str, float] = field(default_factory=dict)
    config: Config | None = None  # as used, after any noise adaptation
    noise_sigma: float | None = None  # estimated, when noise.adapt is on


def check_pair(left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config) -> None:
    """Refuse inputs the method cannot run on, with a message naming the problem."""
    for name, image in (("left", left), ("right", right)):
        if not isinstance(image, np.ndarray) or image.ndim not in (2, 3) or (
                image.ndim == 3 and image.shape[2] != 3):
            raise ValueError(f"{name} image must be an (H, W) or (H, W, 3) array, "
                             f"got shape {getattr(image, 'shape', None)}")
        if image.dtype != np.uint8:
            raise ValueError(f"{name} image must be uint8, got {image.dtype}")
    if left.shape != right.shape:
        raise ValueError(f"left and right images differ in size: {left.shape[1]}x{left.shape[0]}"
                         f" and {right.shape[1]}x{right.shape[0]}")
    height, width = left.shape[:2]
    if width < cfg.cost.census_width or height < cfg.cost.census_height:
        raise ValueError(f"images of {width}x{height} are smaller than the census window "
                         f"{cfg.cost.census_width}x{cfg.cost.census_height}")
    if isinstance(max_disp, bool) or not isinstance(max_disp, (int, np.integer)):
        raise ValueError(f"max_disp must be an integer, got {max_disp!r}")
    if not 0 < max_disp < width:
        raise ValueError(f"max_disp = {max_disp} must be between 1 and the image width "
                         f"minus one ({width - 1})")


def match(left: np.ndarray, right: np.ndarray, *, max_disp: int,
          config: Config | str | None = None) -> np.ndarray:
    """Left-view disparity of a rectified stereo pair.

    Parameters
    ----------
    left, right : ndarray, (H, W, 3) uint8 in BGR order (as ``cv2.imread`` gives), or (H, W)
        uint8 grey. Both the same size.
    max_disp : int
        The largest disparity searched; disparities ``0 .. max_disp`` are considered.
    config : Config, bundled config name or YAML path, optional
        The method's parameters; ``None`` uses the bundled ``default``.

    Returns
    -------
    ndarray, (H, W) float32
        Disparity in pixels, left view. A pixel without an estimate holds
        :data:`vsmatch.INVALID_DISPARITY` (``inf``).
    """
    return run(left, right, max_disp=max_disp, config=config).disparity


def run(left: np.ndarray, right: np.ndarray, *, max_disp: int,
        config: Config | str | None = None) -> MatchResult:
    """:func:`match` with per-stage timings and the left-right labels."""
    cfg = load_config(config)
    check_pair(left, right, max_disp, cfg)
    n_disp = int(max_disp) + 1
    seconds: dict[str, float] = {}

    @contextmanager
    def stage(name: str):
        start = time.perf_counter()
        yield
        seconds[name] = seconds.get(name, 0.0) + time.perf_counter() - start

    noise_sigma = None
    if cfg.noise.adapt:
        with stage("noise"):
            noise_sigma = 0.5 * (noise.estimate_noise(left) + noise.estimate_noise(right))
            cfg = noise.adapt_to_noise(cfg, noise_sigma)
    if cfg.cost.presmooth_sigma > 0:
        with stage("presmooth"):
            left = sensitivity.presmooth(left, cfg.cost.presmooth_sigma)
            right = sensitivity.presmooth(right, cfg.cost.presmooth_sigma)

    with stage("cost"):
        grey_l, grey_r = to_grey(left), to_grey(right)
        grad_l, theta_l = sensitivity.visual_sensitivity(grey_l)
        grad_r, theta_r = sensitivity.visual_sensitivity(grey_r)
        census_kw = dict(width=cfg.cost.census_width, height=cfg.cost.census_height,
                         band=cfg.cost.census_band)
        volume = cost.cost_volume(left, right,
                                  cost.census_transform(grey_l, **census_kw),
                                  cost.census_transform(grey_r, **census_kw),
                                  grad_l, grad_r, n_disp=n_disp, cfg=cfg.cost)

    arms_l = arms_r = None
    if cfg.aggregation.iterations > 0 or cfg.voting.enabled:
        with stage("arms"):
            arms_l = aggregation.cross_arms(left, theta_l, grad_l, cfg.arms)
            if cfg.aggregation.iterations > 0:
                arms_r = aggregation.cross_arms(right, theta_r, grad_r, cfg.arms)
    # One work volume serves aggregation, then holds the scanline costs: the cost volume
    # is allocated twice, not three times (allocation is a measurable share of the time).
    work = np.empty_like(volume)
    if cfg.aggregation.iterations > 0:
        with stage("aggregation"):
            volume = aggregation.aggregate_cross(volume, arms_l, arms_r, scratch=work,
                                                 iterations=cfg.aggregation.iterations)

    aggregated = volume
    if cfg.scanline.enabled:
        with stage("scanline"):
            volume = optimization.scanline_optimise(volume, left, right, cfg.scanline,
                                                    out=work)

    with stage("wta"):
        if cfg.consistency.enabled:
            disp_l, disp_r = disparity.winner_takes_all_both(volume)
        else:
            disp_l = disparity.winner_takes_all(volume)

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

    if cfg.discontinuity.enabled:
        with stage("discontinuity"):
            result = refinement.discontinuity_adjust(result, volume, cfg.discontinuity)
    if cfg.subpixel.enabled:
        with stage("subpixel"):
            # The aggregated costs, not the scanline ones: the penalties flatten the cost
            # curve around the minimum (measured: fewer bad pixels at 0.5 and 1.0).
            result = refinement.subpixel(result, aggregated)
    if cfg.subpixel.median:
        with stage("median"):
            result = refinement.median3(result)

    return MatchResult(disparity=result, labels=labels, seconds=seconds, config=cfg,
                       noise_sigma=noise_sigma)
