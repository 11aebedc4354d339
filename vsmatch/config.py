"""Method parameters: frozen dataclasses with defaults, YAML merged over them.

Every number the method uses lives here, grouped by pipeline stage. A YAML file
names only what it changes; unknown keys and out-of-range values are refused
with a one-line :class:`ConfigError` that names the key.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from . import yamlsafe


class ConfigError(ValueError):
    """A configuration that cannot be used; the message is one line."""


def _param(default, lo=None, hi=None, *, choices=None, nullable=False, doc=""):
    """A config field with its allowed range (inclusive) or set of choices, and one line
    saying what it does (docs/configuration.md is made from it)."""
    return field(default=default, metadata={"range": (lo, hi), "choices": choices,
                                            "nullable": nullable, "doc": doc})


@dataclass(frozen=True)
class CostConfig:
    """Matching cost (ALGORITHM.md §1–2)."""

    census_width: int = _param(9, 1, 15, doc="Census window width (odd), pixels.")
    census_height: int = _param(7, 1, 15, doc="Census window height (odd), pixels.")
    census_band: float = _param(0.0, 0.0, 64.0, doc=(
        "A neighbour sets its census bit only when darker than the centre by more than this "
        "(grey levels)."))
    # An edge in the window makes a pixel beside it match the surface across the edge (a
    # wire drawn several times its width); counted over the neighbours like the centre, the
    # census sees the pixel's own surface (docs/results.md, "A chain-link fence").
    census_like: float = _param(0.0, 0.0, 255.0, doc=(
        "Census distance also counted over the neighbours within this many grey levels of "
        "the left pixel in every channel, scaled to the whole window; the smaller of the two "
        "counts (0 is off)."))
    lambda_census: float = _param(30.0, 0.01, 1000.0, doc=(
        "Scale of the census term, 1 − exp(−c / λ): smaller saturates sooner."))
    lambda_gradient: float | None = _param(None, 0.01, 10000.0, nullable=True, doc=(
        "Scale of the gradient (visual sensitivity) term; null switches it off."))
    lambda_ad: float | None = _param(None, 0.01, 1000.0, nullable=True, doc=(
        "Scale of the colour (absolute difference) term; null switches it off."))
    ad_weight: float = _param(1.0, 0.0, 1.0, doc=(
        "Weight of the colour term (the photometric stage lowers it where colours disagree)."))
    presmooth_sigma: float = _param(0.0, 0.0, 5.0, doc=(
        "Gaussian blur of both views before every stage; 0 is off."))


@dataclass(frozen=True)
class NoiseConfig:
    """Adapting to the estimated image noise (``vsmatch.noise``); off unless ``adapt``.

    Nothing changes while the estimated noise sigma (grey levels) stays at or below
    ``floor``; above it, fading in over ``ramp`` grey levels, both views are smoothed and
    thresholds and lambdas grow with the noise (``vsmatch.noise.adapt_to_noise``).
    """

    adapt: bool = _param(False, doc="Adapt to the estimated image noise.")
    floor: float = _param(2.5, 0.0, 50.0, doc=(
        "Noise (grey levels) up to which nothing changes."))
    ramp: float = _param(1.0, 0.01, 50.0, doc=(
        "Grey levels over which the changes fade in above the floor."))
    tau_per_sigma: float = _param(2.0, 0.0, 20.0, doc=(
        "Arm colour thresholds grow by this per grey level of noise."))
    lambda_per_sigma: float = _param(0.0, 0.0, 10.0, doc=(
        "Cost lambdas grow by this share per grey level of noise."))
    smooth_per_sigma: float = _param(0.0, 0.0, 1.0, doc=(
        "Gaussian smoothing of the views per grey level of noise."))
    band_per_sigma: float = _param(0.0, 0.0, 10.0, doc=(
        "Census band grows by this per grey level of noise."))
    #: The longest arm (arms.l2) on noisy views, reached as the other changes fade in;
    #: 0 keeps arms.l2. Noise needs longer arms to average out than clean views do.
    arms_l2: int = _param(0, 0, 255, doc="Longest arm on noisy views (0 keeps arms.l2).")
    #: The sub-pixel fit on noisy views ("same": the config's): the parabola averages the
    #: noise of three costs, the equiangular fit follows the smallest.
    subpixel_fit: str = _param("same", choices=("same", "parabola", "equiangular", "blend"),
                               doc="Sub-pixel fit on noisy views; same keeps subpixel.fit.")
    planes: bool = _param(True, doc="Keep the slanted planes on noisy views.")


@dataclass(frozen=True)
class ArmsConfig:
    """Direction-guided cross arms (ALGORITHM.md §3)."""

    tau1: float = _param(20.0, 0.0, 255.0, doc="Colour threshold of an arm's first l1 pixels.")
    tau2: float = _param(20.0, 0.0, 255.0, doc=(
        "Colour threshold between the arm's pixel and its neighbour."))
    tau3: float = _param(6.0, 0.0, 255.0, doc="Colour threshold beyond l1 pixels.")
    l1: int = _param(17, 1, 255, doc="Arm length up to which tau1 applies, pixels.")
    l2: int = _param(34, 1, 255, doc="Longest arm, pixels.")
    kappa: float = _param(0.0, -1.0, 10.0, doc=(
        "How much the gradient direction steers the arms (0: plain crosses)."))
    g_sat: float = _param(200.0, 1.0, 2000.0, doc=(
        "Gradient magnitude at which the direction steers fully."))
    # The colour threshold falls linearly with the arm's length, tau1 (1 - k / l2), as in
    # the authors' published code.
    shrink: bool = _param(False, doc=(
        "The colour threshold falls linearly with the arm's length, tau1 (1 − k / l2) (the "
        "authors' published code)."))


@dataclass(frozen=True)
class AggregationConfig:
    """Support-region aggregation; 0 iterations switches it off."""

    iterations: int = _param(4, 0, 16, doc=(
        "Passes of cross aggregation (horizontal then vertical); 0 switches it off."))


@dataclass(frozen=True)
class ScanlineConfig:
    """Scanline optimisation over 4 directions between aggregation and WTA (§5.1).

    P1 and P2 are divided by ``reduce_one`` where the colour changes by ``tau`` or more
    in one image, by ``reduce_both`` where it does in both.
    """

    enabled: bool = _param(False, doc=(
        "Scanline optimisation between aggregation and the winner."))
    p1: float = _param(1.0, 0.0, 100.0, doc="Penalty for a disparity change of 1 along a path.")
    p2: float = _param(3.0, 0.0, 100.0, doc="Penalty for a larger change.")
    tau: float = _param(15.0, 0.0, 255.0, doc=(
        "Colour change at which the penalties are reduced."))
    reduce_one: float = _param(4.0, 1.0, 100.0, doc=(
        "Divide P1, P2 by this where the colour changes in one view."))
    reduce_both: float = _param(10.0, 1.0, 100.0, doc=(
        "Divide P1, P2 by this where it changes in both."))
    directions: int = _param(4, choices=(4, 8), doc=(
        "4: rows and columns; 8: the diagonals too."))
    level_p2: float = _param(1.0, 0.05, 1.0, doc=(
        "P2 multiplied by this at each pyramid level below the views' size: a path there "
        "crosses half the pixels of the same scene, and its matching costs half the "
        "evidence, against the same penalty for a jump (0.5 keeps their balance)."))

    def a_level_down(self) -> ScanlineConfig:
        """The section as a level down takes it: P2 times ``level_p2``."""
        if self.level_p2 == 1.0:
            return self
        return dataclasses.replace(self, p2=self.p2 * self.level_p2)


@dataclass(frozen=True)
class ConsistencyConfig:
    """Left-right check."""

    enabled: bool = _param(True, doc="Left–right check.")
    tolerance: int = _param(1, 0, 16, doc=(
        "Largest left–right difference (pixels) still consistent."))


@dataclass(frozen=True)
class VotingConfig:
    """Iterative region voting on the pixels rejected by the left-right check (§5.2)."""

    enabled: bool = _param(False, doc="Region voting on the pixels the check rejected.")
    iterations: int = _param(5, 1, 20, doc="Voting rounds.")
    min_votes: int = _param(20, 0, 10000, doc="Consistent pixels a region needs to vote.")
    min_share: float = _param(0.4, 0.0, 1.0, doc=(
        "Share of the votes the winning disparity needs."))


@dataclass(frozen=True)
class FillConfig:
    """Filling of pixels rejected by the left-right check (ALGORITHM.md §4).

    ``directions`` = 2 searches along the scanline only (§4); 16 is the
    "proper interpolation" of §5.3.
    """

    enabled: bool = _param(True, doc="Fill the pixels still rejected.")
    directions: int = _param(2, choices=(2, 8, 16), doc=(
        "2: along the row; 8 or 16: the paper's proper interpolation."))
    max_search: int = _param(64, 1, 4096, doc=(
        "How far (pixels) to look for a consistent neighbour."))


@dataclass(frozen=True)
class DiscontinuityConfig:
    """Depth-discontinuity adjustment (§5.4): at a jump of more than ``jump`` pixels, take
    the horizontal neighbour's disparity where its cost is lower."""

    enabled: bool = _param(False, doc="Depth-discontinuity adjustment.")
    jump: float = _param(1.0, 0.0, 64.0, doc="Disparity step (pixels) taken as a depth edge.")


