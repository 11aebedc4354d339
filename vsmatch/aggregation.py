"""Cost aggregation on cross-shaped support regions with direction-guided arms (§3)."""

from __future__ import annotations

import dataclasses

import numpy as np

from ._kernels.aggregate import (LANES, SUM_BITS, sum_along_arms, sum_over_arms,
                                 sum_over_lanes)
from ._kernels.arms import DOWN, LEFT, RIGHT, UP
from ._kernels.arms import cross_arms as _cross_arms_kernel
from ._kernels.rows import thread_classes
from .bands import Bands, of
from .config import ArmsConfig
from .images import (as_channels, channel_planes, colour_change, downsample, mirrored, to_grey,
                     upsample_nearest)
from .sensitivity import visual_sensitivity


def cross_arms(image: np.ndarray, theta: np.ndarray | None, sensitivity: np.ndarray,
               cfg: ArmsConfig, planes: np.ndarray | None = None) -> np.ndarray:
    """Arm lengths ``(4, H, W)`` uint8 in the order left, right, up, down.

    ``image`` is the colour (or grey) image the colour distances are measured on;
    ``theta`` and ``sensitivity`` are the direction and magnitude of its gradient
    (``theta`` may be None when ``cfg.kappa`` is 0: the arms then ignore it).
    ``planes``: the image's ``channel_planes``, where the caller has them.
    """
    image = as_channels(image)
    if cfg.kappa != 0:
        if theta is None:
            raise ValueError("direction-guided arms (kappa != 0) need the gradient direction")
        strength = np.minimum(1.0, sensitivity / cfg.g_sat).astype(np.float32)
        theta = np.ascontiguousarray(theta, dtype=np.float32)
    else:  # the kernel reads the direction and its strength only where kappa != 0
        theta = strength = np.empty((0, 0), np.float32)
    out = np.empty((4,) + image.shape[:2], dtype=np.uint8)  # l2 <= 255 (config range)
    if planes is None:
        planes = channel_planes(image)
    _cross_arms_kernel(planes, theta, strength,
                       colour_change(image, cfg.tau2, along_rows=True, planes=planes),
                       colour_change(image, cfg.tau2, along_rows=False, planes=planes),
                       float(cfg.tau1), float(cfg.tau3), int(cfg.l1), int(cfg.l2),
                       float(cfg.kappa), bool(cfg.shrink), out)
    return out


def _room(arms: np.ndarray) -> tuple[np.ndarray, ...]:
    """The pixels each arm of ``arms`` (4, H, W) has before the array's edge (at most
    255), in the order left, right, up, down, shaped to broadcast against an arm."""
    height, width = arms.shape[1:]
    room = np.minimum(np.arange(max(height, width)), 255).astype(np.uint8)
    return (room[:width], room[:width][::-1], room[:height, None], room[:height][::-1, None])


def keep_arms_inside(arms: np.ndarray) -> np.ndarray:
    """``arms`` (4, H, W) cut, in place, to the pixels the array has on each side (arms
    made elsewhere, or of a block of rows, may reach past its edge); returned."""
    for side, room in zip((LEFT, RIGHT, UP, DOWN), _room(arms)):
        np.minimum(arms[side], room, out=arms[side])
    return arms


def _check_arms_inside(arms: np.ndarray, view: str) -> None:
    """Refuse arms that reach past the view's edge: the kernels read the running sums and
    the neighbours at the arms' ends unchecked."""
    for side, room in zip((LEFT, RIGHT, UP, DOWN), _room(arms)):
        if np.any(arms[side] > room):
            name = ("left", "right", "up", "down")[side]
            raise ValueError(f"aggregation: the {view} view's {name} arms reach past its "
                             f"edge (cut them with keep_arms_inside)")


#: How the sums over the arms are taken in the full search: "running" sums, the orthogonal
#: integral image (Zhang, Lu, Lafruit 2009: prefix sums along each line, then one
#: difference a cell, whatever the arms' length), or "direct" sums of the arm pixels (work
#: ~ arm length; the reference the tests hold the running sums to). Measured on the 13
#: standard pairs, one aggregation of default's arms: running 0.95 s, direct 6.0 s, and
#: running faster on every pair, the short arms of cones (2.8 px) too (36 against 98 ms).
AGGREGATION_METHODS = ("running", "direct")
#: The region sizes a first pass over lanes starts from: each pixel counts as one.
_ONES = np.ones((1, 1, LANES), np.float32)


