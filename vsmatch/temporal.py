"""Video: each frame searches near what the last one found.

After a frame searched over the whole range, a frame's candidates are bands around the
last frame's disparities (``vsmatch.bands``), moved with the image: the 3 x 3 range of the
last disparities, widened to ``temporal.motion`` pixels around where either view changed;
still pixels whose estimate was sure are not searched again, and keep their value to the
last bit (sub-pixel included); unsure ones are searched around the last full search's
estimate, so that they cannot walk. The whole range is searched again every
``temporal.refresh`` frames, on a cut (the grey-level histogram changed, or much of either
view did, after the image's shift), when the image moved to what the last frame did not
show, after a jump in exposure and when a frame's confidence collapses. Where the image
holds still, the last disparity is held: the new one moves only part of the way
(``temporal.hold``), and a pixel that loses its estimate keeps the last one; where it
changed, the new estimate counts alone, so that a moving object leaves no trail. A changed
pixel of a solid change (an object) is also searched where this frame's own search one
level down puts it (an object moving faster than ``motion`` px a frame;
``temporal.coarse_look``), and counts as changed for ``temporal.settle`` frames more (what
the object uncovers settles).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import cv2
import numpy as np

from . import bands as band_tools
from ._kernels import temporal as _k
from .config import Config, TemporalConfig

#: The window over which a pixel's change between frames is averaged (noise cancels).
CHANGE_WINDOW = 5


@dataclass
class Memory:
    """What a frame leaves the next one, in the views' coordinates as matched from 0."""

    shape: tuple[int, int]
    max_disp: int
    disparity: np.ndarray  # float32, inf where there is no estimate
    confidence: np.ndarray
    grey: np.ndarray  # the left view, float32
    grey_right: np.ndarray  # the right view, float32
    # The last full search's disparities, moved with the image and replaced where it
    # changed: the centre an unsure still pixel is searched around (never its own last
    # value, which would let it walk a pixel a frame).
    anchor: np.ndarray
    curve: dict[str, np.ndarray]  # the cost-curve features of the last full search
    config: Config  # the config of the stream
    correction: object  # photometric.Correction or None
    colour_weight: float  # the colour term's weight after the exposure correction
    noise_sigma: float | None  # the views' noise the last full search measured
    full_confidence: float  # the mean confidence of the last full search
    since_full: int = 0
    # Frames each pixel still counts as moved after an object moved over it (uint8; None:
    # none does): what a moving object uncovers first takes its spilt disparity, and held
    # from then on as still, that would stay behind it as a trail.
    settling: np.ndarray | None = None


class Temporal:
    """The memory a stream of frames carries from one to the next (``StereoMatcher`` and
    ``vsmatch video`` hold one); ``reason`` says why the last frame searched the whole
    range (``None``: it searched bands)."""

    def __init__(self):
        self.reset()

    def reset(self) -> None:
        """Forget the stream: the next frame is matched as a first one."""
        self.memory: Memory | None = None
        self.reason: str | None = None
        self._views: tuple | None = None
        self._new_views = False

    def follow(self, left: np.ndarray, right: np.ndarray, min_disp: int, max_disp: int
               ) -> None:
        """A frame of another size, other channels (grey after colour) or another range
        (``min_disp`` included) starts a new stream: the memory is of other views."""
        views = (left.shape, right.shape, left.dtype.str, right.dtype.str, min_disp, max_disp)
        if self._views is not None and views != self._views:
            self.memory = None
            self._new_views = True
        self._views = views

    def first_reason(self) -> str:
        """Why a frame without memory searches the whole range."""
        reason = "new size, channels or range" if self._new_views else "first frame"
        self._new_views = False
        return reason