@dataclass(frozen=True)
class SubpixelConfig:
    """Sub-pixel parabola fit (§5.5) and the 3x3 median after it."""

    enabled: bool = _param(False, doc="Sub-pixel fit on the aggregated costs.")
    median: bool = _param(False, doc="3×3 median after the fit.")
    fit: str = _param("parabola", choices=("parabola", "equiangular", "blend"), doc=(
        "parabola; equiangular (a symmetric V: census-like costs, less locking to whole "
        "pixels); blend (their mean)."))


@dataclass(frozen=True)
class PlanesConfig:
    """Slanted planes (``vsmatch.planes``): each pixel's support region (a cross with arms
    of at most ``l2`` pixels) gets the least-squares plane through its left-right
    consistent disparities, ``iterations`` times with the pixels within ``inlier`` px of
    the last plane; a rejected pixel takes its plane's value, a kept one too when within
    ``snap`` px of it. Regions with less than ``min_share`` of kept pixels fit none."""

    enabled: bool = _param(False, doc="Slanted planes over depth-aware support regions.")
    l2: int = _param(40, 1, 255, doc=(
        "Longest arm of a plane's region, pixels (on the halved view)."))
    iterations: int = _param(2, 1, 10, doc=(
        "Least-squares fits, each on the pixels within inlier of the last."))
    inlier: float = _param(1.0, 0.0, 100.0, doc=(
        "Distance (pixels) to the plane of the pixels the next fit uses."))
    snap: float = _param(1.0, 0.0, 100.0, doc=(
        "A kept pixel within this (pixels) of its plane takes the plane's value."))
    min_share: float = _param(0.2, 0.0, 1.0, doc=(
        "Share of a region's pixels that must be left–right consistent for a plane."))
    # A region whose kept disparities lie farther than this (standard deviation, px) from
    # their plane is no plane (it spans a depth edge): nothing changes there.
    max_spread: float = _param(100.0, 0.0, 100.0, doc=(
        "A region spread more than this (pixels) about its plane fits none (a depth edge)."))
    # Arms end before a step of more than this many px between neighbours' disparities
    # (0: colour alone decides, as in aggregation).
    jump: float = _param(0.0, 0.0, 100.0, doc=(
        "Arms end before a step larger than this between consistent neighbours (0: colour "
        "alone)."))
    fill: bool = _param(True, doc="Rejected pixels take their plane (else the fill's value).")


