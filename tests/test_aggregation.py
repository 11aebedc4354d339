import numpy as np
import pytest

from vsmatch import aggregation
from vsmatch.config import ArmsConfig

import reference


def planes(arms):
    """The library's arm layout, (4, H, W) uint8, from the references' (H, W, 4)."""
    return np.ascontiguousarray(np.moveaxis(arms, -1, 0)).astype(np.uint8)


@pytest.mark.parametrize("kappa", [0.0, 1.5, -0.5])
def test_cross_arms_match_reference(rng, kappa):
    image = rng.integers(0, 60, size=(12, 15, 3), dtype=np.uint8)
    theta = rng.uniform(-np.pi, np.pi, size=(12, 15)).astype(np.float32)
    grad = rng.uniform(0, 300, size=(12, 15)).astype(np.float32)
    cfg = ArmsConfig(tau1=30, tau2=25, tau3=12, l1=3, l2=6, kappa=kappa, g_sat=150)
    got = aggregation.cross_arms(image, theta, grad, cfg)
    want = reference.cross_arms(image, theta, grad, 30, 25, 12, 3, 6, kappa, 150)
    np.testing.assert_array_equal(got, planes(want))


@pytest.mark.parametrize("shape", [(1, 1, 3), (1, 9, 3), (9, 1, 3), (2, 3, 1), (40, 50, 1)])
def test_cross_arms_match_reference_on_thin_and_grey_images(rng, shape):
    """The row-at-a-time kernel narrows each step to the pixels whose arms still grow:
    images of one row or column, and arms that stop at the border or at l2."""
    image = rng.integers(100, 112, size=shape, dtype=np.uint8)  # long arms
    image[:, ::7] = 0  # and some that stop at a step
    grad = np.zeros(shape[:2], np.float32)
    cfg = ArmsConfig(tau1=20, tau2=20, tau3=6, l1=3, l2=9)
    got = aggregation.cross_arms(image, grad, grad, cfg)
    want = reference.cross_arms(image, grad, grad, 20, 20, 6, 3, 9, 0.0, 200)
    np.testing.assert_array_equal(got, planes(want))


def test_arms_of_a_flat_image_reach_l2_or_the_border():
    image = np.full((9, 40, 3), 100, np.uint8)
    zeros = np.zeros((9, 40), np.float32)
    arms = aggregation.cross_arms(image, zeros, zeros, ArmsConfig(l1=5, l2=10))
    assert arms.shape == (4, 9, 40) and arms.dtype == np.uint8
    assert arms[:, 4, 20].tolist() == [10, 10, 4, 4]
    assert arms[:, 0, 0].tolist() == [0, 10, 0, 8]


@pytest.mark.parametrize("method", ["running", "direct"])
@pytest.mark.parametrize("iterations", [1, 2, 3])
@pytest.mark.parametrize("n", [4, 37])  # 37: vector steps of 16 and a remainder
def test_aggregation_matches_explicit_region_average(rng, iterations, method, n):
    h, w = 8, 11
    volume = rng.random((h, w, n), dtype=np.float32)
    arms_l = rng.integers(0, 4, size=(h, w, 4)).astype(np.int32)
    arms_r = rng.integers(0, 4, size=(h, w, 4)).astype(np.int32)
    # Arms must stay inside the image.
    for arms in (arms_l, arms_r):
        xs, ys = np.arange(w), np.arange(h)
        arms[..., 0] = np.minimum(arms[..., 0], xs[None, :])
        arms[..., 1] = np.minimum(arms[..., 1], (w - 1 - xs)[None, :])
        arms[..., 2] = np.minimum(arms[..., 2], ys[:, None])
        arms[..., 3] = np.minimum(arms[..., 3], (h - 1 - ys)[:, None])
    want = reference.aggregate(volume, arms_l, arms_r, iterations)
    got = aggregation.aggregate_cross(volume.copy(), planes(arms_l), planes(arms_r),
                                      iterations=iterations, method=method)
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6)


def test_aggregation_methods_agree_on_real_arms(rng):
    """Long arms and a wide range: the running sums (integral images) are the direct sums
    of the same regions."""
    image = np.zeros((30, 50, 3), np.uint8)
    image[:, 25:] = 200  # two flat halves: arms up to the step or the border
    theta = np.zeros((30, 50), np.float32)
    grad = np.zeros((30, 50), np.float32)
    arms = aggregation.cross_arms(image, theta, grad, ArmsConfig(l1=5, l2=20))
    volume = rng.random((30, 50, 40), dtype=np.float32)
    results = [aggregation.aggregate_cross(volume.copy(), arms, arms, iterations=2,
                                           method=method)
               for method in aggregation.AGGREGATION_METHODS]
    for other in results[1:]:
        np.testing.assert_allclose(other, results[0], rtol=1e-5, atol=1e-6)


