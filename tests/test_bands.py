"""The bands a level searches from the disparity one level down (vsmatch.pyramid), worked
out by a parallel kernel: the same bands as the NumPy and OpenCV steps they replaced."""

import cv2
import numpy as np
import pytest

from vsmatch import pyramid
from vsmatch.config import load_config
from vsmatch.disparity import VALID
from vsmatch.images import upsample_nearest


def _bands_by_numpy(coarse, labels, shape, max_disp, band, max_band):
    """The steps as NumPy and OpenCV took them: each coarse pixel's 3 x 3 extremes (erosion
    and dilation, the border replicated; a rejected pixel its own value), widened, rounded
    outwards, cut to ``max_band`` around twice the pixel's value, repeated over its block."""
    finite = np.isfinite(coarse)
    kernel = np.ones((3, 3), np.uint8)
    low = cv2.erode(np.where(finite, coarse, np.inf).astype(np.float32), kernel,
                    borderType=cv2.BORDER_REPLICATE)
    high = cv2.dilate(np.where(finite, coarse, -np.inf).astype(np.float32), kernel,
                      borderType=cv2.BORDER_REPLICATE)
    if labels is not None:
        unsure = (labels != VALID) & finite
        low[unsure] = coarse[unsure]
        high[unsure] = coarse[unsure]
    low[~finite], high[~finite] = np.inf, -np.inf
    n_disp, widen = max_disp + 1, band + 1
    with np.errstate(invalid="ignore"):
        low, high, centre = 2 * low - widen, 2 * high + widen, 2 * coarse
    known = np.isfinite(low) & np.isfinite(high) & np.isfinite(centre)
    lo = np.clip(np.floor(np.where(known, low, 0)), 0, n_disp - 1)
    count = np.clip(np.ceil(np.where(known, high, 0)), 0, n_disp - 1) - lo + 1
    wide = count > max_band
    middle = np.round(np.where(known, centre, 0)) - max_band // 2
    lo = np.where(wide, np.clip(middle, 0, max(n_disp - max_band, 0)), lo)
    count = np.where(wide, min(max_band, n_disp), count)
    count[~known] = 0
    return (upsample_nearest(lo.astype(np.int32), shape),
            upsample_nearest(count.astype(np.int32), shape))


@pytest.mark.parametrize("coarse_shape, shape", [((20, 30), (40, 60)), ((20, 30), (39, 59)),
                                                 ((1, 1), (2, 1)), ((7, 5), (15, 11))])
@pytest.mark.parametrize("with_labels", [True, False])
def test_bands_from_coarse_are_the_numpy_steps(coarse_shape, shape, with_labels):
    rng = np.random.default_rng(coarse_shape[0] + shape[1])
    max_disp = 70
    coarse = (rng.random(coarse_shape) * 36).astype(np.float32)
    coarse[rng.random(coarse_shape) < 0.1] = np.inf
    coarse[rng.random(coarse_shape) < 0.05] = np.nan
    coarse[: coarse_shape[0] // 2] = np.round(coarse[: coarse_shape[0] // 2] * 2) / 2  # x.5
    labels = rng.integers(0, 3, coarse_shape).astype(np.uint8) if with_labels else None
    cfg = load_config("fast").bands
    found = pyramid.bands_from_coarse(coarse, labels, shape, max_disp, cfg)
    lo, count = _bands_by_numpy(coarse, labels, shape, max_disp, cfg.band, cfg.max_band)
    assert found.lo.tobytes() == lo.tobytes()
    assert found.count.tobytes() == count.tobytes()
    assert found.width == min(cfg.max_band, max_disp + 1) and found.n_disp == max_disp + 1
    if coarse.size > 100:  # both cases were met
        assert (count == cfg.max_band).any() and (count == 0).any()


@pytest.mark.parametrize("shape", [(40, 60), (39, 59), (40, 59), (1, 1), (2, 3)])
@pytest.mark.parametrize("dtype", [np.uint8, np.int32, np.float32])
def test_upsample_nearest_repeats_each_pixel_over_its_block(rng, shape, dtype):
    """The levels' maps taken a level up (the doubled kernel writes each pixel twice along a
    row): every fine pixel holds its coarse pixel, the odd last row and column too, planes
    along the first axis alike."""
    coarse = (rng.random((3, (shape[0] + 1) // 2, (shape[1] + 1) // 2)) * 200).astype(dtype)
    want = np.repeat(np.repeat(coarse, 2, axis=1), 2, axis=2)[:, :shape[0], :shape[1]]
    np.testing.assert_array_equal(upsample_nearest(coarse, shape), want)
    np.testing.assert_array_equal(upsample_nearest(coarse[0], shape), want[0])
