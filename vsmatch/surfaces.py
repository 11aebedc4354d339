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

What no region's plane reaches (a shelf's board, whose crosses hold no sure pixel) may be
bridged: an unsure pixel between two sure pixels of its column (then of its row) that lie
close and agree takes the line between them, unless that puts it far behind its own match.

A bridge is one column's guess, off where the column's ends lie on other surfaces than the
board between them. With ``refit``, the regions' planes are fitted once more through every
pixel now filled (sure, taken, bridged): a board's bridges err either way and average into
the board's plane, which every pixel that was unsure then takes where the region holds
close about it (a road or wall beyond the right view's edge, too, from its visible part).

With ``long_arms``, what all this leaves unsure takes the plane of regions whose arms keep
one colour threshold along their whole length: a wall whose shading changes by more than
``arms.tau3`` within the reach of the regions above, sure only far from its blank part.

With ``segments``, last, a blank segment of the view (``vsmatch.segments``) where the match
found almost nothing sure takes the plane its edge's sure pixels show, where its pixels lie
off it: a white wall wider than every region, sure nowhere but along its skirting board.

None of these steps replaces a pixel in a shadow (``shadow``: the view's light around it
well below the view's median) that has texture: a dark object there is matched mostly
right, but its shallow cost curves read unsure, and a wide region grown across its faint
texture would carry the background's plane over it. A dark scene (more than
``dark_share`` of the view where the light, measured as for a shadow, is below
``dark_level``) has no shadow by that rule, its median being dark too; there a pixel in the
dark whose neighbourhood's cost curves show a margin (``dark_margin``) was matched, though
the matchability gate put its confidence near 0, and keeps its match.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import NamedTuple

import cv2
import numpy as np

from ._kernels.bridges import bridges_along
from .aggregation import arms_grown_below
from .bands import Bands
from .confidence import neighbourhood_margin
from .config import ArmsConfig, Config, SurfacesConfig
from .disparity import VALID
from .images import grey_levels
from .cost import banded_volume
from .level import pair_cost_terms
from .planes import region_planes
from .segments import blank_segments, bounding_box, edge_plane, segment_mask
from .sensitivity import texture


class Spread(NamedTuple):
    """The disparities after :func:`spread_planes`, and the confidence: a bridged pixel's
    is raised to ``surfaces.bridge_confidence``, a refitted one whose plane agrees with its
    disparity to ``surfaces.refit_confidence``."""

    disparity: np.ndarray
    confidence: np.ndarray


def spread_planes(disp: np.ndarray, confidence: np.ndarray, labels: np.ndarray,
                  left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config,
                  colour_weight: float = 1.0, margin: np.ndarray | None = None) -> Spread:
    """``disp`` with the unsure pixels' values (and, with ``surfaces.flat``, those without
    texture) replaced by their wide region's plane where it holds, then bridged, then given
    the long-armed regions' plane, then refitted (float32, new arrays). ``right``: the view
    as matched (after any exposure correction), ``colour_weight`` the colour term's weight
    it was matched with, ``margin`` the match's cost-curve margins (the result's
    ``curve["margin"]``; None: ``surfaces.dark_level`` has nothing to judge by)."""
    s = cfg.surfaces
    grey = grey_levels(left)  # the view's contrast, texture and shadows read it
    contrast = view_contrast(grey)
    arms = arms_grown_below(left, _wide_arms(cfg.arms, s, contrast), s.levels)
    # Longer arms, for what the regions above leave: beyond arms.l1 their threshold is
    # arms.tau3, stricter, and on a wall's shading they stop there (56 px at full size).
    long_arms = (arms_grown_below(left, _wide_arms(cfg.arms, s, contrast, long=True), s.levels)
                 if s.long_arms else None)
    disp = np.ascontiguousarray(disp, dtype=np.float32)
    # Where the view has no texture at all the match saw nothing: whatever its confidence
    # (the colour term can find a faint shading's brightness a few pixels off), unsure.
    flat = (texture(grey) < s.flat if s.flat is not None
            else np.zeros(disp.shape, bool))
    sure = (labels == VALID) & np.isfinite(disp) & (confidence >= s.fit) & ~flat
    # A pixel in a shadow keeps its own match unless it has no texture at all: its cost
    # curves are shallow, so its confidence reads low, though the match is mostly right.
    kept = (in_shadow(grey, s.levels, s.shadow, s.shadow_window) & ~flat
            if s.shadow is not None else np.zeros(disp.shape, bool))
    # A dark scene (most of the view in the dark) has no shadow, its median being dark too;
    # there a pixel in the dark whose cost curves show a margin was matched, though the
    # matchability gate (one scale for every view) read it as unmatched.
    if s.dark_level is not None and margin is not None:
        dark = in_the_dark(grey, s.levels, s.shadow_window, s.dark_level)
        if np.mean(dark) > s.dark_share:
            kept |= dark & (neighbourhood_margin(margin) >= s.dark_margin) & ~flat
    was_unsure = ((confidence < _shrunk(s.take, contrast, s.take_contrast)) | flat) & ~kept
    plane, close = _close_planes(disp, sure, arms, s, s.min_share, s.inlier, was_unsure)
    take = close & was_unsure
    # The views' census and gradients, made once for every cost taken below.
    terms = functools.cache(lambda: pair_cost_terms(left, right, cfg.cost, colour_weight))
    # The found disparities' window cost, computed once and only when a check needs it.
    found_cost = functools.cache(
        lambda: _window_cost(terms(), disp, max_disp, cfg.surfaces.window))

    def no_worse(proposed: np.ndarray, tolerance: float) -> np.ndarray:
        """Where ``proposed``'s window cost is at most ``tolerance`` above the match's."""
        cost = _window_cost(terms(), proposed, max_disp, cfg.surfaces.window)
        with np.errstate(invalid="ignore"):
            return cost <= found_cost() + tolerance

    out = disp.copy()
    if take.any():
        take &= no_worse(np.where(take, plane, disp), s.tolerance)
        out[take] = plane[take]
    confidence = confidence.copy()
    across = np.zeros_like(take)
    if s.bridge > 0:
        unsure = was_unsure & ~take
        bridged = _bridges(np.where(sure, disp, np.nan), unsure, s.bridge, s.bridge_agree,
                           s.bridge_edge)
        # Never far behind the pixel's own match: a thin object in front of one surface (an
        # armrest before a chair's back) is no gap in it.
        with np.errstate(invalid="ignore"):
            across = np.isfinite(bridged) & ~(bridged < out - s.bridge_behind)
        if s.bridge_tolerance is not None and across.any():
            across &= no_worse(np.where(across, bridged, out), s.bridge_tolerance)
        out[across] = bridged[across]
        confidence[across] = np.maximum(confidence[across], np.float32(s.bridge_confidence))
    if long_arms is not None:
        # No cost check: these pixels are unsure because their costs tell little.
        left_over = was_unsure & ~take & ~across
        plane, close = _close_planes(disp, sure, long_arms, s, s.min_share, s.inlier,
                                     left_over)
        late = close & left_over
        out[late] = plane[late]
        take |= late
    if s.refit:
        # A pixel's own witness: its match, or its bridge (from the matches above and
        # below), not a plane taken from these same regions, which would agree with itself.
        witness = np.where(across, out, disp)
        filled = sure | take | across
        plane, close = _close_planes(out, filled, arms, s, s.refit_share, s.refit_inlier,
                                     was_unsure)
        settle = was_unsure & close
        with np.errstate(invalid="ignore"):
            # Two witnesses, the pixel's own and its region's plane: where they agree the
            # pixel is more likely right than either alone.
            agree = settle & (np.abs(plane - witness) <= s.refit_agree)
        if long_arms is not None:
            wider, wider_close = _close_planes(out, filled, long_arms, s, s.refit_share,
                                               s.refit_inlier, was_unsure & ~close)
            plane = np.where(close, plane, wider)
            settle |= was_unsure & wider_close
        out[settle] = plane[settle]
        confidence[agree] = np.maximum(confidence[agree], np.float32(s.refit_confidence))
    if s.segments:
        _segment_planes(out, confidence, left, disp, sure, kept, max_disp, s)
    return Spread(np.clip(out, 0, max_disp, out=out), confidence)


def _segment_planes(out: np.ndarray, confidence: np.ndarray, left: np.ndarray,
                    disp: np.ndarray, sure: np.ndarray, kept: np.ndarray, max_disp: int,
                    s: SurfacesConfig) -> None:
    """In place: each blank segment where the match found little sure takes its edge's
    plane (``vsmatch.segments``) where ``out`` lies more than ``s.segment_move`` off it,
    except at the ``kept`` pixels; a pixel so moved keeps a confidence of at most
    ``s.bridge_confidence`` (a guess from the edge, out of the cloud). A plane that leaves
    the range ``0 .. max_disp`` by more than ``s.inlier`` inside its segment is no surface
    seen there: the segment stays as it is."""
    labels, large = blank_segments(left, s.levels, s.segment_delta, s.segment_area,
                                   s.segment_jump)
    for label in large:
        mask = segment_mask(labels, label, out.shape)
        if np.count_nonzero(mask & sure) > s.segment_sure * np.count_nonzero(mask):
            continue  # the match saw this surface: its disparities stand
        plane = edge_plane(disp, sure, mask, s.segment_ring, s.inlier)
        if plane is None or plane.support < s.segment_support:
            continue
        # Within the segment's bounding box only: a camera-size view's full-size maps of
        # coordinates would cost more than the step.
        box = bounding_box(mask)
        values = (np.float32(plane.a) * np.arange(box[1].start, box[1].stop, dtype=np.float32)
                  + np.float32(plane.b) * np.arange(box[0].start, box[0].stop,
                                                    dtype=np.float32)[:, None]
                  + np.float32(plane.c))
        inside = values[mask[box]]
        if inside.min() < -s.inlier or inside.max() > max_disp + s.inlier:
            # Behind infinity or nearer than the range: the edge's sure pixels lie on
            # other surfaces too (delivery_area_1s: the crates before the wall's foot).
            continue
        with np.errstate(invalid="ignore"):
            move = mask[box] & ~kept[box] & ~(np.abs(values - out[box]) <= s.segment_move)
        out[box][move] = values[move]
        np.minimum(confidence[box], np.float32(s.bridge_confidence), out=confidence[box],
                   where=move)


def _close_planes(disp: np.ndarray, kept: np.ndarray, arms: np.ndarray, s: SurfacesConfig,
                  share: float, inlier: float, wanted: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's region's plane through its ``kept`` pixels (``planes.region_planes``),
    and where the region has one and spreads at most ``s.max_spread`` about it: at the
    ``wanted`` pixels (the only ones read; elsewhere NaN and False, or a plane)."""
    plane, spread = region_planes(disp, kept, arms, s.iterations, share, inlier, wanted)
    with np.errstate(invalid="ignore"):
        return plane, np.isfinite(plane) & (spread <= s.max_spread)


def _bridges(sure: np.ndarray, unsure: np.ndarray, span: int, agree: float,
             edge: int = 0) -> np.ndarray:
    """Per ``unsure`` pixel, the line between the nearest sure disparities (``sure``: NaN
    elsewhere) above and below it in its column, where they are at most ``span`` rows
    apart and differ by at most ``agree``; failing that, the same along its row; failing
    that, with ``edge`` > 0, :func:`_bottom_edge_extension` (NaN where none holds)."""
    bridged = _line_bridges(sure, unsure, span, agree, along_rows=False)
    along_rows = _line_bridges(sure, unsure, span, agree, along_rows=True)
    bridged = np.where(np.isfinite(bridged), bridged, along_rows)
    if edge > 0:
        bridged = np.where(np.isfinite(bridged), bridged,
                           _bottom_edge_extension(sure, unsure, edge))
    return bridged


def _line_bridges(sure: np.ndarray, unsure: np.ndarray, span: int, agree: float,
                  along_rows: bool) -> np.ndarray:
    """:func:`_bridges` along the columns only (``along_rows``: the rows only)."""
    out = np.empty(sure.shape, np.float32)
    bridges_along(np.ascontiguousarray(sure, dtype=np.float32), np.ascontiguousarray(unsure),
                  int(span), np.float32(agree), int(along_rows), out)
    return out


#: The column's sure disparities :func:`_bottom_edge_extension` compares: the nearest one
#: above the gap and the one EDGE_LEVEL_ROWS above it, which must differ by at most
#: EDGE_LEVEL_SLOPE px a row (a vertical face; a floor or a table top rises faster).
EDGE_LEVEL_ROWS, EDGE_LEVEL_SLOPE = 16, 0.05


def _bottom_edge_extension(sure: np.ndarray, unsure: np.ndarray, reach: int) -> np.ndarray:
    """Per ``unsure`` pixel with no sure pixel (``sure``: NaN elsewhere) below it in its
    column, down to the view's bottom edge, the disparity of the nearest sure pixel above,
    where that is at most ``reach`` rows above the edge and the column is level there
    (:data:`EDGE_LEVEL_ROWS`, :data:`EDGE_LEVEL_SLOPE`); NaN elsewhere. A face that runs out
    of the view (a shelf's board) has only one side to bridge from."""
    height, width = sure.shape
    known = np.isfinite(sure)
    # The last sure row of each column (-1: none), and the one EDGE_LEVEL_ROWS above it.
    anchor = np.where(known.any(axis=0), height - 1 - np.argmax(known[::-1], axis=0), -1)
    # Whether a sure pixel lies at or below each pixel of its column: up to that row.
    sure_below = np.arange(height)[:, None] <= anchor[None, :]
    columns = np.arange(width)
    bottom = sure[np.maximum(anchor, 0), columns]
    top = sure[np.maximum(anchor - EDGE_LEVEL_ROWS, 0), columns]
    with np.errstate(invalid="ignore"):
        level = (anchor >= EDGE_LEVEL_ROWS) & (
            np.abs(bottom - top) <= EDGE_LEVEL_SLOPE * EDGE_LEVEL_ROWS)
    ends = unsure & ~sure_below & (level & (height - anchor <= reach))[None, :]
    return np.where(ends, bottom[None, :], np.nan).astype(np.float32)


def _levels_at_or_below(grey: np.ndarray) -> np.ndarray:
    """How many of a uint8 view's pixels lie at or below each grey level (256,): its
    percentiles without a sort of the pixels."""
    return np.cumsum(np.bincount(grey.ravel(), minlength=256))


def view_contrast(view: np.ndarray) -> float:
    """The spread of a view's grey levels: its 90th percentile less its 10th."""
    counts = _levels_at_or_below(grey_levels(view))
    low, high = np.searchsorted(counts, [0.1 * counts[-1], 0.9 * counts[-1]])
    return float(high - low)


def in_shadow(view: np.ndarray, levels: int, share: float, window: int) -> np.ndarray:
    """Where ``view`` lies in a shadow: its mean grey level over a box of 1/``window`` of
    the view's width (on the view reduced ``levels`` times) below ``share`` of the view's
    median, or, within the box's reach of such a place, over a cell and its neighbours. A
    view dark all over has no shadow: its median is dark too."""
    grey = grey_levels(view)
    median = max(1.0, _median_level(grey))
    reduced, boxes, side = _box_light(grey, levels, window)
    level = np.float32(share * median)
    dimmed = boxes / level
    # The box reaches half its side into a shadow from the light around it: within that
    # reach of a shadow, a cell dark with its neighbours (3 x 3 cells) is in it too.
    near = cv2.dilate((dimmed < 1.0).astype(np.uint8), np.ones((side, side), np.uint8))
    own = cv2.blur(reduced, (3, 3), borderType=cv2.BORDER_REFLECT) / level
    dimmed = np.where(near > 0, np.minimum(dimmed, own), dimmed)
    # Its share of the level, at most 1, brought to full size: a shadow's edge cells reach
    # half a cell further out than a comparison on the cells would.
    dimmed = np.minimum(dimmed, np.float32(1.0))
    return cv2.resize(dimmed, view.shape[1::-1], interpolation=cv2.INTER_LINEAR) < 1.0


def in_the_dark(view: np.ndarray, levels: int, window: int, level: float) -> np.ndarray:
    """Where ``view``'s mean grey level over a box of 1/``window`` of its width (on the view
    reduced ``levels`` times, as :func:`in_shadow` measures it) is below ``level`` grey
    levels, at full size."""
    _, boxes, _ = _box_light(grey_levels(view), levels, window)
    return cv2.resize(boxes, view.shape[1::-1], interpolation=cv2.INTER_LINEAR) < level


def _box_light(grey: np.ndarray, levels: int, window: int
               ) -> tuple[np.ndarray, np.ndarray, int]:
    """A uint8 view reduced ``levels`` times (float32), its mean grey level over a box of
    1/``window`` of its width about each cell, and the box's side (cells)."""
    reduced = grey.astype(np.float32)
    for _ in range(levels):
        reduced = cv2.pyrDown(reduced)
    side = max(3, reduced.shape[1] // window) | 1
    return reduced, cv2.blur(reduced, (side, side), borderType=cv2.BORDER_REFLECT), side


def _median_level(grey: np.ndarray) -> float:
    """``np.median`` of a uint8 view, from its histogram: the mean of the two middle
    levels of an even count."""
    below = _levels_at_or_below(grey)
    middle = np.searchsorted(below, [(grey.size - 1) // 2 + 1, grey.size // 2 + 1])
    return float(middle.mean())


def _shrunk(value: float, contrast: float, reference: float | None) -> float:
    """``value`` shrunk in proportion to a view's ``contrast`` below ``reference`` (None:
    ``value`` whatever the contrast): a dark view's surfaces differ by fewer grey levels,
    and its right matches' costs separate less, so its confidence reads lower."""
    return value if reference is None else value * min(1.0, contrast / reference)


def _wide_arms(arms: ArmsConfig, s: SurfacesConfig, contrast: float,
               long: bool = False) -> ArmsConfig:
    """The arms config of the wide regions, its lengths in pixels of the reduced view; the
    colour threshold shrinks with a view's ``contrast`` below ``s.contrast``: a dark view's
    surfaces differ by fewer grey levels, and a region would grow across them. ``long``:
    the same threshold along the whole arm (``arms.tau3`` is stricter beyond ``arms.l1``)."""
    l2 = max(2, s.l2 >> s.levels)
    tau = _shrunk(s.tau, contrast, s.contrast)
    return dataclasses.replace(arms, tau1=tau, tau2=tau, l2=l2, l1=min(arms.l1, l2 - 1),
                               tau3=tau if long else arms.tau3, kappa=0.0, shrink=False)


def _window_cost(terms: tuple, disp: np.ndarray, max_disp: int, window: int) -> np.ndarray:
    """The matching cost (census, gradient, colour; ``terms``: the pair's prepared
    ``cost.cost_terms``) of each pixel at its rounded disparity in ``disp``, averaged over
    the ``window`` square around it (over the pixels with a disparity)."""
    n_disp = max_disp + 1
    known = np.isfinite(disp)
    lo = np.clip(np.rint(np.where(known, disp, 0)), 0, max_disp).astype(np.int32)
    bands = Bands(lo, known.astype(np.int32), 1, n_disp)
    volume = banded_volume(terms, bands)
    cost = np.where(known, volume[:, :, 0], 0).astype(np.float32)
    box = (window, window)
    total = cv2.blur(cost, box)
    count = cv2.blur(known.astype(np.float32), box)
    with np.errstate(invalid="ignore", divide="ignore"):
        return total / count
