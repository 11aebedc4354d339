"""The error measures on hand-made arrays, expected values written as arithmetic."""

import numpy as np
import pytest

from vsmatch import metrics

INF = np.inf


@pytest.fixture
def case():
    gt = np.array([[10.0, 10.0, 10.0, 100.0, 100.0]])
    disp = np.array([[10.4, 11.5, INF, 104.0, 106.0]])
    mask = np.ones_like(gt, dtype=bool)
    return disp, gt, mask


def test_middlebury_measures(case):
    disp, gt, mask = case
    m = metrics.middlebury_measures(disp, gt, mask)
    # errors of the valid estimates: 0.4, 1.5, 4, 6; one invalid of five pixels
    assert m["bad0.5"] == pytest.approx(100 * 4 / 5)  # 1.5, 4, 6 and the invalid one
    assert m["bad1.0"] == pytest.approx(100 * 4 / 5)
    assert m["bad2.0"] == pytest.approx(100 * 3 / 5)
    assert m["bad4.0"] == pytest.approx(100 * 2 / 5)  # 6 and the invalid; 4 is not > 4
    assert m["invalid"] == pytest.approx(100 * 1 / 5)
    assert m["avgerr"] == pytest.approx((0.4 + 1.5 + 4 + 6) / 4)
    assert m["rms"] == pytest.approx(np.sqrt((0.16 + 2.25 + 16 + 36) / 4))
    assert m["A50"] == pytest.approx((1.5 + 4) / 2)


def test_mask_selects_pixels(case):
    disp, gt, _ = case
    mask = np.array([[True, False, False, False, False]])
    m = metrics.middlebury_measures(disp, gt, mask)
    assert m["bad0.5"] == 0.0 and m["invalid"] == 0.0
    assert metrics.middlebury_measures(disp, gt, np.zeros_like(mask)) == {}


def test_kitti_d1_needs_both_conditions(case):
    disp, gt, mask = case
    m = metrics.kitti_measures(disp, gt, mask)
    # 10.4 and 11.5: under 3 px; 104: 4 px but 4 % of 100; 106: 6 px and 6 %: bad;
    # the invalid one: bad
    assert m["D1"] == pytest.approx(100 * 2 / 5)
    assert m["out3"] == pytest.approx(100 * 3 / 5)  # 4, 6 and the invalid
    assert m["invalid"] == pytest.approx(20.0)


def test_bad_name():
    assert metrics.bad_name(2) == "bad2.0" and metrics.bad_name(0.5) == "bad0.5"