@dataclass(frozen=True)
class SurfacesConfig:
    """Planes carried across wide regions (``vsmatch.surfaces``): crosses grown on the left view
    reduced ``levels`` times with the colour threshold ``tau`` (shrunk in a view of less
    ``contrast``; arms of at most ``l2`` full-size pixels) fit planes through their pixels of
    confidence ``fit`` or more; a pixel of confidence below ``take`` takes its region's plane
    where the region spreads at most ``max_spread`` about it and the plane's matching cost over
    a ``window`` square is at most ``tolerance`` above the found disparities'. Then a pixel
    still unsure between two sure pixels at most ``bridge`` apart along its column (then its
    row) whose disparities agree within ``bridge_agree`` takes the line between them, unless
    that is more than ``bridge_behind`` below its own disparity, and where its window cost is at
    most ``bridge_tolerance`` above the match's (when set); one with nothing sure below it down
    to the view's bottom edge, at most ``bridge_edge`` rows away, takes the sure disparity
    above it where its column is level. With ``refit``, the wide regions' planes are then
    fitted again through the sure, taken and bridged pixels (where these are at least
    ``refit_share`` of the region; each fit on those within ``refit_inlier`` of the last), and
    every pixel that was unsure takes its region's plane where the region spreads at most
    ``max_spread`` about it; its confidence is raised to ``refit_confidence`` where the plane
    lies within ``refit_agree`` of its own match or bridge. A pixel whose texture is below
    ``flat`` counts as unsure; one in a ``shadow`` (and not flat) keeps its match, and so does
    one in the dark (light below ``dark_level``) of a view more than ``dark_share`` of which is,
    whose neighbourhood's cost curves have a mean margin of ``dark_margin`` or more. With
    ``long_arms``, what the planes and bridges leave unsure, and what the refit leaves, take
    the plane of longer-armed regions (one threshold ``tau`` along the whole arm). With
    ``segments``, last, a blank segment of the view reduced ``levels`` times (cut where
    neighbours differ by ``segment_delta``, or, with ``segment_jump``, by that, or where their
    step bends by ``segment_delta``; at least ``segment_area`` of it, at most
    ``segment_sure`` of its pixels sure) takes the plane that at least ``segment_support`` of
    the columns of sure pixels within ``segment_ring`` of it fit within ``inlier``, where its
    pixels lie more than ``segment_move`` off it."""

    enabled: bool = _param(False, doc="Planes across wide regions for unsure pixels.")
    levels: int = _param(3, 1, 5, doc="Pyramid levels down where the wide regions grow.")
    l2: int = _param(255, 2, 255, doc="Longest arm of a wide region, full-size pixels.")
    tau: float = _param(30.0, 0.0, 255.0, doc=(
        "Colour difference (grey levels) a wide region's arm crosses."))
    contrast: float | None = _param(None, 1.0, 255.0, nullable=True, doc=(
        "A view's contrast (90th less 10th percentile of its grey levels) below which tau "
        "shrinks in proportion; null: tau whatever the contrast."))
    fit: float = _param(0.5, 0.0, 1.0, doc="Least confidence of the pixels a plane is fitted to.")
    take: float = _param(0.3, 0.0, 1.0, doc="A pixel below this confidence may take its plane.")
    take_contrast: float | None = _param(None, 1.0, 255.0, nullable=True, doc=(
        "A view's contrast below which take shrinks in proportion; null: take whatever "
        "the contrast."))
    shadow: float | None = _param(None, 0.01, 1.0, nullable=True, doc=(
        "A pixel whose neighbourhood's mean grey level (a box of 1/shadow_window of the "
        "view's width, on the view reduced levels times) is below this share of the view's "
        "median lies in a shadow and keeps its own match, unless it is flat: no plane, "
        "bridge, refit or segment replaces it. null: off."))
    shadow_window: int = _param(16, 1, 256, doc=(
        "The view's width over this is the side of the box a shadow's light is measured "
        "over."))
    dark_level: float | None = _param(None, 1.0, 255.0, nullable=True, doc=(
        "A pixel whose neighbourhood's mean grey level (measured as for a shadow) is below "
        "this is in the dark; where more than dark_share of the view is (a dark scene, "
        "whose median is dark too: no shadow), a pixel in the dark whose neighbourhood's "
        "cost curves have a mean margin of dark_margin or more keeps its own match, unless "
        "it is flat (the matchability gate judges margins on one scale for every view, and "
        "reads a dark scene's matched texture as unmatched). null: off."))
    dark_share: float = _param(0.5, 0.0, 1.0, doc=(
        "Share of the view in the dark above which it is a dark scene."))
    dark_margin: float = _param(0.06, 0.0, 1.0, doc=(
        "The mean cost-curve margin (over the matchability gate's window) from which a "
        "pixel in the dark of a dark scene counts as matched."))
    min_share: float = _param(0.05, 0.0, 1.0, doc=(
        "Share of a region's pixels that must be sure for a plane."))
    max_spread: float = _param(1.0, 0.0, 100.0, doc=(
        "A region's sure disparities spread more than this (pixels) about its plane: none."))
    iterations: int = _param(3, 1, 10, doc=(
        "Least-squares fits, each on the sure pixels within inlier of the last."))
    inlier: float = _param(1.0, 0.0, 100.0, doc=(
        "Distance (pixels) to the plane of the pixels the next fit uses."))
    window: int = _param(7, 1, 63, doc=(
        "Square (pixels) the matching cost of the plane and of the match is averaged over."))
    tolerance: float = _param(0.05, 0.0, 3.0, doc=(
        "How much more the plane's mean matching cost may be than the match's."))
    bridge: int = _param(0, 0, 1024, doc=(
        "Longest gap (pixels) along a column or row between two sure pixels that an "
        "unsure pixel between them takes the line of (a shelf's board, a wall); 0: off."))
    bridge_edge: int = _param(0, 0, 1024, doc=(
        "An unsure pixel with no sure pixel below it down to the view's bottom edge, at most "
        "this many rows above the edge, takes the nearest sure disparity above it where "
        "the column is level there (a board running out of the view); 0: off."))
    bridge_agree: float = _param(2.0, 0.0, 100.0, doc=(
        "Most the two ends of a bridge may differ (pixels)."))
    bridge_behind: float = _param(8.0, 0.0, 1024.0, doc=(
        "Most a bridge may put a pixel behind its own match (pixels of disparity): a thin "
        "object in front of a surface is not bridged over."))
    bridge_confidence: float = _param(0.75, 0.0, 1.0, doc=(
        "The confidence a bridged pixel is given at least: the share of bridged pixels "
        "that are right (0.77 over the five datasets)."))
    bridge_tolerance: float | None = _param(None, 0.0, 3.0, nullable=True, doc=(
        "How much more a bridge's mean matching cost may be than the match's; null: no "
        "check."))
    refit: bool = _param(False, doc=(
        "Refit the wide regions' planes through the sure, taken and bridged pixels, and give "
        "every unsure pixel its region's plane."))
    refit_share: float = _param(0.2, 0.0, 1.0, doc=(
        "Share of a region's pixels that must be sure, taken or bridged for a refitted plane."))
    refit_inlier: float = _param(2.0, 0.0, 100.0, doc=(
        "Distance (pixels) to the refitted plane of the pixels the next refit uses."))
    refit_agree: float = _param(1.0, 0.0, 100.0, doc=(
        "A pixel given its refitted plane within this (pixels) of its own match (or its "
        "bridge) is raised to refit_confidence."))
    refit_confidence: float = _param(0.0, 0.0, 1.0, doc=(
        "The confidence a pixel whose refitted plane agrees with its disparity is given at "
        "least (0: unchanged)."))
    flat: float | None = _param(None, 0.0, 255.0, nullable=True, doc=(
        "A pixel whose texture (|gx| + |gy| of the Sobel over 5 x 5; 8 for one grey level "
        "a pixel) is below this counts as unsure, whatever its confidence: with nothing to "
        "see, its match is the colour term's guess. null: off."))
    long_arms: bool = _param(False, doc=(
        "For the unsure pixels no plane, bridge or refit filled: the planes of regions whose "
        "arms keep tau along their whole length (not the stricter arms.tau3 beyond arms.l1)."))
    segments: bool = _param(False, doc=(
        "Last, a large blank segment of the view, with few sure pixels inside, takes the "
        "plane the sure pixels along its edge agree on (vsmatch.segments)."))
    segment_delta: float = _param(3.0, 0.0, 255.0, doc=(
        "Grey levels between neighbours of the view reduced levels times that cut segments "
        "(with segment_jump: a change of that many between one pair's step and the next's)."))
    segment_jump: float | None = _param(None, 0.0, 255.0, nullable=True, doc=(
        "Grey levels between neighbours that always cut; below it a smooth shading does not "
        "(null: segment_delta between neighbours cuts)."))
    segment_area: float = _param(0.02, 0.0, 1.0, doc="Least share of the view a segment covers.")
    segment_ring: int = _param(16, 1, 1024, doc=(
        "How far (pixels) outside a segment its edge's sure pixels are taken from."))
    segment_support: float = _param(0.3, 0.0, 1.0, doc=(
        "Least share of the edge's columns (each weighing the same) the plane fits within "
        "inlier."))
    segment_sure: float = _param(0.05, 0.0, 1.0, doc=(
        "Most share of a segment's pixels that may be sure: where the match found more "
        "inside, its own disparities stand."))
    segment_move: float = _param(2.0, 0.0, 1024.0, doc=(
        "A segment's pixel takes the plane where it lies more than this (pixels) off it."))


