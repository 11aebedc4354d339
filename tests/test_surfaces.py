"""Planes across wide regions (vsmatch.surfaces): unsure pixels take their region's plane
where it explains the views as well, and only there."""

import dataclasses

import numpy as np
import pytest

from vsmatch import synthetic
from vsmatch.config import load_config
from vsmatch.disparity import VALID
from vsmatch.surfaces import spread_planes

#: A block of the synthetic pair's background plane (x beyond 0.85 of the width, clear of
#: the rectangles and the disc).
BLOCK = (slice(100, 140), slice(280, 312))


@pytest.fixture(scope="module")
def pair():
    return synthetic.make_pair(width=320, height=240, seed=3)


def _inputs(pair):
    disp = pair.disparity.copy()
    confidence = np.full(disp.shape, 0.9, np.float32)
    labels = np.full(disp.shape, VALID, np.uint8)
    return disp, confidence, labels


def _config(**changes):
    cfg = load_config("accurate")
    return dataclasses.replace(cfg, surfaces=dataclasses.replace(cfg.surfaces, **changes))


def test_an_unsure_wrong_block_takes_its_planes_value(pair):
    disp, confidence, labels = _inputs(pair)
    disp[BLOCK] = 2.0  # far from the plane's 6 + 10 x / 320 (about 15)
    confidence[BLOCK] = 0.1
    out = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                        _config())
    truth = pair.disparity[BLOCK]
    assert np.mean(np.abs(out[BLOCK] - truth) <= 1.0) > 0.95
    sure = confidence >= 0.5
    assert np.array_equal(out[sure], disp[sure])  # the sure pixels keep their values


def test_a_plane_that_explains_the_views_worse_is_refused(pair):
    """The block holds the true disparities but is unsure; the sure pixels around it are
    3 px off, so their plane is too: its matching cost is higher, and it is not taken
    unless the tolerance lets it through."""
    disp, confidence, labels = _inputs(pair)
    around = (slice(60, 180), slice(250, 320))
    disp[around] += 3.0
    disp[BLOCK] = pair.disparity[BLOCK]
    confidence[BLOCK] = 0.1
    kept = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                         _config())
    assert np.mean(np.abs(kept[BLOCK] - pair.disparity[BLOCK]) <= 1.0) > 0.95
    lenient = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                            _config(tolerance=3.0))
    assert np.mean(np.abs(lenient[BLOCK] - pair.disparity[BLOCK]) > 1.0) > 0.5  # taken


def test_without_unsure_pixels_nothing_changes(pair):
    disp, confidence, labels = _inputs(pair)
    out = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                        _config())
    assert np.array_equal(out, disp) and out is not disp
