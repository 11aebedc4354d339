"""The disparity search range found from the pair itself (``--max-disp auto``).

Two estimates of the largest disparity, each robust where the other is weak:

- sparse: SIFT matches between the views (OpenCV), kept when they pass the ratio test,
  lie on the same row (the pair is rectified) and agree with their neighbouring matches;
  their 99.5th percentile. Exposure changes do not fool it, but it misses near objects
  without corners;
- dense: vsmatch itself on the pair reduced to about 200 columns, searching half the
  width, the 99.5th percentile of the pixels that pass the left-right check. It sees
  near surfaces without corners, but can lock onto wrong matches under lighting changes,
  so it may only raise the sparse estimate by :data:`DENSE_MAX_GAIN` at most, and is
  not used alone (a blank pair passes its check at every disparity).

The larger estimate, times :data:`MARGIN_FACTOR` plus :data:`MARGIN_PIXELS`, is the
range's top (rounded up); its bottom is 0, or below 0 by the same margin when the low
percentile of the sparse disparities is negative (verged cameras, cropped views). Views
that are swapped or not rectified are refused (:func:`pair_problem`). The constants were set on
the 24 scenes of
middlebury2, middlebury-third, middlebury2014-quarter and kitti2015 together so that the
range covers every scene's non-occluded ground truth (``python scripts/disparity_range.py``
prints the table).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np

from .images import grey_levels

#: Features are found on the pair reduced to at most this many columns.
FEATURE_WIDTH = 1280
#: When the range is given, the pair is still checked (swapped, unrectified) on features
#: found at most this wide: 0.05-0.07 s on the quarter-size pairs, 0.2-0.27 s at 1280.
CHECK_WIDTH = 400
FEATURE_MIN_ROWS = 8
#: Lowe's ratio test, and the strongest features kept per view.
RATIO = 0.75
MAX_FEATURES = 4000
#: A match is kept when it is this close (pixels, or share) to the median disparity of
#: its 8 nearest matches in the image.
NEIGHBOURS = 8
AGREE_PIXELS, AGREE_SHARE = 2.0, 0.1
SPARSE_PERCENTILE = 99.5
#: The dense check runs at about this many columns.
DENSE_WIDTH = 200
DENSE_PERCENTILE = 99.5
DENSE_MIN_ROWS = 16
DENSE_MIN_VALID = 0.1  # share of pixels passing the left-right check, else ignored
DENSE_MAX_GAIN = 1.5
#: The dense check's bottom comes from its pixels at least this confident, when there
#: are this many (scripts/range_kinds.py: every cropped benchmark scene still covered,
#: and the bottom no further below the truth than the margin puts it).
DENSE_CONFIDENT = 0.5
DENSE_MIN_CONFIDENT = 50
MARGIN_FACTOR = 1.3
MARGIN_PIXELS = 8
#: With fewer consistent matches than this, no range is given.
MIN_MATCHES = 10


#: The views are taken as swapped when at least this share of the consistent matches
#: has a negative disparity. Measured (scripts/range_kinds.py): 0 % on all 24 scenes the
#: developers have, 99.0-100 % with their views swapped; but 97.9 % on Aloe cropped so
#: that half its range is negative (its features sit on the far wall): a thin margin.
SWAPPED_SHARE = 0.985
#: The views' rows are taken to disagree (the pair is not rectified) when the feature
#: matches' median vertical offset exceeds this (pixels). Measured: <= 0.47 on the 24
#: rectified scenes.
ROW_OFFSET_LIMIT = 1.0
#: A low percentile of the disparities; below 0 the range's bottom goes below 0 too.
LOW_PERCENTILE = 0.5


class RangeError(ValueError):
    """No disparity range could be estimated; the message asks for --max-disp."""


class PairGeometryError(RangeError):
    """The views are swapped or not rectified: the method cannot see that itself."""


@dataclass(frozen=True)
class DisparityRange:
    min_disp: int
    max_disp: int
    sparse: float  # the sparse estimate (pixels)
    dense: float | None  # the dense estimate, None when it was not usable
    matches: int  # consistent feature matches

    def describe(self) -> str:
        parts = [f"disparity range {self.min_disp}..{self.max_disp}",
                 f"{self.matches} feature matches, {SPARSE_PERCENTILE:g}th percentile "
                 f"{self.sparse:.1f}"]
        if self.dense is not None:
            parts.append(f"dense check {self.dense:.1f}")
        return "; ".join(parts)


@dataclass(frozen=True)
class FeatureMatches:
    """SIFT matches that pass the ratio test, in full-size pixels: the left point and
    the offset to its right partner, ``dx = x_left - x_right`` and ``dy = y_left -
    y_right``. ``height`` is the views' height; ``factor`` how much they were reduced
    for the features (tolerances scale with it)."""

    x: np.ndarray
    y: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    height: int
    factor: int = 1

    def consistent_disparities(self) -> np.ndarray:
        """Disparities of the matches on the same row that agree with their neighbours."""
        row_tolerance = max(1.5 * self.factor, self.height / 300)
        same_row = np.abs(self.dy) <= row_tolerance
        return _agreeing(self.x[same_row], self.y[same_row], self.dx[same_row], self.factor)


@dataclass(frozen=True)
class SearchRange:
    """The range a pair is searched over, and where it came from: ``given`` (by hand),
    ``calibration`` (its ndisp) or ``found`` (from the pair, ``found`` then holds how)."""

    min_disp: int
    max_disp: int
    source: str
    found: DisparityRange | None = None


def resolve_range(left: np.ndarray, right: np.ndarray, *, min_disp: int | None = None,
                  max_disp: int | None = None, camera=None, rectified_here: bool = False,
                  before_dense_check: Callable[[], None] | None = None) -> SearchRange:
    """The one range policy of every entry point (``run``, ``match``, ``StereoMatcher``,
    ``batch``, ``eval``): a given ``max_disp`` searches ``min_disp`` (default 0) ..
    ``max_disp``; else the calibration's ``ndisp`` (from ``min_disp`` when given, else
    from its own bottom) when it gives a real one; else the range found from the pair,
    from ``min_disp`` when given, and never below what the calibration allows (a
    disparity below ``-doffs`` lies beyond infinity). ``rectified_here``: the views were
    rectified by vsmatch from a raw rig's calibration (a problem is said of that).
    ``before_dense_check`` is called before the range found from the pair runs its match
    (the command line compiles the kernels then). Raises :class:`RangeError` (or
    :class:`PairGeometryError`)."""
    if max_disp is not None:
        return SearchRange(0 if min_disp is None else min_disp, max_disp, "given")
    calibrated = None if camera is None else camera.search_range(left.shape[1])
    if calibrated is not None:
        low = calibrated[0] if min_disp is None else min_disp
        return SearchRange(low, low + calibrated[1] - calibrated[0], "calibration")
    try:
        found = estimate_disparity_range(
            left, right, lowest=None if camera is None else camera.lowest_disparity(),
            before_dense_check=before_dense_check)
    except RangeError as exc:
        if rectified_here:
            raise type(exc)(said_of_rig(str(exc))) from None
        raise
    low = found.min_disp if min_disp is None else min_disp
    return SearchRange(low, max(found.max_disp, low + 1), "found", found)


def said_of_rig(problem: str) -> str:
    """A pair problem as said of views that vsmatch rectified itself (a raw rig's)."""
    return problem.replace(NOT_RECTIFIED, STILL_NOT_RECTIFIED)


def estimate_disparity_range(left: np.ndarray, right: np.ndarray,
                             matches: FeatureMatches | None = None,
                             lowest: int | None = None,
                             before_dense_check: Callable[[], None] | None = None
                             ) -> DisparityRange:
    """The search range for a rectified pair (BGR or grey uint8 views): ``0 .. max``, or
    from a negative bottom when the matches show negative disparities, but never below
    ``lowest`` (a calibration's: the disparity of a point at infinity); ``before_dense_check``
    as :func:`resolve_range` takes it. Raises :class:`PairGeometryError` for swapped or
    unrectified views."""
    width = left.shape[1]
    matches = feature_matches(left, right) if matches is None else matches
    problem = pair_problem(matches)
    if problem is not None:
        raise PairGeometryError(problem)
    disparities = matches.consistent_disparities()
    sparse = (float(np.percentile(disparities, SPARSE_PERCENTILE))
              if disparities.size >= MIN_MATCHES else None)
    if sparse is None:
        # The dense check alone is not trusted: on a blank pair every disparity passes.
        raise RangeError(f"could not estimate the disparity range (only "
                         f"{disparities.size} consistent feature matches); give --max-disp")
    low = float(np.percentile(disparities, LOW_PERCENTILE))
    if before_dense_check is not None:
        before_dense_check()
    dense, dense_low = dense_estimate(left, right, low)
    top = sparse if dense is None else max(sparse, min(dense, DENSE_MAX_GAIN * sparse))
    max_disp = math.ceil(MARGIN_FACTOR * max(top, 0.0) + MARGIN_PIXELS)
    if low < 0 and dense_low is not None:
        # The dense check sees far surfaces without corners; its own search (from twice
        # the sparse bottom) bounds how far it may widen the range.
        low = min(low, dense_low)
    min_disp = 0 if low >= 0 else math.floor(MARGIN_FACTOR * low - MARGIN_PIXELS)
    if lowest is not None:
        min_disp = max(min_disp, min(lowest, 0))
    # The views are cropped by |min_disp| columns for an offset range (pipeline.run).
    max_disp = int(min(max_disp, width - 2 - abs(min_disp) + min_disp))
    return DisparityRange(min_disp, max_disp, sparse, dense, int(disparities.size))


#: What rows that disagree mean for a pair given as rectified.
NOT_RECTIFIED = "the pair is not rectified; rectify it first (--calib with the rig's calibration)"
#: ... and for a raw rig's pair after its rectification.
STILL_NOT_RECTIFIED = ("after rectifying with the rig's calibration: are the views swapped "
                       "(left first), or is the calibration of another rig?")


def pair_problem(matches: FeatureMatches) -> str | None:
    """Why the pair cannot be matched as it is (swapped views, rows that disagree), or
    None. Too few matches to tell: None."""
    if matches.dx.size < MIN_MATCHES:
        return None
    offset = float(np.median(np.abs(matches.dy)))
    if offset > ROW_OFFSET_LIMIT * matches.factor:
        return (f"the views' rows disagree by {offset:.1f} px (median over "
                f"{matches.dy.size} feature matches): {NOT_RECTIFIED}")
    disparities = matches.consistent_disparities()
    if disparities.size >= MIN_MATCHES:
        negative = float(np.mean(disparities < -0.5))
        if negative >= SWAPPED_SHARE:
            return (f"the views look swapped: {100 * negative:.0f} % of {disparities.size} "
                    "feature matches have a negative disparity; give the left view first "
                    "(or --min-disp and --max-disp for a rig whose disparities are all "
                    "negative)")
    return None


def _reduced(image: np.ndarray, factor: int) -> np.ndarray:
    if factor == 1:
        return image
    height, width = image.shape[:2]
    return cv2.resize(image, (width // factor, height // factor),
                      interpolation=cv2.INTER_AREA)


def feature_matches(left: np.ndarray, right: np.ndarray, max_width: int = FEATURE_WIDTH
                    ) -> FeatureMatches:
    """SIFT matches between the views that pass Lowe's ratio test (any row), found on
    the views reduced to at most ``max_width`` columns."""
    factor = max(1, math.ceil(left.shape[1] / max_width))
    points = []
    if left.shape[0] // factor < FEATURE_MIN_ROWS:  # too thin to find features in
        return FeatureMatches(*np.empty((4, 0)), height=left.shape[0], factor=factor)
    grey_l, grey_r = (_reduced(grey_levels(v), factor) for v in (left, right))
    sift = cv2.SIFT_create(nfeatures=MAX_FEATURES, contrastThreshold=0.02)
    keys_l, desc_l = sift.detectAndCompute(grey_l, None)
    keys_r, desc_r = sift.detectAndCompute(grey_r, None)
    if desc_l is not None and desc_r is not None and len(keys_r) >= 2:
        for pair in cv2.BFMatcher(cv2.NORM_L2).knnMatch(desc_l, desc_r, k=2):
            if len(pair) == 2 and pair[0].distance < RATIO * pair[1].distance:
                (xl, yl), (xr, yr) = keys_l[pair[0].queryIdx].pt, keys_r[pair[0].trainIdx].pt
                points.append((xl, yl, xl - xr, yl - yr))
    points = np.array(points, dtype=np.float64).reshape(-1, 4) * factor
    return FeatureMatches(*points.T, height=left.shape[0], factor=factor)


def _agreeing(x: np.ndarray, y: np.ndarray, disp: np.ndarray, factor: int) -> np.ndarray:
    """The disparities that agree with the median of their nearest matches' (a wrong
    match rarely has neighbours that agree with it)."""
    if disp.size <= NEIGHBOURS:
        return np.empty(0)
    points = np.stack([x, y], axis=1).astype(np.float32)
    near = cv2.BFMatcher(cv2.NORM_L2).knnMatch(points, points, k=NEIGHBOURS + 1)
    neighbours = np.array([[m.trainIdx for m in row[1:]] for row in near])
    median = np.median(disp[neighbours], axis=1)
    tolerance = np.maximum(AGREE_PIXELS * factor, AGREE_SHARE * np.abs(median))
    agree = np.abs(disp - median) <= tolerance
    return disp[agree]


def dense_estimate(left: np.ndarray, right: np.ndarray, low: float = 0.0
                   ) -> tuple[float | None, float | None]:
    """The high and low percentiles of a wide, coarse vsmatch run's checked disparities
    (None when the run is not usable). It searches ``0 .. half the width``, from twice
    ``low`` when the sparse matches reach below 0."""
    # Imported here: the range's checks load without the method's kernels.
    from .disparity import VALID
    from .pipeline import run

    factor = max(1, round(left.shape[1] / DENSE_WIDTH))
    if left.shape[0] // factor < DENSE_MIN_ROWS:
        return None, None  # a very wide, thin pair has no rows left at this size
    small_l, small_r = _reduced(left, factor), _reduced(right, factor)
    bottom = min(0, math.floor(2 * low / factor) - MARGIN_PIXELS) if low < 0 else 0
    try:
        result = run(small_l, small_r, min_disp=bottom,
                     max_disp=small_l.shape[1] // 2 + min(bottom, 0))
    except ValueError:  # too small to match at this size
        return None, None
    valid = result.labels == VALID
    if valid.mean() < DENSE_MIN_VALID:
        return None, None
    values = result.disparity[valid]
    # The bottom from confident pixels only: consistent but unsure ones pile up at the
    # search's own bottom (Piano cropped to -15.7..25: -45 from all, -13 from these).
    confident = valid & (result.confidence >= DENSE_CONFIDENT)
    low = (float(np.percentile(result.disparity[confident], LOW_PERCENTILE)) * factor
           if confident.sum() >= DENSE_MIN_CONFIDENT else None)
    return float(np.percentile(values, DENSE_PERCENTILE)) * factor, low


#: The share of a match's pixels within half a pixel of an end of the range searched beyond
#: which the scene very likely reaches past that end. With the datasets' own ranges (36
#: scenes, default) at most 4.0 % lie at the top (PianoL) and 4.0 % at a bottom of 0 (KITTI's
#: sky: the far distance piles there rightly, so a bottom of 0 is never blamed); cones
#: searched to 30 of its ~55 pixels: 19.5 % at the top.
RANGE_END_SHARE = 0.10


def range_end_warning(disparity: np.ndarray, min_disp: int, max_disp: int) -> str | None:
    """A line saying how many pixels pile at an end of ``min_disp .. max_disp`` where more
    than :data:`RANGE_END_SHARE` of those with a disparity do (the bottom only above 0);
    None where none does."""
    finite = np.isfinite(disparity)
    count = int(finite.sum())
    if count == 0:
        return None
    with np.errstate(invalid="ignore"):
        ends = (("top", max_disp, int((disparity > max_disp - 0.5).sum()), "larger --max-disp"),
                ("bottom", min_disp, int((disparity < min_disp + 0.5).sum()) if min_disp > 0
                 else 0, "smaller --min-disp"))
    for end, value, piled, advice in ends:
        if piled > RANGE_END_SHARE * count:
            return (f"{100 * piled / count:.0f} % of the pixels lie at the {end} of the range "
                    f"searched ({value}): the scene likely reaches past it; try a {advice}, "
                    "or give none and let the range be found")
    return None
