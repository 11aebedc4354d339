"""What the method refuses before any work: views it cannot run on, a range it cannot
search, a budget too small."""

from __future__ import annotations

import numpy as np

from .config import Config
from .scale import full_search_size, stripe_rows


def check_views(left: np.ndarray, right: np.ndarray, cfg: Config) -> None:
    """Refuse views the method cannot run on whatever the range (type, shape, size)."""
    for name, image in (("left", left), ("right", right)):
        if not isinstance(image, np.ndarray) or image.ndim not in (2, 3) or (
                image.ndim == 3 and image.shape[2] != 3):
            raise ValueError(f"{name} image must be an (H, W) or (H, W, 3) array, "
                             f"got shape {getattr(image, 'shape', None)}")
        if image.dtype != np.uint8:
            raise ValueError(f"{name} image must be uint8, got {image.dtype}")
    if left.shape[:2] != right.shape[:2]:
        raise ValueError(f"left and right images differ in size: {left.shape[1]}x{left.shape[0]}"
                         f" and {right.shape[1]}x{right.shape[0]}")
    if left.ndim != right.ndim:
        kinds = ["grey (H, W)" if image.ndim == 2 else "colour (H, W, 3)"
                 for image in (left, right)]
        raise ValueError(f"the left image is {kinds[0]} and the right {kinds[1]}: give "
                         "both grey or both colour")
    height, width = left.shape[:2]
    if width < cfg.cost.census_width or height < cfg.cost.census_height:
        raise ValueError(f"images of {width}x{height} are smaller than the census window "
                         f"{cfg.cost.census_width}x{cfg.cost.census_height}")


def check_pair(left: np.ndarray, right: np.ndarray, max_disp: int, cfg: Config,
               min_disp: int = 0) -> None:
    """Refuse inputs the method cannot run on, with a message naming the problem."""
    check_views(left, right, cfg)
    width = left.shape[1]
    for name, value in (("max_disp", max_disp), ("min_disp", min_disp)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise ValueError(f"{name} must be an integer, got {value!r}")
    if min_disp == 0 and not 0 < max_disp < width:
        raise ValueError(f"max_disp = {max_disp} must be between 1 and the image width "
                         f"minus one ({width - 1})")
    if max_disp <= min_disp:
        raise ValueError(f"max_disp = {max_disp} must be larger than min_disp = {min_disp}")
    # With an offset the views are cropped by |min_disp| columns (see run()).
    cropped = width - abs(min_disp)
    if max_disp - min_disp >= cropped or cropped < cfg.cost.census_width:
        raise ValueError(f"the range {min_disp}..{max_disp} is too wide for images "
                         f"{width} pixels wide")
    stripe_rows(*full_search_size(cropped, max_disp - min_disp, cfg, left.shape[0]),
                cfg, left.shape[0])  # budget enough? (the full size's height: at most)
