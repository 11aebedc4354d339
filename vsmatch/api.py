"""The public matching functions, :func:`match` and :func:`run`: the range policy
(``vsmatch.search_range``) when no range is given, then the method (``vsmatch.pipeline``)."""

from __future__ import annotations

import numpy as np

from . import pipeline
from .checks import check_views
from .config import Config, load_config
from .forking import check_not_forked
from .result import MatchResult
from .search_range import resolve_range


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
    config : Config, bundled config name, YAML path or a mapping laid out as one, optional
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
    """:func:`match` with per-stage timings, the left-right labels, the confidence and the
    range used."""
    check_not_forked()  # before the range's search, which runs kernels too
    cfg = load_config(config)
    if max_disp is None:
        check_views(left, right, cfg)  # the views' own checks, before the features
        searched = resolve_range(left, right, min_disp=min_disp)
        min_disp, max_disp = searched.min_disp, searched.max_disp
    return pipeline.run(left, right, max_disp=max_disp,
                        min_disp=0 if min_disp is None else min_disp, config=cfg)