@dataclass(frozen=True)
class BandsConfig:
    """The band search above the coarsest level (``vsmatch.pyramid``): each pixel searches
    the coarse estimate's 3 x 3 range widened by ``band`` (at most ``max_band``
    candidates), with arms of at most ``support`` pixels and, with ``scanline``, the
    scanline optimisation (the ``scanline`` section's values)."""

    scanline: bool = _param(False, doc=(
        "Scanline optimisation at the finer levels (when the scanline stage is on)."))
    band: int = _param(0, 0, 64, doc="Pixels added on each side of a band.")
    support: int = _param(8, 1, 255, doc="Longest arm at the finer levels, pixels.")
    aggregation: bool = _param(True, doc=(
        "Cross-region aggregation at the finer levels (when the aggregation stage is on); "
        "without it the scanline optimisation alone smooths the bands' costs."))
    max_band: int = _param(8, 3, 4096, doc=(
        "Most candidates a pixel keeps at a finer level; a wider 3 × 3 range is cut to "
        "this many around the pixel's own estimate."))
    guide: float | None = _param(None, 0.0, 255.0, nullable=True, doc=(
        "Where the 3 × 3 range is cut: around the estimate of the coarse neighbour whose grey "
        "level is nearest the pixel's, the pixel's own unless another is nearer by more than "
        "this (grey levels); null: always its own."))
    census_width: int | None = _param(None, 1, 15, nullable=True, doc=(
        "Census window width (odd) at the finer levels; null: cost.census_width."))
    census_height: int | None = _param(None, 1, 15, nullable=True, doc=(
        "Census window height (odd) at the finer levels; null: cost.census_height."))

    def cost_at_bands(self, cost: CostConfig) -> CostConfig:
        """The ``cost`` section as the finer levels take it: their census window."""
        width = cost.census_width if self.census_width is None else self.census_width
        height = cost.census_height if self.census_height is None else self.census_height
        if (width, height) == (cost.census_width, cost.census_height):
            return cost
        return dataclasses.replace(cost, census_width=width, census_height=height)


