"""Depth edges decided again by adaptive support weights (vsmatch.edges)."""

import dataclasses

import numpy as np

from vsmatch.config import load_config
from vsmatch.edges import weigh_edges

#: The synthetic scene: a textured square (columns FRONT_FROM .. FRONT_TO, disparity FRONT)
#: before a textured wall (disparity BACK), the square brighter than the wall.
HEIGHT, WIDTH, BACK, FRONT, FRONT_FROM, FRONT_TO = 60, 120, 4, 10, 40, 80


def square_before_wall(rng):
    """The views and the true left disparity: left x shows the square where it lies in
    FRONT_FROM .. FRONT_TO, else the wall; right x shows what left x + disparity shows."""
    wall = rng.integers(0, 120, (HEIGHT, WIDTH + FRONT, 3)).astype(np.uint8)
    square = rng.integers(130, 256, (HEIGHT, WIDTH + FRONT, 3)).astype(np.uint8)
    xs = np.arange(WIDTH)
    in_front = (xs >= FRONT_FROM) & (xs < FRONT_TO)
    left = np.where(in_front[None, :, None], square[:, :WIDTH], wall[:, :WIDTH])
    seen_front = (xs + FRONT >= FRONT_FROM) & (xs + FRONT < FRONT_TO)
    right = np.where(seen_front[None, :, None], square[:, FRONT:WIDTH + FRONT],
                     wall[:, BACK:WIDTH + BACK])
    truth = np.where(in_front, FRONT, BACK).astype(np.float32)[None, :].repeat(HEIGHT, 0)
    return np.ascontiguousarray(left), np.ascontiguousarray(right), truth


def edges_config():
    return dataclasses.replace(load_config("accurate").edges, enabled=True)


def test_a_surface_spilt_past_its_edge_goes_back_to_the_wall_behind(rng):
    left, right, truth = square_before_wall(rng)
    spilt = truth.copy()
    spilt[:, FRONT_TO:FRONT_TO + 3] = FRONT  # the square's disparity 3 px onto the wall
    confidence = np.full(truth.shape, 0.9, np.float32)
    disp, conf = weigh_edges(spilt, confidence, left, right, edges_config())
    rows = slice(10, HEIGHT - 10)  # away from the window's cut at the top and bottom
    np.testing.assert_array_equal(disp[rows, FRONT_TO:FRONT_TO + 3], BACK)
    # The square's own pixels stay, up to its edge.
    np.testing.assert_array_equal(disp[:, FRONT_FROM + 6:FRONT_TO], FRONT)
    moved = disp != spilt
    assert moved.any()
    assert np.all(conf[moved] == np.float32(edges_config().moved_confidence))
    assert np.all(conf[~moved] == np.float32(0.9))


def test_only_steps_back_are_taken(rng):
    """A pixel is moved onto the surface behind it, never onto one in front: the square's
    edge pixels given the wall's disparity stay so."""
    left, right, truth = square_before_wall(rng)
    shrunk = truth.copy()
    shrunk[:, FRONT_TO - 3:FRONT_TO] = BACK
    disp, _ = weigh_edges(shrunk, np.ones(truth.shape, np.float32), left, right,
                          edges_config())
    np.testing.assert_array_equal(disp[:, FRONT_TO - 3:FRONT_TO], BACK)


def test_a_view_without_texture_is_left_as_it_is(rng):
    left, right, truth = square_before_wall(rng)
    spilt = truth.copy()
    spilt[:, FRONT_TO:FRONT_TO + 3] = FRONT
    cfg = dataclasses.replace(edges_config(), min_texture=1e4)  # nothing has this texture
    disp, _ = weigh_edges(spilt, np.ones(truth.shape, np.float32), left, right, cfg)
    np.testing.assert_array_equal(disp, spilt)


def test_grey_views_and_invalid_pixels(rng):
    left, right, truth = square_before_wall(rng)
    grey_l, grey_r = left[:, :, 1].copy(), right[:, :, 1].copy()
    spilt = truth.copy()
    spilt[:, FRONT_TO:FRONT_TO + 3] = FRONT
    spilt[:5] = np.nan
    disp, _ = weigh_edges(spilt, np.ones(truth.shape, np.float32), grey_l, grey_r,
                          edges_config())
    assert np.all(np.isnan(disp[:5]))
    np.testing.assert_array_equal(disp[10:-10, FRONT_TO:FRONT_TO + 3], BACK)


def test_blocks_of_rows_give_the_same_bytes_as_one_piece(rng, monkeypatch):
    from vsmatch import edges

    left, right, truth = square_before_wall(rng)
    spilt = truth + rng.normal(0, 1.5, truth.shape).astype(np.float32)  # steps everywhere
    spilt[:, FRONT_TO:FRONT_TO + 3] = FRONT
    confidence = np.ones(truth.shape, np.float32)
    whole = weigh_edges(spilt, confidence, left, right, edges_config())
    monkeypatch.setattr(edges, "EDGE_ROWS", 7)
    blocks = weigh_edges(spilt, confidence, left, right, edges_config())
    assert (whole[0] != spilt).any()
    assert whole[0].tobytes() == blocks[0].tobytes()
    assert whole[1].tobytes() == blocks[1].tobytes()
