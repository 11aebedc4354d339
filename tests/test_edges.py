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


def _weighed_by_python(disp, left, right, cfg):
    """:func:`weigh_edges`' disparities written out pixel by pixel, one window pixel at a
    time, as the method states them (the reference the kernel's vector loops must equal)."""
    from vsmatch.edges import SOBEL_GAIN
    from vsmatch.images import as_channels, grey_levels
    from vsmatch.sensitivity import sobel, texture

    left, right = as_channels(left).astype(np.float64), as_channels(right).astype(np.float64)
    grad_l = sobel(grey_levels(as_channels(left.astype(np.uint8)).squeeze()))[0] / SOBEL_GAIN
    grad_r = sobel(grey_levels(as_channels(right.astype(np.uint8)).squeeze()))[0] / SOBEL_GAIN
    skip = texture(grey_levels(as_channels(left.astype(np.uint8)).squeeze())) < cfg.min_texture
    height, width, channels = left.shape
    radius = cfg.radius
    out = disp.copy()
    for y in range(height):
        for x in range(width):
            own = float(disp[y, x])
            if not np.isfinite(own) or skip[y, x]:
                continue
            candidates = [own]
            for side in (-1, 1):
                for k in range(1, cfg.reach + 1):
                    nx = x + side * k
                    if not 0 <= nx < width:
                        break
                    if np.isfinite(disp[y, nx]) and disp[y, nx] < own - cfg.jump:
                        candidates.append(float(disp[y, nx]))
                        break
            if len(candidates) == 1:
                continue
            totals, weights = [0.0] * len(candidates), 0.0
            for qy in range(max(0, y - radius), min(height, y + radius + 1)):
                for qx in range(max(0, x - radius), min(width, x + radius + 1)):
                    if qx - own < 0 or qx - min(candidates) > width - 1:
                        continue
                    similar = np.abs(left[y, x] - left[qy, qx]).sum()
                    w = (np.exp(-np.arange(255 * channels + 1) / channels
                                / cfg.colour_scale)[int(similar)]
                         * np.exp(-np.arange(2 * radius + 1) / cfg.distance_scale)[
                             abs(qx - x) + abs(qy - y)])
                    weights += w
                    for c, d in enumerate(candidates):
                        x0 = int(np.floor(qx - d))
                        f = (qx - d) - x0
                        x1 = min(x0 + 1, width - 1)
                        colour = 0.0
                        for ch in range(channels):
                            colour += abs(left[qy, qx, ch] - ((1.0 - f) * right[qy, x0, ch]
                                                              + f * right[qy, x1, ch]))
                        colour = min(colour / channels, cfg.colour_cap)
                        shown = (1.0 - f) * grad_r[qy, x0] + f * grad_r[qy, x1]
                        gradient = min(abs(grad_l[qy, qx] - shown), cfg.gradient_cap)
                        totals[c] += w * ((1.0 - cfg.gradient_share) * colour
                                          + cfg.gradient_share * gradient)
            if weights <= 0:
                continue
            best, best_cost = own, totals[0]
            for c in range(1, len(candidates)):
                if totals[c] * (1.0 + cfg.margin) < best_cost:
                    best_cost, best = totals[c] * (1.0 + cfg.margin), candidates[c]
            out[y, x] = best
    return out


def test_the_kernel_weighs_as_the_method_states(rng):
    """The kernel's window rows as vectors, its padded last column and its candidates'
    shifts found once, against the method written out one window pixel at a time: random
    views, sub-pixel disparities with steps (some matching at the right view's last
    column), colour and grey."""
    height, width = 24, 40
    cfg = edges_config()
    left = rng.integers(0, 256, (height, width, 3)).astype(np.uint8)
    right = rng.integers(0, 256, (height, width, 3)).astype(np.uint8)
    disp = (rng.random((height, width)) * 3).astype(np.float32)
    disp[:, 12:20] += 9  # steps back at both ends of a band in front
    disp[:, 30:] += 6
    disp[3, 5] = np.nan
    disp[::2, 36:] = 0.0  # matched at the same column: the last one's reads the padding
    for views in ((left, right), (left[:, :, 0].copy(), right[:, :, 0].copy())):
        for margin in (cfg.margin, 0.0):  # without the margin, more pixels move
            changed = dataclasses.replace(cfg, margin=margin)
            got, _ = weigh_edges(disp, np.ones(disp.shape, np.float32), *views, changed)
            expected = _weighed_by_python(disp, *views, changed)
            assert (got != disp).sum() >= 5  # the test weighs steps, and some move
            np.testing.assert_array_equal(got, expected.astype(np.float32))