@dataclass(frozen=True)
class PyramidConfig:
    """When to search coarse-to-fine (``vsmatch.pyramid``; scheduling): halve the views
    while a row holds more than ``max_row_cells`` width x disparity cells, or the pair more
    than ``max_cells`` width x height x disparity cells (0: no such limit); the finer
    levels search bands (the ``bands`` section)."""

    max_row_cells: int = _param(262144, 1024, 1 << 40, doc=(
        "Halve the views while a row holds more width × disparity cells."))
    max_cells: int = _param(0, 0, 1 << 50, doc=(
        "Halve at least once above this many width × height × disparity cells (0: no "
        "limit)."))
    # Halve at least this many times, whatever the row (while 64 columns and 16
    # disparities remain): the ``fast`` config's coarse-to-fine at every size.
    min_levels: int = _param(0, 0, 4, doc="Halve at least this often, whatever the size.")


@dataclass(frozen=True)
class EdgesConfig:
    """Depth edges decided again by adaptive support weights (``vsmatch.edges``): a pixel
    near a step back along its row takes the disparity behind the step where a window
    weighted by colour likeness to it explains the views better."""

    enabled: bool = _param(False, doc=(
        "Weigh each pixel near a depth step against the surface behind the step."))
    radius: int = _param(8, 1, 32, doc="Half the window's side, pixels.")
    colour_scale: float = _param(5.0, 0.1, 255.0, doc=(
        "A window pixel weighs exp(-colour difference from the centre / this), grey levels."))
    distance_scale: float = _param(100.0, 0.1, 10000.0, doc=(
        "... and exp(-city-block distance / this), pixels."))
    gradient_share: float = _param(0.9, 0.0, 1.0, doc=(
        "Share of the x-gradient difference in the cost (the rest: the colour difference)."))
    colour_cap: float = _param(10.0, 0.0, 255.0, doc="Colour difference truncated here.")
    gradient_cap: float = _param(2.0, 0.0, 255.0, doc="Gradient difference truncated here.")
    reach: int = _param(4, 1, 64, doc="Pixels along the row a step is looked for.")
    jump: float = _param(2.0, 0.0, 1000.0, doc=(
        "A step: a disparity this many pixels behind the pixel's own."))
    margin: float = _param(0.1, 0.0, 10.0, doc=(
        "The surface behind must cost less than the pixel's own by this share."))
    min_texture: float = _param(4.0, 0.0, 10000.0, doc=(
        "Pixels whose texture (Sobel |gx| + |gy| over 5 x 5, 8 a grey level a pixel) is "
        "below this are left as they are."))
    moved_confidence: float = _param(0.5, 0.0, 1.0, doc=(
        "A moved pixel's confidence is at most this."))


@dataclass(frozen=True)
class PhotometricConfig:
    """Exposure and lighting differences (``vsmatch.photometric``): a quick first match on
    the views halved until at most ``max_width`` pixels wide (census and gradient costs
    averaged over ``box`` x ``box`` windows, left-right checked) gives the pixels the right
    view's colour map is learnt from; the colour term's weight falls from 1 to 0 as the
    colour difference the map leaves beyond the noise grows from ``fade_from`` to
    ``fade_to`` grey levels."""

    enabled: bool = _param(False, doc="Learn the right view's colour map onto the left's.")
    max_width: int = _param(400, 32, 100000, doc=(
        "Width (pixels) of the quick first match the map is learnt from."))
    box: int = _param(9, 1, 63, doc="Window of the first match's costs, pixels.")
    fade_from: float = _param(5.0, 0.0, 255.0, doc=(
        "Colour residual (grey levels) where the colour term starts to fade."))
    fade_to: float = _param(10.0, 0.0, 255.0, doc="Residual where it is gone.")
    # What the map leaves, spread smoothly (a Gaussian of this many widths) and added to
    # the right view: vignetting and colour responses that differ across the image. 0: off.
    field_sigma: float = _param(0.0, 0.0, 1.0, doc=(
        "What the map leaves, smoothed over this share of the width and added to the right "
        "view (vignetting); 0 is off."))


@dataclass(frozen=True)
class MemoryConfig:
    """Working memory of the full search: with more than ``max_mb`` megabytes of cost
    volumes and per-pixel arrays, it runs on horizontal stripes that fit, each with
    ``overlap`` extra rows above and below whose results are dropped."""

    max_mb: int = _param(1024, 16, 1 << 20, doc=(
        "Working-memory budget of the full search, MB (--max-memory); stripes above it."))
    overlap: int = _param(48, 0, 4096, doc="Extra rows above and below each stripe.")
    max_megapixels: float = _param(200.0, 0.01, 10000.0, doc=(
        "Views larger than this are refused from their header."))


