"""Coarse-to-fine search: the full search on a reduced image, a narrow band per pixel above.

Work and memory of the full search grow as width x height x disparities. Where a row holds
more than ``pyramid.max_row_cells`` width x disparity cells, the views are halved
(``cv2.pyrDown``) until it does not; the whole method runs there, and each finer level
searches only the disparities around the upsampled coarser estimate: from twice the
smallest to twice the largest coarse disparity of the 3 x 3 coarse neighbourhood, widened
by ``bands.band`` (so both sides of a depth edge stay candidates), at most
``bands.max_band`` of them. The same stages run over those bands (``vsmatch.bands``),
with arms of at most ``bands.support`` pixels. Every parameter is measured in pixels of
the level it runs on.
"""

from __future__ import annotations

import math

import numpy as np

from . import bands
from .bands import Bands
from .config import BandsConfig
from .disparity import VALID, labels_for_kernels
from ._kernels.bands import bands_from_coarse as bands_from_coarse_kernel, centre_on_likest
from .images import to_grey

#: Disparities the level below must keep for ``pyramid.min_levels`` to go down to it.
MIN_FORCED_DISPARITIES = 10


def coarse_levels(width: int, n_disp: int, max_row_cells: int, min_levels: int = 0,
                  height: int = 0, max_cells: int = 0) -> int:
    """How many times to halve a pair before the full search: while a row holds more
    than ``max_row_cells`` cells; at least once if the pair of ``height`` rows holds more
    than ``max_cells`` (> 0) cells (a camera-size pair: the bands above a halved full search
    keep its accuracy, where a second level down loses it); never below 64 columns or 16
    disparities; and at least ``min_levels`` times (the ``fast`` config's coarse-to-fine at
    every size) while the level below keeps :data:`MIN_FORCED_DISPARITIES` (a range
    halved below that leaves too few disparities to tell surfaces apart)."""
    levels = 0
    while ((width * n_disp > max_row_cells
            or (levels == 0 and 0 < max_cells < width * height * n_disp)
            or (levels < min_levels and n_disp >= 2 * MIN_FORCED_DISPARITIES))
           and width >= 64 and n_disp >= 16):
        width, max_disp = level_down(width, n_disp - 1)
        n_disp = max_disp + 1
        height = (height + 1) // 2
        levels += 1
    return levels


def level_down(width: int, max_disp: int) -> tuple[int, int]:
    """Width and largest disparity one level down (as :func:`downsample` halves the width),
    the range kept below the width."""
    width = (width + 1) // 2
    return width, min(int(math.ceil(max_disp / 2)), width - 1)


def bands_from_coarse(coarse: np.ndarray, coarse_labels: np.ndarray | None,
                      shape: tuple[int, int], max_disp: int, cfg: BandsConfig,
                      views: tuple[np.ndarray, np.ndarray] | None = None) -> Bands:
    """Each pixel's candidates at this level from the disparity one level down: twice the
    smallest to twice the largest of its coarse 3 x 3 neighbourhood (a pixel the coarse
    level rejected, then filled: its own value only, its neighbours' being mostly the
    occluder's),
    widened by ``band`` and one more each side (the sub-pixel fit's neighbours), at most
    ``max_band`` of them around twice its own coarse disparity (with ``guide`` and the
    ``views``, this level's left view and the one below, around that of the coarse
    neighbour most like the pixel: :func:`_centre_on_likest`); none where the coarse
    level has no estimate."""
    n_disp = max_disp + 1
    lo, count = (np.empty(shape, np.int32) for _ in range(2))
    wide = np.empty(coarse.shape, np.bool_)
    # Each coarse pixel's band, repeated over its block of fine pixels as it is written.
    bands_from_coarse_kernel(np.ascontiguousarray(coarse, dtype=np.float32),
                             labels_for_kernels(coarse_labels), VALID, cfg.band + 1,
                             n_disp, cfg.max_band, lo, count, wide)
    found = bands.Bands(lo, count, min(cfg.max_band, n_disp), n_disp)
    if cfg.guide is not None and views is not None and wide.any():
        _centre_on_likest(found, coarse, coarse_labels, wide, views, cfg.guide)
    return found


def _centre_on_likest(found: Bands, coarse: np.ndarray, coarse_labels: np.ndarray | None,
                      wide: np.ndarray, views: tuple[np.ndarray, np.ndarray],
                      guide: float) -> None:
    """Where a coarse pixel's 3 x 3 range is wider than a band, its fine pixels' bands (in
    ``found``, in place) centred on the coarse neighbour whose grey level is nearest each
    one's, the pixel's own unless another is nearer by more than ``guide``. At a depth
    edge the coarse pixel mixes both surfaces; centred on its own estimate, the fine
    pixels beside a thin object could only take the object's disparity (``fast`` drew a
    synthetic wire 3 px wide 1.47x its width, 1.15x with this)."""
    n_disp = found.n_disp
    usable = np.isfinite(coarse)
    if coarse_labels is not None:
        usable &= coarse_labels == VALID
    fine, small = (to_grey(view) for view in views)
    centre_on_likest(np.ascontiguousarray(coarse, dtype=np.float32), usable, small, fine,
                     wide, np.float32(guide), int(found.width), int(n_disp), found.lo,
                     found.count)