def test_aggregation_method_is_checked():
    with pytest.raises(ValueError, match="aggregation method"):
        aggregation.aggregate_cross(np.zeros((2, 2, 2), np.float32),
                                    np.zeros((4, 2, 2), np.uint8),
                                    np.zeros((4, 2, 2), np.uint8), iterations=1,
                                    method="fast")


def test_aggregation_keeps_a_constant_volume():
    volume = np.full((6, 7, 3), 0.25, np.float32)
    arms = np.ones((6, 7, 4), np.int32)
    arms[:, 0, 0] = 0
    arms[:, -1, 1] = 0
    arms[0, :, 2] = 0
    arms[-1, :, 3] = 0
    got = aggregation.aggregate_cross(volume, planes(arms), planes(arms), iterations=4)
    np.testing.assert_allclose(got, 0.25, rtol=1e-6)


def test_shrinking_threshold_shortens_arms_on_a_ramp():
    """One grey level per pixel along x: the fixed threshold 16 stops the arm after 15
    pixels; falling as 16 (1 - k / 40), it stops where k >= 16 (1 - k / 40), after 11."""
    ramp = np.tile(np.arange(100, dtype=np.uint8), (5, 1))
    theta = np.zeros(ramp.shape, np.float32)
    grad = np.zeros(ramp.shape, np.float32)
    lengths = {}
    for shrink in (False, True):
        cfg = ArmsConfig(tau1=16, tau2=16, tau3=16, l1=39, l2=40, shrink=shrink)
        lengths[shrink] = aggregation.cross_arms(ramp, theta, grad, cfg)[1, 2, 50]  # right arm
    assert lengths == {False: 15, True: 11}


@pytest.mark.parametrize("side", [0, 1, 2, 3])
def test_arms_past_the_edge_are_refused(rng, side):
    """An arm past the view's edge would be read past the running sums' ends: named."""
    h, w, n = 6, 9, 5
    volume = rng.random((h, w, n), dtype=np.float32)
    arms = np.ones((4, h, w), np.uint8)
    aggregation.keep_arms_inside(arms)
    aggregation.aggregate_cross(volume.copy(), arms, arms.copy(), iterations=1)  # inside
    reaching = arms.copy()
    y, x = ((3, 0), (3, w - 1), (0, 4), (h - 1, 4))[side]
    reaching[side, y, x] = 1
    name = ("left", "right", "up", "down")[side]
    with pytest.raises(ValueError, match=f"right view's {name} arms reach past"):
        aggregation.aggregate_cross(volume.copy(), arms, reaching, iterations=1)


@pytest.mark.parametrize("shape", [(4, 1, 1), (4, 7, 300), (4, 290, 5)])
def test_arms_kept_inside_end_at_the_edge_or_at_255(rng, shape):
    arms = rng.integers(0, 256, size=shape).astype(np.uint8)
    kept = aggregation.keep_arms_inside(arms.copy())
    height, width = shape[1:]
    ys, xs = np.mgrid[:height, :width]
    rooms = np.minimum(np.stack([xs, width - 1 - xs, ys, height - 1 - ys]), 255)
    np.testing.assert_array_equal(kept, np.minimum(arms, rooms))
    aggregation.aggregate_cross(rng.random(shape[1:] + (3,), dtype=np.float32), kept,
                                kept.copy(), iterations=1)  # inside: taken


@pytest.mark.parametrize("largest, length", [(123.0, 718), (3.0, 2872), (1e-3, 40),
                                             (5e4, 100000), (0.0, 10)])
def test_fixed_point_scale_is_the_largest_power_of_two_that_fits_a_line(largest, length):
    from vsmatch._kernels.aggregate import SUM_BITS

    line_max = np.array([largest / 2, largest], np.float32)
    scale = aggregation.fixed_point_scale(line_max, length)
    exponent = np.log2(scale)
    assert exponent == int(exponent) and exponent <= 32
    total = float(np.float32(largest)) * length
    assert total * scale < 2.0 ** SUM_BITS
    assert exponent == 32 or total * scale * 2 >= 2.0 ** SUM_BITS


@pytest.mark.parametrize("bad", [np.inf, np.nan])
def test_a_cost_that_is_not_a_number_is_refused_by_the_running_sums(rng, bad):
    volume = rng.random((5, 6, 3), dtype=np.float32)
    volume[2, 3, 1] = bad
    arms = aggregation.keep_arms_inside(np.full((4, 5, 6), 2, np.uint8))
    with pytest.raises(ValueError, match="not a finite number"):
        aggregation.aggregate_cross(volume, arms, arms.copy(), iterations=1)


