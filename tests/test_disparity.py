import numpy as np
import pytest

from vsmatch import disparity
from vsmatch.config import FillConfig

import reference


def test_winner_takes_all_both_views(rng):
    volume = rng.random((7, 10, 4), dtype=np.float32)
    np.testing.assert_array_equal(disparity.winner_takes_all(volume), volume.argmin(axis=2))
    np.testing.assert_array_equal(disparity.winner_takes_all_both(volume)[1],
                                  reference.wta_right(volume))


def test_winner_takes_all_ties_take_smallest_disparity():
    volume = np.zeros((2, 3, 5), np.float32)
    assert np.all(disparity.winner_takes_all(volume) == 0)


@pytest.mark.parametrize("n_disp", [3, 37])
def test_winner_takes_all_in_one_pass_matches_both_views(rng, n_disp):
    # Few distinct values, so that ties are common in both views.
    volume = np.round(rng.random((6, 40, n_disp), dtype=np.float32) * 4)
    got_l, got_r = disparity.winner_takes_all_both(volume)
    np.testing.assert_array_equal(got_l, volume.argmin(axis=2))
    np.testing.assert_array_equal(got_r, reference.wta_right(volume))


def test_left_right_check_matches_reference(rng):
    dl = rng.integers(0, 5, size=(9, 14)).astype(np.int32)
    dr = rng.integers(0, 5, size=(9, 14)).astype(np.int32)
    for tol in (0, 1):
        got = disparity.left_right_check(dl, dr, n_disp=5, tolerance=tol)
        np.testing.assert_array_equal(got, reference.lr_labels(dl, dr, 5, tol))


def test_left_right_check_matches_reference_with_bands(rng):
    """Right pixels pointing past either end, or offered nothing (NO_DISPARITY), left
    pixels without a candidate (< 0), and right disparities beyond the range checked."""
    from vsmatch._kernels.disparity import NO_DISPARITY

    dl = rng.integers(-1, 30, size=(20, 60)).astype(np.int32)
    dr = rng.integers(0, 40, size=(20, 60)).astype(np.int32)
    dr[rng.random(dr.shape) < 0.1] = NO_DISPARITY
    labels = set()
    for n_disp, tol in ((30, 0), (30, 1), (12, 2), (64, 0)):
        got = disparity.left_right_check(dl, dr, n_disp=n_disp, tolerance=tol)
        np.testing.assert_array_equal(got, reference.lr_labels(dl, dr, n_disp, tol))
        labels |= set(np.unique(got).tolist())
    assert labels == {disparity.VALID, disparity.OCCLUDED, disparity.MISMATCHED}


def test_left_right_check_accepts_a_consistent_pair():
    dl = np.full((3, 10), 2, np.int32)
    dr = np.full((3, 10), 2, np.int32)
    labels = disparity.left_right_check(dl, dr, n_disp=4, tolerance=0)
    assert np.all(labels[:, 2:] == disparity.VALID)
    assert np.all(labels[:, :2] != disparity.VALID)  # x - d falls outside the right view


def test_fill_occluded_takes_background_and_mismatched_takes_similar_colour():
    disp = np.array([[5, 9, 2, 7, 3]], np.float32)
    labels = np.array([[0, 1, 0, 2, 0]], np.uint8)
    image = np.zeros((1, 5, 3), np.uint8)
    image[0, 3] = 200
    image[0, 4] = 190  # the right neighbour is similar in colour
    out = disparity.fill_rejected(disp, labels, image, FillConfig(directions=2))
    assert out.tolist() == [[5, 2, 2, 3, 3]]


def test_fill_with_sixteen_directions_uses_pixels_off_the_row():
    disp = np.full((5, 5), 4.0, np.float32)
    labels = np.zeros((5, 5), np.uint8)
    labels[2, :] = disparity.OCCLUDED  # the whole row rejected: only other rows help
    disp[1, :] = 3.0
    out = disparity.fill_rejected(disp, labels, np.zeros((5, 5, 3), np.uint8),
                                  FillConfig(directions=16))
    assert np.all(out[2] == 3.0)
    out2 = disparity.fill_rejected(disp, labels, np.zeros((5, 5, 3), np.uint8),
                                   FillConfig(directions=2))
    assert np.all(np.isinf(out2[2]))  # nothing valid along the row


@pytest.mark.parametrize("count", [2, 8, 16])
def test_search_directions_are_distinct_unit_steps(count):
    dy, dx = disparity.search_directions(count)
    assert len(set(zip(np.round(dy, 6), np.round(dx, 6)))) == count
    np.testing.assert_allclose(np.maximum(np.abs(dy), np.abs(dx)), 1.0)


@pytest.mark.parametrize("directions", [2, 8, 16])
def test_fill_matches_reference(rng, directions):
    disp = rng.integers(0, 9, size=(10, 13)).astype(np.float32)
    labels = rng.choice([0, 0, 0, 1, 2], size=(10, 13)).astype(np.uint8)
    image = rng.integers(0, 256, size=(10, 13, 3), dtype=np.uint8)
    cfg = FillConfig(directions=directions, max_search=6)
    steps_y, steps_x = disparity.search_directions(directions)
    np.testing.assert_array_equal(disparity.fill_rejected(disp, labels, image, cfg),
                                  reference.fill(disp, labels, image, steps_y, steps_x, 6))
