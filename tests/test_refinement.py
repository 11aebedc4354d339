import numpy as np
import pytest

from vsmatch import optimization, refinement
from vsmatch.config import DiscontinuityConfig, ScanlineConfig, VotingConfig

import reference


# Depths below a vector, whole vectors and vectors with a last one part-filled.
@pytest.mark.parametrize("directions, h, w, n", [(4, 7, 9, 5), (8, 7, 9, 5), (8, 11, 6, 5),
                                                 (4, 5, 21, 5), (4, 6, 10, 16), (4, 6, 10, 13),
                                                 (8, 5, 9, 21)])
def test_scanline_matches_reference(rng, directions, h, w, n):
    cost = rng.random((h, w, n), dtype=np.float32) * 2
    left = rng.integers(0, 40, size=(h, w, 3), dtype=np.uint8)
    right = rng.integers(0, 40, size=(h, w, 3), dtype=np.uint8)
    cfg = ScanlineConfig(enabled=True, p1=0.5, p2=1.7, tau=20, reduce_one=4, reduce_both=10,
                         directions=directions)
    got = optimization.scanline_optimise(cost, left, right, cfg)
    want = reference.scanline(cost, left, right, 0.5, 1.7, 20, 4, 10, directions)
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-5)


def test_scanline_smooths_an_isolated_wrong_minimum():
    cost = np.ones((1, 9, 4), np.float32)
    cost[0, :, 2] = 0.0
    cost[0, 4, 2], cost[0, 4, 0] = 1.0, 0.5  # one pixel prefers d = 0
    flat = np.zeros((1, 9, 3), np.uint8)
    out = optimization.scanline_optimise(cost, flat, flat, ScanlineConfig(p1=1.0, p2=3.0))
    assert out[0, 4].argmin() == 2


def test_region_vote_matches_reference(rng):
    h, w, n = 12, 14, 6
    disp = rng.integers(0, n, size=(h, w)).astype(np.int32)
    disp[:, 7:] = 3  # a consensus on the right half
    labels = (rng.random((h, w)) < 0.3).astype(np.uint8)
    arms = np.full((h, w, 4), 3, np.int32)
    xs, ys = np.arange(w), np.arange(h)
    arms[..., 0] = np.minimum(3, xs)[None]
    arms[..., 1] = np.minimum(3, w - 1 - xs)[None]
    arms[..., 2] = np.minimum(3, ys)[:, None]
    arms[..., 3] = np.minimum(3, h - 1 - ys)[:, None]
    cfg = VotingConfig(enabled=True, iterations=2, min_votes=8, min_share=0.4)
    planes = np.ascontiguousarray(np.moveaxis(arms, -1, 0)).astype(np.uint8)
    got_d, got_l = refinement.region_vote(disp, labels, planes, n_disp=n, cfg=cfg)
    want_d, want_l = disp, labels
    for _ in range(2):
        want_d, want_l = reference.region_vote_once(want_d, want_l, arms, n, 8, 0.4)
    np.testing.assert_array_equal(got_d, want_d)
    np.testing.assert_array_equal(got_l, want_l)
    assert got_l[:, 8:-3].sum() < labels[:, 8:-3].sum()  # the consensus fixed some


def test_region_vote_matches_reference_with_arms_of_every_length(rng):
    """Regions of odd and even numbers of rows whose rows reach unequally far (the kernel
    walks two rows' runs side by side, then what is left of the longer)."""
    h, w, n = 13, 17, 5
    for _ in range(20):
        disp = rng.integers(0, n, size=(h, w)).astype(np.int32)
        disp[:, :6] = rng.integers(0, 2, size=(h, 6))  # long runs, few votes
        labels = (rng.random((h, w)) < 0.4).astype(np.uint8)
        arms = rng.integers(0, 6, size=(h, w, 4)).astype(np.int32)
        xs, ys = np.arange(w), np.arange(h)
        arms[..., 0] = np.minimum(arms[..., 0], xs[None])
        arms[..., 1] = np.minimum(arms[..., 1], (w - 1 - xs)[None])
        arms[..., 2] = np.minimum(arms[..., 2], ys[:, None])
        arms[..., 3] = np.minimum(arms[..., 3], (h - 1 - ys)[:, None])
        cfg = VotingConfig(enabled=True, iterations=1, min_votes=3, min_share=0.3)
        planes = np.ascontiguousarray(np.moveaxis(arms, -1, 0)).astype(np.uint8)
        got_d, got_l = refinement.region_vote(disp, labels, planes, n_disp=n, cfg=cfg)
        want_d, want_l = reference.region_vote_once(disp, labels, arms, n, 3, 0.3)
        np.testing.assert_array_equal(got_d, want_d)
        np.testing.assert_array_equal(got_l, want_l)