@dataclass
class Plan:
    """A frame's search near the last one: the memory moved with the image, where either
    view changed (grown by ``motion``), and each pixel's candidates."""

    memory: Memory
    moved: np.ndarray  # changed (grown), or where an object moved not long ago (settling)
    bands: band_tools.Bands
    # Where an object moved this frame (a solid change, grown back to its block): it counts
    # as moved ``settle`` frames more. None: nowhere.
    object_moved: np.ndarray | None = None
    changed: np.ndarray | None = None  # changed this frame (grown); None: ``moved``
    # Rows (first, stop) of a solid change, which an object moving farther than ``motion``
    # makes: searched where this frame's coarse search puts them too (None: none).
    look: tuple[int, int] | None = None


def plan(memory: Memory, grey: np.ndarray, grey_right: np.ndarray, max_disp: int,
         cfg: TemporalConfig) -> tuple[str | None, Plan | None]:
    """Why this frame searches the whole range (and None), or (None, how it searches near
    the last one)."""
    reason = full_search_reason(memory, grey, grey_right, max_disp, cfg)
    if reason is not None:
        return reason, None
    memory = aligned(memory, grey, grey_right)  # a moving camera's memory moves with it
    left_changed = changed_pixels(memory.grey, grey, cfg)
    right_changed = changed_pixels(memory.grey_right, grey_right, cfg)
    # A view mostly changed is a new scene for that camera (dead, frozen against a moving
    # other, moved on its mount, cut to a look-alike scene): nothing held can be trusted.
    if max(_share(left_changed), _share(right_changed)) > cfg.scene_change:
        return "cut", None
    # A left pixel is still only if what it matched in the right view is still too.
    if right_changed.any():
        left_changed |= seen_from_left(right_changed, memory.disparity)
    changed = grown(left_changed, cfg.motion)
    moved = changed if memory.settling is None else changed | (memory.settling > 0)
    bands = bands_from_previous(memory, moved, cfg)
    unseen = (bands.count == 0) & ~np.isfinite(bands.held)
    if _share(unseen) > cfg.unseen:
        return "new view", None
    solid = solid_change(left_changed, memory.disparity)
    object_moved = grown(solid, SOLID + cfg.motion) & changed
    look = solid_rows(solid, cfg.motion) if cfg.coarse_look else None
    return None, Plan(memory, moved, bands, object_moved, changed, look)


#: A change is solid where a (2 x SOLID + 1) square around the pixel changed too: an object
#: that moved (where it is and where it was); a camera's motion, once aligned, leaves thin
#: edges changed (1.3-1.6 % of the pixels of a sliding clip, none of them solid but what came
#: into view; a square moving over a scene, 0.8-1.0 % solid). 5, not 3: a drone's parallax
#: (EuRoC) makes blocks too, on 35 of 46 frames over 40 % of the rows at 3, 18 over 19 % at 5.
SOLID = 5
#: Rows added above and below a solid change for the coarse look: the arms' context.
LOOK_MARGIN = 8


def looked_curve(curve: dict[str, np.ndarray], looked: dict[str, np.ndarray], first: int,
                 moved: np.ndarray) -> dict[str, np.ndarray]:
    """The last full search's cost-curve features ``curve``, with the coarse look's
    (``looked``: rows ``first ..``) at its moved pixels: their confidence is of what this
    frame shows (a moved pixel over a view gone to noise had the old curve's, and stayed
    sure)."""
    out = dict(curve)  # the features the look has not are shared, not copied
    for name in curve.keys() & looked.keys():
        rows = slice(first, first + looked[name].shape[0])
        out[name] = curve[name].copy()
        out[name][rows] = np.where(moved[rows], looked[name], curve[name][rows])
    return out


def solid_change(changed: np.ndarray, disparity: np.ndarray) -> np.ndarray:
    """The pixels of ``changed`` whose whole (2 x SOLID + 1) square changed. What came into
    view (no last ``disparity``) is no object: the unseen share decides on it."""
    size = 2 * SOLID + 1
    solid = cv2.erode(changed.astype(np.uint8), np.ones((size, size), np.uint8),
                      borderType=cv2.BORDER_CONSTANT, borderValue=0).astype(bool)
    return solid & np.isfinite(disparity)