@dataclass(frozen=True)
class TemporalConfig:
    """Video (``vsmatch.temporal``): after a frame searched over the whole range, each
    frame searches bands around the last one's disparities; a full search again every
    ``refresh`` frames, on a cut and after a jump in exposure. Where the image holds still,
    the last disparity is held (an average weighted by ``hold``)."""

    refresh: int = _param(30, 1, 100000, doc="Search the whole range again every this many frames.")
    change: float = _param(4.0, 0.0, 255.0, doc=(
        "A pixel has changed when its 5 × 5 mean absolute difference from the last frame "
        "exceeds this (grey levels)."))
    motion: int = _param(4, 0, 64, doc=(
        "Pixels a changed region may have moved: its band holds the last disparities this "
        "far around."))
    band: int = _param(1, 0, 64, doc="Disparities added on each side of a band.")
    unsure: float = _param(0.3, 0.0, 1.0, doc=(
        "Below this confidence the last estimate counts as unsure: searched again (around "
        "itself) even where the image held still."))
    max_band: int = _param(12, 3, 4096, doc="Most candidates a pixel keeps.")
    hold: float = _param(0.8, 0.0, 1.0, doc=(
        "Where the image holds still, the share of the last disparity kept (0: none)."))
    exposure_jump: float = _param(10.0, 0.0, 255.0, doc=(
        "A change of the mean grey level (grey levels) that starts a full search."))
    cut: float = _param(0.2, 0.0, 1.0, doc=(
        "A cut (a full search): the grey-level histograms of two frames this far apart "
        "(total variation, 0 to 1; a camera that moves keeps its histogram)."))
    scene_change: float = _param(0.3, 0.0, 1.0, doc=(
        "A cut too: more than this share of either view changed since the last frame, "
        "after the image's shift (a camera that died, moved against the other, or a scene "
        "of the same grey levels)."))
    unseen: float = _param(0.01, 0.0, 1.0, doc=(
        "A full search when more than this share of the pixels has no last estimate near "
        "enough to search around (a pan into what the last frame did not show)."))
    planes: bool = _param(False, doc=(
        "Fit slanted planes on frames searched near the last one too (the held pixels "
        "keep the last full search's)."))
    scanline: bool = _param(True, doc=(
        "The scanline optimisation over a frame's bands (where the config's bands have it)."))
    aggregation: bool = _param(True, doc=(
        "Cross aggregation over a frame's bands (where the config's bands have it)."))
    collapse: float = _param(0.7, 0.0, 1.0, doc=(
        "A full search again when a frame's mean confidence falls below this share of the "
        "last full search's."))
    settle: int = _param(4, 0, 255, doc=(
        "Frames the pixels an object moved over (a block of change) are still searched as "
        "moved: what it uncovers first takes its spilt disparity, which held would stay "
        "behind it as a trail."))
    coarse_look: bool = _param(True, doc=(
        "The rows of a block of change (an object) also searched over the whole range one "
        "pyramid level down, and their moved pixels where that puts them (an object moving "
        "faster than motion px a frame); off: only near the last frame's disparities."))


@dataclass(frozen=True)
class CloudConfig:
    """What ``--depth`` and ``--cloud`` keep unless told otherwise (``--min-confidence``):
    the confidence at which a pixel is likely right, measured per config
    (``scripts/cloud_threshold.py``)."""

    min_confidence: float = _param(0.88, 0.0, 1.0, doc=(
        "Pixels below this confidence are left out of the depth map and the point cloud."))


@dataclass(frozen=True)
class Config:
    """All parameters of the method, one section per pipeline stage."""

    cost: CostConfig = field(default_factory=CostConfig)
    noise: NoiseConfig = field(default_factory=NoiseConfig)
    arms: ArmsConfig = field(default_factory=ArmsConfig)
    aggregation: AggregationConfig = field(default_factory=AggregationConfig)
    scanline: ScanlineConfig = field(default_factory=ScanlineConfig)
    consistency: ConsistencyConfig = field(default_factory=ConsistencyConfig)
    voting: VotingConfig = field(default_factory=VotingConfig)
    fill: FillConfig = field(default_factory=FillConfig)
    discontinuity: DiscontinuityConfig = field(default_factory=DiscontinuityConfig)
    subpixel: SubpixelConfig = field(default_factory=SubpixelConfig)
    planes: PlanesConfig = field(default_factory=PlanesConfig)
    surfaces: SurfacesConfig = field(default_factory=SurfacesConfig)
    edges: EdgesConfig = field(default_factory=EdgesConfig)
    photometric: PhotometricConfig = field(default_factory=PhotometricConfig)
    bands: BandsConfig = field(default_factory=BandsConfig)
    temporal: TemporalConfig = field(default_factory=TemporalConfig)
    cloud: CloudConfig = field(default_factory=CloudConfig)
    # Scheduling, not the method: how the work is laid out (levels, stripes). In a file
    # these sit under ``schedule:``.
    pyramid: PyramidConfig = field(default_factory=PyramidConfig)
    memory: MemoryConfig = field(default_factory=MemoryConfig)

    def a_level_down(self) -> Config:
        """The config a pyramid level down searches with (the scanline's P2 scaled by
        ``scanline.level_p2``); itself where nothing changes."""
        scanline = self.scanline.a_level_down()
        return self if scanline is self.scanline else dataclasses.replace(self,
                                                                          scanline=scanline)

    def to_dict(self) -> dict[str, dict[str, Any]]:
        """Every section's values, by section name."""
        return dataclasses.asdict(self)

    def to_file_dict(self) -> dict[str, Any]:
        """The values as a config file holds them: the method's sections, then
        ``schedule`` with the scheduling ones."""
        values = self.to_dict()
        schedule = {name: values.pop(name) for name in SCHEDULE_SECTIONS}
        return {**values, "schedule": schedule}