def _long_line_means(volume, reach):
    """The cross regions' means (rows first) in float64, for arms of ``reach`` pixels cut at
    the views' edges in both views (:func:`aggregation.keep_arms_inside`)."""
    height, width, n = volume.shape
    xs, ys = np.arange(width), np.arange(height)
    out = np.empty(volume.shape)
    for d in range(n):
        # At d the arm is the shorter of the left pixel's and the right pixel x - d's (none
        # where x - d < 0: no limit); the vertical arms are alike in both views.
        right = xs - d
        lo = np.minimum(np.minimum(reach, xs), np.where(right >= 0, np.minimum(reach, right),
                                                        255))
        hi = np.minimum(np.minimum(reach, width - 1 - xs),
                        np.where(right >= 0, np.minimum(reach, width - 1 - right), 255))
        sums = np.concatenate([np.zeros((height, 1)), np.cumsum(volume[:, :, d], axis=1)], 1)
        rows = sums[:, xs + hi + 1] - sums[:, xs - lo]
        sizes = (lo + hi + 1).astype(np.float64)
        up, down = np.minimum(reach, ys), np.minimum(reach, height - 1 - ys)
        for y in range(height):
            out[y, :, d] = rows[y - up[y]:y + down[y] + 1].sum(0) / \
                (sizes * (up[y] + down[y] + 1))
    return out


def test_running_sums_keep_close_costs_apart_on_a_long_line(rng):
    """Long rows of large costs: the fixed-point running sums give each region's mean to
    float32 rounding (float64 sums as the truth), and keep two candidates 1e-4 apart
    apart."""
    height, width, n = 3, 3000, 6
    volume = (2.0 + rng.random((height, width, n))).astype(np.float32)
    volume[:, :, 1] = volume[:, :, 0] + np.float32(1e-4)
    arms = aggregation.keep_arms_inside(np.full((4, height, width), 200, np.uint8))
    running = aggregation.aggregate_cross(volume.copy(), arms, arms.copy(), iterations=1)
    np.testing.assert_allclose(running, _long_line_means(volume.astype(np.float64), 200),
                               rtol=1.5e-7, atol=0)
    assert np.all(running[:, :, 1] > running[:, :, 0])


def test_a_line_too_long_for_the_running_sums_is_refused():
    """The running sums' offsets are 32-bit: a line whose sums would pass them is named
    before any work (a view-sized array stands in for the huge volume)."""
    volume = np.lib.stride_tricks.as_strided(np.zeros(1, np.float32), (1, 2 ** 22, 512),
                                             (0, 0, 0))
    arms = np.zeros((4, 1, 2 ** 22), np.uint8)
    with pytest.raises(ValueError, match="too long for the running sums"):
        aggregation.aggregate_cross(volume, arms, arms, iterations=1,
                                    scratch=np.empty((1, 1, 1), np.float32))


@pytest.mark.parametrize("channels", [1, 2, 3])  # grey and colour written out, the rest
@pytest.mark.parametrize("threshold", [0.0, 16.5, 17.0, 300.0])
def test_colour_change_is_the_largest_channel_step_against_the_threshold(rng, channels,
                                                                         threshold):
    from vsmatch.images import channel_planes, colour_change

    image = rng.integers(0, 256, size=(23, 37, channels)).astype(np.uint8)
    image[5:9, 10:20] = 128  # flat patches: steps of 0
    wide = image.astype(np.int32)
    for along_rows in (True, False):
        view = image[:, :, 0] if channels == 1 else image
        got = colour_change(view, threshold, along_rows=along_rows)
        np.testing.assert_array_equal(colour_change(view, threshold, along_rows=along_rows,
                                                    planes=channel_planes(view)), got)
        step = np.abs(np.diff(wide, axis=1 if along_rows else 0)).max(axis=2) >= threshold
        want = np.ones(image.shape[:2], np.uint8)
        if along_rows:
            want[:, 1:] = step
        else:
            want[1:, :] = step
        np.testing.assert_array_equal(got, want)


def test_arms_and_scanline_take_the_views_planes_made_once(rng):
    """The solver makes each view's int16 planes once and hands them to the arms and the
    scanline: the same arms and path costs as each making its own (colour and grey)."""
    from vsmatch import optimization
    from vsmatch.config import load_config
    from vsmatch.images import channel_planes

    cfg = load_config("default")
    for channels in (3, 1):
        left = rng.integers(0, 256, size=(29, 41, channels)).astype(np.uint8)
        right = np.roll(left, -3, axis=1)
        if channels == 1:
            left, right = left[:, :, 0], right[:, :, 0]
        planes = channel_planes(left), channel_planes(right)
        grad = np.zeros(left.shape[:2], np.float32)
        np.testing.assert_array_equal(
            aggregation.cross_arms(left, None, grad, cfg.arms, planes[0]),
            aggregation.cross_arms(left, None, grad, cfg.arms))
        # They are read, not made again: the other view's planes give other arms.
        assert not np.array_equal(aggregation.cross_arms(left, None, grad, cfg.arms, planes[1]),
                                  aggregation.cross_arms(left, None, grad, cfg.arms))
        volume = rng.random((29, 41, 8), dtype=np.float32)
        np.testing.assert_array_equal(
            optimization.scanline_optimise(volume, left, right, cfg.scanline, planes=planes),
            optimization.scanline_optimise(volume, left, right, cfg.scanline))
