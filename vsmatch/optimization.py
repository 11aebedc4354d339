"""Scanline optimisation between aggregation and winner-takes-all (ALGORITHM.md §5.1)."""

from __future__ import annotations

import numpy as np

from ._kernels.scanline import LANES, scanline_columns, scanline_diagonal_pass, scanline_rows
from .bands import Bands, of
from .config import ScanlineConfig
from .images import as_channels, channel_planes, colour_change, mirrored

#: Columns walked side by side in the column passes (``_kernels.scanline.scanline_columns``);
#: the result does not depend on it.
COLUMN_CHUNK = 8


def scanline_optimise(volume: np.ndarray, left: np.ndarray, right: np.ndarray,
                      cfg: ScanlineConfig, out: np.ndarray | None = None,
                      bands: Bands | None = None,
                      planes: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """The mean of the directional path costs, (H, W, B): left, right, up, down, and with
    ``directions: 8`` the four diagonals, over the candidates of ``bands`` (the volume's;
    default the whole range), a candidate outside the previous pixel's band being
    infinitely costly there.

    P1 and P2 are divided by ``reduce_one`` where the colour changes by ``tau`` or more
    between a pixel and the previous one on the path in one image (left pixel, or its
    match at d in the right image), by ``reduce_both`` where it does in both.
    ``out``, if given, is a work volume of the same shape to write the result into;
    ``planes``: both views' ``channel_planes``, where the caller has them.
    """
    if out is None:
        out = np.empty_like(volume)  # the first pass writes every cell of the bands
    bands = of(volume, bands)
    lo, count, n_disp = bands.lo, bands.count, bands.n_disp
    banded = not bands.is_full
    p1s, p2s = penalties(cfg)
    weight = np.float32(1.0 / cfg.directions)
    if planes is None:  # for both passes' change maps
        planes = channel_planes(left), channel_planes(right)
    for along_rows in (True, False):
        # LANES more: a narrow band's step reads that far.
        change_l, change_r_rev = change_maps(left, right, cfg.tau, along_rows, n_disp + LANES,
                                             planes)
        if along_rows:  # first: writes every cell of ``out``
            scanline_rows(volume, lo, count, banded, change_l, change_r_rev, p1s, p2s, weight, out)
        else:
            scanline_columns(volume, lo, count, banded, change_l, change_r_rev, p1s, p2s, weight,
                             COLUMN_CHUNK, out)
    if cfg.directions == 8:
        for step_x in (1, -1):
            change_l = diagonal_colour_change(left, cfg.tau, step_x)
            change_r_rev = mirrored(diagonal_colour_change(right, cfg.tau, step_x),
                                    pad=n_disp + LANES, fill=1)
            scanline_diagonal_pass(volume, lo, count, banded, change_l, change_r_rev, p1s, p2s,
                                   step_x, weight, out)
    return out


def diagonal_colour_change(image: np.ndarray, threshold: float, step_x: int) -> np.ndarray:
    """uint8 (H, W): 1 where the largest channel difference between (y, x) and
    (y - 1, x - step_x) is ``threshold`` or more, and where there is no such pixel."""
    image = as_channels(image).astype(np.int16)
    out = np.ones(image.shape[:2], dtype=np.uint8)
    if step_x == 1:
        diff = np.abs(image[1:, 1:] - image[:-1, :-1]).max(axis=2)
        out[1:, 1:] = diff >= threshold
    else:
        diff = np.abs(image[1:, :-1] - image[:-1, 1:]).max(axis=2)
        out[1:, :-1] = diff >= threshold
    return out


def change_maps(left: np.ndarray, right: np.ndarray, tau: float, along_rows: bool,
                n_disp: int, planes: tuple[np.ndarray, np.ndarray] | None = None
                ) -> tuple[np.ndarray, np.ndarray]:
    """Where each view's colour changes by ``tau`` or more along the pass; the right
    view's reversed along x and padded with ``n_disp`` ones (no right pixel: a change),
    as the scanline kernels read it. ``planes``: both views' ``channel_planes``, where
    the caller has them."""
    planes_l, planes_r = (None, None) if planes is None else planes
    change_r = colour_change(right, tau, along_rows=along_rows, planes=planes_r)
    return (colour_change(left, tau, along_rows=along_rows, planes=planes_l),
            mirrored(change_r, pad=n_disp, fill=1))


def penalties(cfg: ScanlineConfig) -> tuple[np.ndarray, np.ndarray]:
    """P1 and P2 where 0, 1 or 2 of the views change colour (float32 arrays of three)."""
    divisors = np.array([1.0, cfg.reduce_one, cfg.reduce_both])
    return (cfg.p1 / divisors).astype(np.float32), (cfg.p2 / divisors).astype(np.float32)