def aggregate_cross(volume: np.ndarray, arms_l: np.ndarray, arms_r: np.ndarray,
                    *, iterations: int, scratch: np.ndarray | None = None,
                    method: str = "running", bands: Bands | None = None) -> np.ndarray:
    """Average the cost over each pixel's cross support region, ``iterations`` times.

    The first iteration sums rows then columns, the next columns then rows, and so on.
    At disparity d each arm is the shorter of the left pixel's and the right pixel
    (x - d)'s, and with ``bands`` (the volume's candidates; default the whole range) the
    region at d holds the pixels whose band holds d. ``volume`` is used as a work buffer
    and overwritten, as is ``scratch``, a float32 volume of the same shape, if given.
    ``method``: one of :data:`AGGREGATION_METHODS`; they agree to float32 rounding. Bands
    narrower than the range take direct sums: their arms are a few pixels long
    (``bands.support``), and one pixel's band is not its neighbour's.
    """
    if method not in AGGREGATION_METHODS:
        raise ValueError(f"aggregation method must be one of {AGGREGATION_METHODS}, "
                         f"got {method!r}")
    bands = of(volume, bands)
    narrow = not bands.is_full
    if not narrow and method == "running":
        # The running sums are read at 32-bit offsets: a line of them must fit.
        line = max(volume.shape[:2]) + 1
        if line * volume.shape[2] >= 2 ** 31:
            raise ValueError(f"aggregation: a line of {line - 1} pixels x "
                             f"{volume.shape[2]} candidates is too long for the running "
                             f"sums; use method='direct' or smaller stripes")
    _check_arms_inside(arms_l, "left")
    _check_arms_inside(arms_r, "right")
    current = np.ascontiguousarray(volume, dtype=np.float32)
    # One scratch volume: the first pass of each iteration writes it, the second writes
    # the result back over ``current``, so aggregation holds two volumes at most.
    if scratch is None:
        scratch = np.empty_like(current)
    # No right pixel: no limit; LANES more, read past a band's end.
    arms_r_rev = mirrored(arms_r, pad=bands.n_disp + LANES, fill=255)
    # Narrow bands differ from pixel to pixel: the regions' sizes are counted.
    sizes = np.empty(current.shape if narrow else (0, 0, 0), np.float32)
    none = np.empty((0, 0, 0), np.float32)
    # The running sums' first pass writes each line's largest sum, from which the second
    # takes its fixed-point scale.
    line_max = np.empty(max(current.shape[:2]), np.float32)

    def one_pass(src, along_rows, normalise, out):
        if narrow and current.shape[2] == LANES:
            sum_over_lanes(src, arms_l, arms_r_rev, along_rows, bands.lo, bands.count,
                           none if normalise else sizes, sizes if normalise else _ONES, out)
        elif narrow:
            sum_over_arms(src, arms_l, arms_r_rev, along_rows, normalise, bands.lo,
                          bands.count, none if normalise else sizes,
                          sizes if normalise else none, thread_classes(), out)
        elif method == "direct":
            sum_over_arms(src, arms_l, arms_r_rev, along_rows, normalise, bands.lo,
                          bands.count, none, none, thread_classes(), out)
        else:
            # The first pass's lines cross the second's: as many as a second line's pixels.
            length = src.shape[1] if along_rows else src.shape[0]
            scale = fixed_point_scale(line_max[:length], length) if normalise else 1.0
            sum_along_arms(src, arms_l, arms_r_rev, along_rows, normalise, scale, line_max,
                           out)

    for it in range(iterations):
        rows_first = it % 2 == 0
        one_pass(current, rows_first, False, scratch)
        one_pass(scratch, not rows_first, True, current)
    return current


def fixed_point_scale(line_max: np.ndarray, length: int) -> float:
    """The power of two by which the running sums' second pass multiplies the first pass's
    sums (at most ``line_max.max()`` each) to add them as integers: the largest, at most
    2^32, that keeps a whole line of ``length`` of them below 2^:data:`SUM_BITS`. Integer
    sums are exact whatever the line's length; the bits dropped lie below 2^-25 on the
    pairs here (a sum of up to 41 costs of at most 3 over 2,000 pixels), below float32's
    resolution of such a sum. Refuses a sum that is not a finite number."""
    largest = float(line_max.max(initial=0.0))
    if not np.isfinite(largest):
        raise ValueError("aggregation: the cost volume holds a cost that is not a finite "
                         "number")
    total = max(largest * max(length, 1), 2.0 ** -32)
    exponent = min(32, int(np.floor(SUM_BITS - np.log2(total))))
    if exponent < 0:
        raise ValueError(f"aggregation: costs up to {largest:g} over a line of {length} "
                         "pixels are too large for the running sums; use method='direct'")
    return float(2.0 ** exponent)


def arms_from_below(view: np.ndarray, cfg: ArmsConfig) -> np.ndarray:
    """Cross arms ``(4, H, W)`` of ``view`` at most ``cfg.l2`` long, from the level below:
    grown there with half the lengths, doubled, repeated over each 2 x 2 block and cut at
    the border. The band search's arms are a few pixels long, where this follows the
    colour edges as well as arms grown here (fast: bad 2.0 12.31 against 12.32 on
    Middlebury 2014 quarter, D1 7.37 against 7.43 on KITTI; default on Adirondack 4x: bad
    8.0 7.91 against 7.92) for a quarter of the work."""
    half = dataclasses.replace(cfg, l2=max(1, cfg.l2 // 2), l1=max(1, cfg.l1 // 2))
    return arms_grown_below(view, half, 1)


def arms_grown_below(view: np.ndarray, cfg: ArmsConfig, levels: int) -> np.ndarray:
    """Cross arms ``(4, H, W)`` of ``view`` grown ``levels`` pyramid levels down with
    ``cfg`` (its lengths in pixels of that level), scaled up (at most 255), repeated over
    each block and cut at the border."""
    views = [view]
    for _ in range(levels):
        views.append(downsample(views[-1]))
    small = views[-1]
    grad, theta = visual_sensitivity(to_grey(small), cfg.kappa != 0)
    arms = cross_arms(small, theta, grad, cfg)
    if levels == 1:
        arms = arms * np.uint8(2)  # l2 <= 127 at the level below: no overflow
    else:
        arms = np.minimum(arms.astype(np.int32) << levels, 255).astype(np.uint8)
    for finer in views[-2::-1]:
        arms = upsample_nearest(arms, finer.shape[:2])
    # Scaled, a left or up arm stays inside (2 (c - k) >= 0); a right or down one may
    # pass an odd-sized border by a pixel a level.
    return keep_arms_inside(arms)