def solid_rows(solid: np.ndarray, motion: int) -> tuple[int, int] | None:
    """The rows (first, stop) that a ``solid`` change spans, grown by the square, ``motion``
    and :data:`LOOK_MARGIN`; None where there is none."""
    rows = np.flatnonzero(solid.any(axis=1))
    if rows.size == 0:
        return None
    grow = SOLID + motion + LOOK_MARGIN
    return max(int(rows[0]) - grow, 0), min(int(rows[-1]) + 1 + grow, solid.shape[0])


def looked_again(near: Plan, coarse: band_tools.Bands) -> Plan:
    """``near`` with each moved pixel searched where this frame's own coarse search puts it
    (``coarse``: its bands at this size): an object moving faster than ``motion`` leaves the
    last frame's disparities behind. A pixel that changed this frame searches both spans
    where they fit in one band (a coarse level can miss a fine texture), else the coarse
    one; a settling pixel (changed frames ago) the coarse one alone: near its last value it
    holds the object's spilt disparity, which a band spanning both kept as a trail (ETH3D
    electro_1l, `fast`, 8 px a frame: 47 % of where it passed; 11 % so; per frame 3 %)."""
    bands = near.bands
    moved = near.moved & (coarse.count > 0)
    changed = moved if near.changed is None else moved & near.changed
    low = np.minimum(bands.lo, coarse.lo)
    high = np.maximum(bands.lo + bands.count, coarse.lo + coarse.count)
    width = max(bands.width, coarse.width)
    both = changed & (bands.count > 0) & (high - low <= width)
    lo = np.where(both, low, np.where(moved, coarse.lo, bands.lo)).astype(np.int32)
    count = np.where(both, high - low, np.where(moved, coarse.count, bands.count))
    return dataclasses.replace(near, bands=band_tools.Bands(
        lo, count.astype(np.int32), width, bands.n_disp, bands.held))


def _share(mask: np.ndarray) -> float:
    """The share of ``mask`` that holds (a boolean mean without the float copy)."""
    return np.count_nonzero(mask) / mask.size


#: Below this phase-correlation peak the views' shift is not trusted (taken as none).
MIN_RESPONSE = 0.05
#: A shift is taken when it leaves at most this share of the views' mean difference.
SHIFT_GAIN = 0.9


def image_shift(previous: np.ndarray, grey: np.ndarray) -> tuple[int, int]:
    """The whole image's shift (rows, columns) from the last frame to this one, by phase
    correlation of the halved views: what a panning or travelling camera does to every
    pixel at once (0, 0 where the correlation does not say)."""
    a, b = (cv2.resize(v, None, fx=0.5, fy=0.5, interpolation=cv2.INTER_AREA)
            for v in (previous, grey))
    window = cv2.createHanningWindow(a.shape[::-1], cv2.CV_32F)
    (dx, dy), response = cv2.phaseCorrelate(a, b, window)
    guess = int(round(2 * dy)), int(round(2 * dx))
    if not response >= MIN_RESPONSE or guess == (0, 0):
        return 0, 0
    # The halved views' estimate is refined among its whole-pixel neighbours, and kept only
    # when it brings the views closer: on a still view noise alone can tip the estimate
    # over half a pixel, and a memory moved for nothing would drift.
    margin = max(abs(guess[0]), abs(guess[1])) + 1
    height, width = grey.shape
    here = grey[margin:height - margin:2, margin:width - margin:2]

    def difference(shift):
        dy, dx = shift  # this frame's (y, x) shows the last one's (y - dy, x - dx)
        there = previous[margin - dy:height - margin - dy:2, margin - dx:width - margin - dx:2]
        return float(np.abs(here - there).mean())

    candidates = [(guess[0] + i, guess[1] + j) for i in (-1, 0, 1) for j in (-1, 0, 1)]
    best = min(candidates, key=difference)
    return best if difference(best) < SHIFT_GAIN * difference((0, 0)) else (0, 0)