def test_discontinuity_adjust_moves_an_edge_to_the_lower_cost():
    disp = np.array([[2, 2, 2, 5, 5]], np.float32)
    volume = np.ones((1, 5, 6), np.float32)
    volume[0, 3, 2] = 0.1  # pixel 3 fits its left neighbour's disparity better
    out = refinement.discontinuity_adjust(disp, volume, DiscontinuityConfig(jump=1.0))
    assert out.tolist() == [[2, 2, 2, 2, 5]]


@pytest.mark.parametrize("true_d", [2.0, 2.3, 1.7])
def test_subpixel_finds_the_vertex_of_a_parabola(true_d):
    d = np.arange(5, dtype=np.float32)
    volume = ((d - true_d) ** 2).reshape(1, 1, 5).astype(np.float32)
    disp = np.array([[round(true_d)]], np.float32)
    np.testing.assert_allclose(refinement.subpixel(disp, volume), [[true_d]], atol=1e-5)


def test_subpixel_keeps_the_range_ends_and_invalid():
    volume = np.random.default_rng(1).random((1, 3, 4), dtype=np.float32)
    disp = np.array([[0, 3, np.inf]], np.float32)
    out = refinement.subpixel(disp, volume)
    assert out[0, 0] == 0 and out[0, 1] == 3 and np.isinf(out[0, 2])


def test_median3_keeps_invalid_pixels_apart():
    disp = np.full((5, 5), 4.0, np.float32)
    disp[2, 2] = 9.0
    disp[0, 0] = np.inf
    out = refinement.median3(disp)
    assert out[2, 2] == 4.0 and np.isinf(out[0, 0]) and np.isfinite(out[1:, 1:]).all()


def test_discontinuity_adjust_matches_reference(rng):
    disp = rng.integers(0, 6, size=(9, 12)).astype(np.float32)
    disp[2, 3] = np.inf
    volume = rng.random((9, 12, 6), dtype=np.float32)
    for jump in (0.0, 1.0, 2.5):
        got = refinement.discontinuity_adjust(disp, volume, DiscontinuityConfig(jump=jump))
        np.testing.assert_array_equal(got, reference.discontinuity(disp, volume, jump))


def test_subpixel_matches_reference(rng):
    disp = rng.integers(0, 7, size=(9, 12)).astype(np.float32)
    disp[4, 4] = np.inf
    volume = rng.random((9, 12, 7), dtype=np.float32)
    np.testing.assert_allclose(refinement.subpixel(disp, volume),
                               reference.subpixel(disp, volume), rtol=1e-5, atol=1e-6)


