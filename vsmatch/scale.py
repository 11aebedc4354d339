"""Bookkeeping around one level's solver: offsets, pyramid levels, stripes and the
memory budget. Nothing here knows the method: a solver (``vsmatch.level.solve``) is passed
in, as scikit-image's ``coarse_to_fine`` takes its solver.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from . import confidence, disparity, pyramid, volumes
from .bands import Bands
from .config import Config
from .disparity import INVALID_DISPARITY
from .images import downsample
from .result import MatchResult, timed
from .tiles import stripe_layout

#: One level's solver: (left, right, max_disp, config, bands or None) -> MatchResult; the
#: same for every level and stripe of a pair (what it learnt of the pair is bound in).
Solver = Callable[[np.ndarray, np.ndarray, int, Config, "Bands | None"], MatchResult]
#: The method over ``0 .. max_disp``: (left, right, max_disp) -> MatchResult.
FromZero = Callable[[np.ndarray, np.ndarray, int], MatchResult]


def with_offset(run_from_zero: FromZero, left: np.ndarray, right: np.ndarray, min_disp: int,
                max_disp: int) -> MatchResult:
    """Disparities ``min_disp .. max_disp`` of the views by ``run_from_zero``, which searches
    ``0 .. max`` (offsets are bookkeeping, not the method)."""
    if min_disp == 0:
        result = run_from_zero(left, right, max_disp)
        result.search_range = (0, max_disp)
        return result
    if min_disp < 0:
        return _below_zero(run_from_zero, left, right, max_disp, min_disp)
    # Disparities m .. max of the whole views are 0 .. max - m of views cropped by m
    # columns: the left view loses its first m columns (they have no right pixel at any
    # d >= m) and the right view its last m. Every stage then runs unchanged, and the
    # offset is added back at the end.
    keep, other = slice(min_disp, None), slice(None, left.shape[1] - min_disp)
    result = run_from_zero(np.ascontiguousarray(left[:, keep]),
                           np.ascontiguousarray(right[:, other]), max_disp - min_disp)
    return _placed(result, left.shape[:2], keep, min_disp, max_disp)


def _below_zero(run_from_zero: FromZero, left: np.ndarray, right: np.ndarray, max_disp: int,
                min_disp: int) -> MatchResult:
    """Disparities ``min_disp .. max_disp`` with ``min_disp < 0`` (a verged rig's far
    scene): 0 .. max - min of the left view and the right view moved |min| columns left,
    its last |min| columns repeating its last one. Every left column keeps its candidates
    that lie in the right view; a winner that lands in the repeated columns (x - d beyond
    the right view's last column) is out of view, and marked invalid."""
    width, shift = left.shape[1], -min_disp
    moved = np.empty_like(right)
    moved[:, :width - shift] = right[:, shift:]
    moved[:, width - shift:] = right[:, -1:]
    result = run_from_zero(left, moved, max_disp - min_disp)
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


def search_levels(width: int, height: int, max_disp: int, cfg: Config) -> int:
    """Pyramid levels below views ``width`` x ``height`` where ``cfg``'s full search over
    ``0 .. max_disp`` runs (:func:`vsmatch.pyramid.coarse_levels` with the config's limits;
    ``height`` 0: no limit on the pair's cells)."""
    return pyramid.coarse_levels(width, max_disp + 1, cfg.pyramid.max_row_cells,
                                 cfg.pyramid.min_levels, height, cfg.pyramid.max_cells)


def full_search_size(width: int, max_disp: int, cfg: Config, height: int = 0
                     ) -> tuple[int, int]:
    """Width and disparity count of the pyramid level where the full search runs."""
    for _ in range(search_levels(width, height, max_disp, cfg)):
        width, max_disp = pyramid.level_down(width, max_disp)
    return width, max_disp + 1


def coarse_to_fine(solve: Solver, left: np.ndarray, right: np.ndarray, max_disp: int,
                   cfg: Config, levels: int) -> MatchResult:
    """``solve`` over the whole range ``levels`` pyramid levels down, then at each level up
    over bands around twice the estimate below (``pyramid.bands_from_coarse``); each level
    in stripes (:func:`in_stripes`), each level down with ``cfg.a_level_down()``. The
    solver and the config are all this knows of the method."""
    if levels == 0:
        return in_stripes(solve, left, right, max_disp, cfg)
    small_l, small_r = downsample(left), downsample(right)
    _, coarse_max = pyramid.level_down(left.shape[1], max_disp)
    coarse = coarse_to_fine(solve, small_l, small_r, coarse_max, cfg.a_level_down(),
                            levels - 1)
    with timed(coarse.seconds, "bands"):
        bands = pyramid.bands_from_coarse(coarse.disparity, coarse.labels, left.shape[:2],
                                          max_disp, cfg.bands, views=(left, small_l))
    result = in_stripes(solve, left, right, max_disp, cfg, bands)
    seconds = dict(coarse.seconds)
    for name, value in result.seconds.items():
        seconds[name] = seconds.get(name, 0.0) + value
    # A band's cost curve is short: the coarse level's, over the whole range, stand for it
    # (the confidence is calibrated on whole-range curves); its repeats are tested again
    # on this level's view, counted with the confidence.
    with timed(seconds, "confidence"):
        curve = confidence.curve_a_level_up(coarse.curve, left)
    return MatchResult(disparity=result.disparity, labels=result.labels, seconds=seconds,
                       config=result.config, noise_sigma=result.noise_sigma,
                       colour_weight=result.colour_weight, levels=coarse.levels + 1,
                       stripes=coarse.stripes, curve=curve)


#: Bytes per pixel of the full search besides its two float32 cost volumes (census, arms,
#: gradients, maps; measured: 2.2 x the cost volume on cones, 60 disparities).
PIXEL_BYTES = 64


def stripe_rows(width: int, n_disp: int, cfg: Config, height: int | None = None) -> int:
    """The most rows the full search may take at once within ``memory.max_mb``; with the
    ``height`` of the views, a budget for all their rows needs no stripes (and no
    overlap)."""
    row_bytes = width * (8 * n_disp + PIXEL_BYTES)
    rows = cfg.memory.max_mb * 2**20 // row_bytes
    least = 2 * cfg.memory.overlap + 16
    if height is not None and rows >= height:
        return int(rows)
    if rows < least:
        # What one piece of the views needs, where that is less than a stripe's rows.
        need = math.ceil(min(least, height or least) * row_bytes / 2**20)
        raise ValueError(f"a memory budget of {cfg.memory.max_mb} MB is too small for "
                         f"stripes of 16 rows and twice memory.overlap = {cfg.memory.overlap} "
                         f"rows of {width} pixels x {n_disp} disparities; allow at least "
                         f"{need} MB" + (" or a smaller overlap" if cfg.memory.overlap > 64
                                         else ""))
    return int(rows)


def in_stripes(solve: Solver, left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config,
               bands: Bands | None = None) -> MatchResult:
    """``solve`` (one level's solver) on horizontal stripes that fit ``memory.max_mb``.

    The layout depends on the image size, the range and the config only, so results are
    the same on any machine; they differ from one piece near the seams (README).
    """
    height, width = left.shape[:2]
    depth = max_disp + 1 if bands is None else bands.width
    layout = stripe_layout(height, stripe_rows(width, depth, cfg, height), cfg.memory.overlap)
    if len(layout) == 1:
        return solve(left, right, max_disp, cfg, bands)
    disp = np.empty((height, width), dtype=np.float32)
    labels = None
    curve = None
    seconds: dict[str, float] = {}
    with volumes.shared_by_stripes():
        for first, stop, core_first, core_stop in layout:
            part = solve(left[first:stop], right[first:stop], max_disp, cfg,
                         None if bands is None else bands.rows(first, stop))
            if part.curve is not None and curve is None:
                curve = {name: np.empty((height, width), np.float32) for name in part.curve}
            core = slice(core_first - first, core_stop - first)
            disp[core_first:core_stop] = part.disparity[core]
            if part.labels is not None:
                if labels is None:
                    labels = np.empty((height, width), dtype=np.uint8)
                labels[core_first:core_stop] = part.labels[core]
            for name, values in (part.curve or {}).items():
                curve[name][core_first:core_stop] = values[core]
            for name, value in part.seconds.items():
                seconds[name] = seconds.get(name, 0.0) + value
    return MatchResult(disparity=disp, labels=labels, seconds=seconds, config=part.config,
                       noise_sigma=part.noise_sigma, colour_weight=part.colour_weight,
                       stripes=len(layout), curve=curve)