_SECTIONS = {f.name: f.default_factory for f in dataclasses.fields(Config)}
#: The sections that lay the work out rather than define the method: under ``schedule:``
#: in a file (at the top level, as before, still read).
SCHEDULE_SECTIONS = ("pyramid", "memory")
#: Keys that moved, still read where they were: the band search's options were pyramid's.
MOVED_KEYS = {("pyramid", key): ("bands", key)
              for key in ("scanline", "band", "support", "max_band")}


#: A config file larger than this is refused unread: the bundled ones are under 4 kB, and
#: a config names at most ~70 values.
MAX_CONFIG_BYTES = 64 * 1024
#: Values are quoted in messages up to this many characters (a YAML alias can make a
#: 300-byte value print as gigabytes).
MAX_QUOTED = 40


def quote(value: Any) -> str:
    """A short, size-limited ``repr`` of a value for a one-line message."""
    if isinstance(value, (dict, list, tuple)):
        return f"a {type(value).__name__}"  # never walked: it may be an alias bomb
    text = repr(value)
    return text if len(text) <= MAX_QUOTED else text[:MAX_QUOTED - 3] + "..."


def _check_value(key: str, spec: dataclasses.Field, value: Any) -> Any:
    meta = spec.metadata
    kind = _field_kind(spec)
    if value is None:
        if meta.get("nullable"):
            return None
        raise ConfigError(f"config value {key} must not be empty")
    if kind is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"config value {key} = {quote(value)} must be true or false")
        return value
    if kind is str:
        if value not in meta["choices"]:
            raise ConfigError(f"config value {key} = {quote(value)} is not one of "
                              f"{', '.join(meta['choices'])}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"config value {key} = {quote(value)} must be a number")
    lo, hi = meta.get("range", (None, None))
    if isinstance(value, int) and (kind is int or abs(value) > 1e300):
        # Whole already: a huge one is out of range, not "not a whole number".
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            raise ConfigError(f"config value {key} = {quote(value)} is out of range "
                              f"[{lo}, {hi}]")
    elif not math.isfinite(value):
        raise ConfigError(f"config value {key} = {quote(value)} must be a finite number")
    elif kind is int:
        if value != int(value):
            raise ConfigError(f"config value {key} = {quote(value)} must be a whole number")
        value = int(value)
    else:
        value = float(value)
    choices = meta.get("choices")
    if choices is not None and value not in choices:
        allowed = ", ".join(str(c) for c in choices)
        raise ConfigError(f"config value {key} = {quote(value)} is not one of {allowed}")
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        raise ConfigError(f"config value {key} = {quote(value)} is out of range [{lo}, {hi}]")
    return value


def _field_kind(spec: dataclasses.Field) -> type:
    text = str(spec.type)
    for kind in (bool, int, float, str):
        if text.startswith(kind.__name__):
            return kind
    raise TypeError(f"unsupported config field type {text}")


def _check_cross_constraints(cfg: Config) -> None:
    if cfg.photometric.fade_to <= cfg.photometric.fade_from:
        raise ConfigError(f"config values photometric.fade_from = {cfg.photometric.fade_from} "
                          f"and fade_to = {cfg.photometric.fade_to} must satisfy "
                          "fade_from < fade_to")
    if cfg.arms.l1 >= cfg.arms.l2:
        raise ConfigError(f"config values arms.l1 = {cfg.arms.l1} and arms.l2 = {cfg.arms.l2} "
                          "must satisfy l1 < l2")
    if 0 < cfg.noise.arms_l2 <= cfg.arms.l1:
        raise ConfigError(f"config value noise.arms_l2 = {cfg.noise.arms_l2} must be 0 or more "
                          f"than arms.l1 = {cfg.arms.l1}")
    for section, c in (("cost", cfg.cost), ("bands", cfg.bands.cost_at_bands(cfg.cost))):
        if c.census_width % 2 == 0 or c.census_height % 2 == 0:
            raise ConfigError(f"config values {section}.census_width and "
                              f"{section}.census_height must be odd")
        if c.census_width * c.census_height - 1 > 64:
            raise ConfigError(f"config values {section}.census_width x {section}.census_height "
                              "must give at most 64 neighbours (one uint64 per pixel)")


def config_from_dict(data: dict[str, Any] | None, base: Config | None = None) -> Config:
    """Merge a nested mapping over ``base`` (the defaults), checking every key and value."""
    base = base or Config()
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError("config must be a mapping of sections (cost, arms, ...)")
    data = _moved_keys_read(_schedule_lifted(data))
    sections = {}
    for name, value in data.items():
        if name not in _SECTIONS:
            allowed = ", ".join(_SECTIONS)
            raise ConfigError(f"unknown config key {quote(name)} (allowed sections: {allowed})")
        if value is None:
            continue
        if not isinstance(value, dict):
            raise ConfigError(f"config section '{name}' must be a mapping")
        current = getattr(base, name)
        fields = {f.name: f for f in dataclasses.fields(current)}
        changes = {}
        for key, item in value.items():
            if key not in fields:
                allowed = ", ".join(fields)
                raise ConfigError(f"unknown config key {quote(f'{name}.{key}')} "
                                  f"(allowed: {allowed})")
            changes[key] = _check_value(f"{name}.{key}", fields[key], item)
        sections[name] = dataclasses.replace(current, **changes)
    cfg = dataclasses.replace(base, **sections)
    _check_cross_constraints(cfg)
    return cfg


def _schedule_lifted(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` with the sections under ``schedule`` at the top level beside the rest."""
    if "schedule" not in data:
        return data
    data = dict(data)
    schedule = data.pop("schedule")
    if schedule is None:
        return data
    if not isinstance(schedule, dict):
        raise ConfigError("config section 'schedule' must be a mapping")
    for name, value in schedule.items():
        if name not in SCHEDULE_SECTIONS:
            raise ConfigError(f"unknown config key {quote(f'schedule.{name}')} (allowed: "
                              f"{', '.join(SCHEDULE_SECTIONS)})")
        if name in data:
            raise ConfigError(f"config section '{name}' is given twice: at the top and under "
                              "schedule")
        data[name] = value
    return data


def _moved_keys_read(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` with keys that moved (:data:`MOVED_KEYS`) taken to their new sections."""
    data = dict(data)
    for (old_section, key), (section, new_key) in MOVED_KEYS.items():
        values = data.get(old_section)
        if not isinstance(values, dict) or key not in values:
            continue
        target = data.get(section) or {}
        if not isinstance(target, dict):
            continue  # refused below as any section that is not a mapping
        if new_key in target:
            raise ConfigError(f"config value {old_section}.{key} is given twice: also as "
                              f"{section}.{new_key}")
        data[old_section] = {k: v for k, v in values.items() if k != key}
        data[section] = {**target, new_key: values[key]}
    return data


def bundled_config_names() -> list[str]:
    """Names of the configs shipped with the package (``paper``, ``census``, ...)."""
    folder = resources.files(__package__) / "configs"
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".yaml"))


DEFAULT_CONFIG_NAME = "default"


def load_config(name_or_path: str | Path | Config | Mapping | None = None) -> Config:
    """Load a bundled config by name (``paper``), or a YAML file by path, or take a mapping
    laid out as a config file is (``{"base": "fast", "arms": {"l1": 20}}``).

    ``None`` gives the bundled ``default`` config.
    """
    if isinstance(name_or_path, Config):
        return name_or_path
    if isinstance(name_or_path, Mapping):
        return _config_from_data(dict(name_or_path), "the config mapping")
    if name_or_path is None:
        name_or_path = DEFAULT_CONFIG_NAME
    if str(name_or_path) in bundled_config_names():
        return _bundled_config(str(name_or_path))
    return _parse_config(str(name_or_path))


def with_changes(name_or_path: str | Path | Config | None, changes: list[str]) -> Config:
    """The config :func:`load_config` gives, with each ``section.key=value`` of ``changes``
    applied (the value read as YAML: ``null``, ``true``, ``4``), as scripts that try a
    value take it: ``with_changes("accurate", ["surfaces.bridge=128"])``."""
    values = load_config(name_or_path).to_dict()
    for change in changes:
        key, value = change.split("=", 1)
        section, last = key.rsplit(".", 1)
        node = values
        for part in section.split("."):
            node = node[part]
        node[last] = yaml.safe_load(value)
    return config_from_dict(values)


@functools.lru_cache(maxsize=None)
def _bundled_config(name: str) -> Config:
    """A bundled config, parsed once per process (parsing took ~6 ms per match() call)."""
    return _parse_config(name)


def _parse_config(name_or_path: str) -> Config:
    text, origin = _read_config_text(str(name_or_path))
    if len(text.encode("utf-8")) > MAX_CONFIG_BYTES:
        raise ConfigError(f"config {origin} is larger than {MAX_CONFIG_BYTES // 1024} kB; "
                          "no real config is")
    try:
        data = yamlsafe.load(text)
    except RecursionError:
        raise ConfigError(f"config {origin} is nested too deeply") from None
    except yamlsafe.DuplicateKeyError as exc:
        raise ConfigError(f"config {origin}: {exc.problem}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise ConfigError(f"config {origin} is not valid YAML{where}") from None
    return _config_from_data(data, origin)


def _config_from_data(data: Any, origin: str) -> Config:
    """A config's parsed YAML (or a mapping given in Python) over the built-in values, or
    over the bundled config its ``base`` names; errors name ``origin``."""
    base = None
    if isinstance(data, dict) and "base" in data:
        # `base: default` merges the file over a bundled config instead of the built-in values.
        data = dict(data)
        name = data.pop("base")
        if not isinstance(name, str) or name not in bundled_config_names():
            names = ", ".join(bundled_config_names())
            raise ConfigError(f"{origin}: base must name a bundled config ({names}), not "
                              f"{quote(name)}")
        base = _bundled_config(name)
    try:
        return config_from_dict(data, base=base)
    except ConfigError as exc:
        raise ConfigError(f"{origin}: {exc}") from None


def _read_config_text(name_or_path: str) -> tuple[str, str]:
    if name_or_path in bundled_config_names():
        res = resources.files(__package__) / "configs" / f"{name_or_path}.yaml"
        return res.read_text(encoding="utf-8"), f"'{name_or_path}'"
    path = Path(name_or_path)
    if not path.is_file():
        names = ", ".join(bundled_config_names())
        raise ConfigError(f"config '{name_or_path}' is neither a bundled config ({names}) "
                          "nor an existing file")
    try:
        return path.read_text(encoding="utf-8"), str(path)
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"cannot read config {path}: {exc}") from None