def test_region_planes_match_reference(rng):
    """The planes' fit (moments, running sums along rows, then down blocks of columns, and
    a solve written as selects so that it vectorises) gives the bytes of the moments
    summed in NumPy and solved a pixel at a time with branches: empty, too light, one-axis
    and full regions alike, a width that is not a whole number of column blocks."""
    from vsmatch._kernels.planes import COLUMN_BLOCK, fit_region_planes
    from vsmatch.planes import moment_blocks
    from vsmatch.aggregation import keep_arms_inside

    height, width = 23, 2 * COLUMN_BLOCK + 5
    disp = (rng.random((height, width)) * 40).astype(np.float32)
    disp[5, :] = np.nan
    kept = rng.random((height, width)) < 0.7
    arms = rng.integers(0, 4, (4, height, width)).astype(np.uint8)
    arms[:, :, :10] = 0  # single pixels: no spread along either axis
    arms[0:2, 10:, 10:20] = 0  # columns only: a constant along u
    keep_arms_inside(arms)
    got = np.empty((height, width), np.float32), np.empty((height, width), np.float32)
    fit_region_planes(disp, kept, np.empty((0, 0), np.float32), np.float32(1.0), arms,
                      np.float32(0.5), np.float32(1.0), np.ones((height, width), bool),
                      moment_blocks((height, width)), *got)
    sums = reference.region_moment_sums(
        reference.plane_moments(disp, kept.astype(np.float32)), arms)
    want = reference.plane_values(sums, 0.5, 1.0)
    for g, w in zip(got, want):
        assert g.tobytes() == w.tobytes()
    assert np.isnan(got[0]).any() and np.isfinite(got[0]).any()


def test_region_planes_iterate_on_inliers_and_solve_where_wanted(rng):
    """Three fits, each through the kept pixels within ``inlier`` of the last fit's plane
    (weighed inside the kernel), give the reference's bytes at every wanted pixel; a run
    of a block's row with no wanted pixel is left NaN (not solved), and without ``wanted``
    every pixel is solved."""
    from vsmatch._kernels.planes import COLUMN_BLOCK
    from vsmatch.aggregation import keep_arms_inside
    from vsmatch.planes import MIN_SPREAD, region_planes

    height, width = 21, 3 * COLUMN_BLOCK + 3
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    disp = (0.2 * xs - 0.1 * ys + 10).astype(np.float32)
    outliers = rng.random((height, width)) < 0.15
    disp[outliers] += rng.uniform(-6, 6, int(outliers.sum())).astype(np.float32)
    kept = rng.random((height, width)) < 0.8
    arms = rng.integers(0, 6, (4, height, width)).astype(np.uint8)
    keep_arms_inside(arms)
    wanted = np.zeros((height, width), bool)
    wanted[3, 5] = wanted[10, COLUMN_BLOCK + 2:COLUMN_BLOCK + 9] = True

    plane = None
    for _ in range(3):
        weight = kept if plane is None else kept & (np.abs(disp - plane) <= 1.0)
        sums = reference.region_moment_sums(
            reference.plane_moments(disp, weight.astype(np.float32)), arms)
        plane, spread = reference.plane_values(sums, 0.3, MIN_SPREAD)
    got, got_spread = region_planes(disp, kept, arms, 3, 0.3, 1.0, wanted)
    assert got[wanted].tobytes() == plane[wanted].tobytes()
    assert got_spread[wanted].tobytes() == spread[wanted].tobytes()
    unsolved = np.ones((height, width), bool)
    unsolved[3, :COLUMN_BLOCK] = unsolved[10, COLUMN_BLOCK:2 * COLUMN_BLOCK] = False
    assert np.isnan(got[unsolved]).all() and np.isfinite(got[~unsolved]).any()
    everywhere, _ = region_planes(disp, kept, arms, 3, 0.3, 1.0)
    assert everywhere.tobytes() == plane.tobytes()
    assert (np.abs(disp - plane) > 1.0)[kept & np.isfinite(plane)].any()  # outliers left


def test_reference_region_sums_add_each_cross_region(rng):
    """The reference's running sums against each cross region's pixels added one by one."""
    from vsmatch.aggregation import keep_arms_inside

    h, w = 13, 17
    src = rng.random((h, w, 3)).astype(np.float32)
    arms = rng.integers(0, 6, (4, h, w)).astype(np.uint8)
    keep_arms_inside(arms)
    want = np.zeros_like(src, dtype=np.float64)
    for y in range(h):
        for x in range(w):
            for yy in range(y - arms[2, y, x], y + arms[3, y, x] + 1):
                want[y, x] += src[yy, x - arms[0, yy, x]:x + arms[1, yy, x] + 1].sum(axis=0)
    np.testing.assert_allclose(reference.region_moment_sums(src, arms), want, rtol=1e-5,
                               atol=1e-5)