def _moved(image: np.ndarray, dy: int, dx: int, fill) -> np.ndarray:
    """``image`` moved by (dy, dx) pixels; what comes into view holds ``fill``."""
    out = np.full_like(image, fill)
    height, width = image.shape[:2]
    if abs(dy) >= height or abs(dx) >= width:
        return out
    out[max(dy, 0):height + min(dy, 0), max(dx, 0):width + min(dx, 0)] = \
        image[max(-dy, 0):height + min(-dy, 0), max(-dx, 0):width + min(-dx, 0)]
    return out


def aligned(memory: Memory, grey: np.ndarray, grey_right: np.ndarray) -> Memory:
    """The memory moved with the image (:func:`image_shift`; a rigid rig moves both views
    alike), so that each pixel's memory is of the same scene point; what came into view
    has none (and counts as changed)."""
    dy, dx = image_shift(memory.grey, grey)
    if dy == 0 and dx == 0:
        return memory
    return dataclasses.replace(
        memory, disparity=_moved(memory.disparity, dy, dx, np.inf),
        confidence=_moved(memory.confidence, dy, dx, 0.0),
        anchor=_moved(memory.anchor, dy, dx, np.inf),
        settling=None if memory.settling is None else _moved(memory.settling, dy, dx, 0),
        grey=_moved(memory.grey, dy, dx, -1e6),
        grey_right=_moved(memory.grey_right, dy, dx, -1e6),
        curve={name: _moved(values, dy, dx, 0.0) for name, values in memory.curve.items()})


def changed_pixels(previous: np.ndarray, grey: np.ndarray, cfg: TemporalConfig) -> np.ndarray:
    """Where a view changed since the last frame: the mean absolute difference over
    :data:`CHANGE_WINDOW` square windows above ``change`` (noise cancels)."""
    difference = cv2.blur(np.abs(grey - previous), (CHANGE_WINDOW, CHANGE_WINDOW))
    return difference > cfg.change


def grown(mask: np.ndarray, pixels: int) -> np.ndarray:
    """``mask`` grown by ``pixels`` on every side (what moved in, and what it uncovered)."""
    if pixels <= 0 or not mask.any():
        return mask
    size = 2 * pixels + 1
    return cv2.dilate(mask.astype(np.uint8), np.ones((size, size), np.uint8)).astype(bool)


def seen_from_left(right_mask: np.ndarray, disparity: np.ndarray) -> np.ndarray:
    """``right_mask`` (right-view pixels) at each left pixel's match ``x - d`` of
    ``disparity`` (the pixel itself where it has none)."""
    width = right_mask.shape[1]
    columns = np.arange(width, dtype=np.float32)[None, :]
    with np.errstate(invalid="ignore"):
        match = np.where(np.isfinite(disparity), columns - disparity, columns)
    match = np.clip(np.rint(match), 0, width - 1).astype(np.intp)
    return np.take_along_axis(right_mask, match, axis=1)


def full_search_reason(memory: Memory, grey: np.ndarray, grey_right: np.ndarray,
                       max_disp: int, cfg: TemporalConfig) -> str | None:
    """Why this frame searches the whole range whatever its pixels show, or None (views
    of another size or range have no memory: :meth:`Temporal.follow`)."""
    if memory.since_full + 1 >= cfg.refresh:
        return "refresh"
    pairs = ((memory.grey, grey), (memory.grey_right, grey_right))
    if max(histogram_distance(a, b) for a, b in pairs) > cfg.cut:
        return "cut"
    if max(abs(float(b.mean()) - float(a.mean())) for a, b in pairs) > cfg.exposure_jump:
        return "exposure"
    return None


#: Bins of the grey-level histograms compared for a cut.
HISTOGRAM_BINS = 32


def histogram_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Total variation between two views' grey-level histograms (0: the same, 1: apart)."""
    # As whole grey levels (uint8, saturated): OpenCV counts those fast.
    h = [cv2.calcHist([cv2.convertScaleAbs(v)], [0], None, [HISTOGRAM_BINS], [0, 256]).ravel()
         / v.size for v in (a, b)]
    return 0.5 * float(np.abs(h[0] - h[1]).sum())


def bands_from_previous(memory: Memory, moved: np.ndarray, cfg: TemporalConfig
                        ) -> band_tools.Bands:
    """Each pixel's candidates: the last frame's 3 x 3 range widened by ``band``; where the
    image moved, its range over ``motion`` pixels around; none where the image held still
    and the last estimate was sure (the pixel keeps it). An unsure still estimate is
    searched again around the last full search's (the anchor's 3 x 3 range): around its
    own last value it walked a pixel a frame on a still view (29 frames of 200 x 150: bad
    1.0 7.6 -> 10.7), and over the motion window it jumped between frames (KITTI's still
    road D1 9.80, around itself 9.60, per frame 9.44; scripts/video_bench.py). Where the
    band would be wider than ``max_band``, the ``max_band`` centred on the estimate."""
    shape = memory.disparity.shape
    lo, count = np.empty(shape, np.int32), np.empty(shape, np.int32)
    held = np.empty(shape, np.float32)
    n_disp = memory.max_disp + 1
    _k.bands_from_previous(memory.disparity, memory.anchor, memory.confidence,
                           np.ascontiguousarray(moved), np.float32(cfg.unsure), cfg.motion,
                           cfg.band, n_disp, cfg.max_band, lo, count, held)
    return band_tools.Bands(lo, count, int(min(cfg.max_band, n_disp)), n_disp, held)


def hold(near: Plan, new: np.ndarray, cfg: TemporalConfig) -> np.ndarray:
    """The disparity shown: where the image held still, the last estimate moved part of
    the way to the new one (and kept where the new frame has none); elsewhere the new one.
    A still pixel searched again (an unsure one) starts from the last full search's
    estimate, not from its own last value: frame after frame the averages would carry it
    wherever the narrower search leans (the error of a still view rising 0.9 -> 1.4). A
    held pixel's new value is its last one already."""
    memory, moved = near.memory, near.moved
    searched_still = (near.bands.count > 0) & ~moved
    last = np.where(np.isfinite(memory.anchor), memory.anchor, memory.disparity)[searched_still]
    fresh = new[searched_still]
    keep = np.float32(cfg.hold)
    with np.errstate(invalid="ignore"):
        # A new estimate moves part of the way; none keeps the last; none before takes it.
        mixed = np.where(np.isfinite(fresh), last + (1 - keep) * (fresh - last), last)
    out = new.copy()
    out[searched_still] = np.where(np.isfinite(last), mixed, fresh)
    return out


def remember(result, grey: np.ndarray, grey_right: np.ndarray, max_disp: int,
             plan: Plan | None = None, config: Config | None = None) -> Memory:
    """The memory a frame's result (``MatchResult``, matched from 0) leaves the next frame:
    a full search's anew (``plan`` None; ``config`` the stream's), a band search's added
    to the last (its anchor replaced where the image changed)."""
    disparity, confidence = result.disparity.copy(), result.confidence.copy()
    if plan is None:
        curve = {name: values.copy() for name, values in result.curve.items()}
        return Memory(grey.shape, int(max_disp), disparity, confidence, grey, grey_right,
                      disparity.copy(), curve, config, result.photometric,
                      result.colour_weight, result.noise_sigma,
                      float(result.confidence.mean()))
    memory = plan.memory
    anchor = np.where(plan.moved, disparity, memory.anchor)
    left = (np.zeros(plan.moved.shape, np.uint8) if memory.settling is None
            else np.maximum(memory.settling, 1) - 1)
    settling = left if plan.object_moved is None else np.where(
        plan.object_moved, np.uint8(memory.config.temporal.settle), left)
    return dataclasses.replace(memory, disparity=disparity, confidence=confidence, grey=grey,
                               grey_right=grey_right, anchor=anchor,
                               since_full=memory.since_full + 1,
                               settling=settling)
