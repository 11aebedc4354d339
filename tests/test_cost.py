import numpy as np
import pytest

from vsmatch import cost, sensitivity
from vsmatch._kernels.census import popcount64
from vsmatch.config import CostConfig

import reference


# Windows whose neighbours fill the kernel's passes of eight whole (3 x 3), leave a rest
# (9 x 7: 62 = 7 x 8 + 6; 5 x 7, fast's full search: 4 x 8 + 2), or only a rest (1 x 3).
@pytest.mark.parametrize("width,height,band", [(9, 7, 0.0), (3, 3, 0.0), (5, 9, 0.0),
                                               (5, 7, 0.0), (1, 3, 0.0), (9, 7, 1.5)])
def test_census_matches_reference(rng, width, height, band):
    grey = rng.integers(0, 8, size=(11, 13)).astype(np.float32)  # many ties
    got = cost.census_transform(grey, width=width, height=height, band=band)
    assert got.dtype == np.uint64
    np.testing.assert_array_equal(got, reference.census(grey, width // 2, height // 2, band))


def test_census_rejects_even_or_too_large_window():
    with pytest.raises(ValueError, match="census window"):
        cost.census_transform(np.zeros((5, 5), np.float32), width=4, height=3)
    with pytest.raises(ValueError, match="census window"):
        cost.census_transform(np.zeros((5, 5), np.float32), width=11, height=7)


def test_popcount_counts_bits(rng):
    from numba import njit

    count = njit(lambda v: popcount64(v))
    values = rng.integers(0, 2**63, size=50, dtype=np.uint64)
    for v in list(values) + [np.uint64(0), np.uint64(2**64 - 1)]:
        assert count(np.uint64(v)) == bin(int(v)).count("1")


@pytest.mark.parametrize("lam_g,lam_ad", [(None, None), (20.0, None), (20.0, 10.0)])
def test_cost_volume_matches_reference(rng, lam_g, lam_ad):
    left = rng.integers(0, 256, size=(9, 12, 3), dtype=np.uint8)
    right = rng.integers(0, 256, size=(9, 12, 3), dtype=np.uint8)
    gl, gr = (rng.random((9, 12), dtype=np.float32) * 100 for _ in range(2))
    cl = cost.census_transform(left[..., 0].astype(np.float32))
    cr = cost.census_transform(right[..., 0].astype(np.float32))
    cfg = CostConfig(lambda_census=15.0, lambda_gradient=lam_g, lambda_ad=lam_ad)
    got = cost.cost_volume(left, right, cl, cr, gl, gr, n_disp=5, cfg=cfg)
    assert got.shape == (9, 12, 5) and got.dtype == np.float32
    # The gradient term is looked up on gradients quantised to 1/GRADIENT_STEPS.
    q = cost.GRADIENT_STEPS
    gl_q, gr_q = np.round(gl * q) / q, np.round(gr * q) / q
    want = reference.cost_volume(cl, cr, gl_q, gr_q, left, right, 5, 15.0, lam_g, lam_ad)
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6)
    exact = reference.cost_volume(cl, cr, gl, gr, left, right, 5, 15.0, lam_g, lam_ad)
    if lam_g is not None:  # quantisation moves a gradient difference by at most 1/q
        assert np.abs(got - exact).max() <= (1.0 / q) / lam_g + 1e-6
    assert np.all(got[:, 0, 1:] == cost.max_cost(cfg))  # no right pixel: maximum cost


def test_visual_sensitivity_of_a_ramp():
    # Grey rising by 2 per column: Sobel Gx = (1 + 2 + 1) * (2 * 2) = 16 inside, Gy = 0.
    grey = np.tile(np.arange(10, dtype=np.float32) * 2, (6, 1))
    g, theta = sensitivity.visual_sensitivity(grey)
    np.testing.assert_allclose(g[1:-1, 1:-1], 16.0)
    np.testing.assert_allclose(theta[1:-1, 1:-1], 0.0, atol=1e-6)
    g, theta = sensitivity.visual_sensitivity(-grey.T.copy())  # falling downwards
    np.testing.assert_allclose(theta[1:-1, 1:-1], -np.pi / 2, atol=1e-6)


@pytest.mark.parametrize("shape", [(1, 1), (1, 7), (6, 1), (2, 2), (23, 31)])
def test_the_gradient_magnitude_is_opencvs_sobel_on_grey_levels(rng, shape):
    # The magnitude alone comes from a kernel of its own: on whole numbers, cv2.Sobel's
    # values to the bit, the mirrored borders (1-pixel sides too) included.
    grey = rng.integers(0, 256, size=shape).astype(np.float32)
    magnitude, theta = sensitivity.visual_sensitivity(grey, direction=False)
    gx, gy = sensitivity.sobel(grey)
    assert theta is None and magnitude.dtype == np.float32
    np.testing.assert_array_equal(magnitude, np.sqrt(gx * gx + gy * gy))
    np.testing.assert_array_equal(sensitivity.visual_sensitivity(grey)[0], magnitude)


def test_presmooth_zero_is_identity(rng):
    grey = rng.random((8, 8), dtype=np.float32)
    assert sensitivity.presmooth(grey, 0.0) is grey
    assert not np.array_equal(sensitivity.presmooth(grey, 1.0), grey)


def test_texture_is_eight_for_a_gradient_of_one_grey_level_a_pixel():
    ramp = np.tile(np.arange(64, dtype=np.float32), (16, 1))
    inside = sensitivity.texture(ramp)[4:-4, 4:-4]
    assert np.allclose(inside, 8.0)
    assert np.all(sensitivity.texture(np.full((16, 16), 77, np.float32)) == 0)


def _like_reference(colour, half_w, half_h, threshold):
    """Each pixel's like neighbours in the census's bit order, directly."""
    rows, cols = colour.shape[:2]
    padded = np.pad(colour.astype(int), ((half_h, half_h), (half_w, half_w), (0, 0)),
                    mode="edge")
    out = np.zeros((rows, cols), np.uint64)
    for y in range(rows):
        for x in range(cols):
            bits = 0
            for dy in range(2 * half_h + 1):
                for dx in range(2 * half_w + 1):
                    if (dy, dx) == (half_h, half_w):
                        continue
                    near = np.abs(padded[y + dy, x + dx] - padded[y + half_h, x + half_w])
                    bits = (bits << 1) | int(near.max() <= threshold)
            out[y, x] = bits
    return out


@pytest.mark.parametrize("channels", [1, 3])
def test_like_masks_match_reference(rng, channels):
    colour = rng.integers(0, 60, size=(8, 11, channels), dtype=np.uint8)
    cfg = CostConfig(census_width=5, census_height=3, census_like=20)
    view = colour if channels == 3 else colour[..., 0]
    np.testing.assert_array_equal(cost.like_masks(view, cfg),
                                  _like_reference(colour, 2, 1, 20))


@pytest.mark.parametrize("lam_ad", [None, 10.0])
def test_census_over_like_neighbours_is_the_smaller_of_the_two_counts(rng, lam_ad):
    """With ``cost.census_like`` the census term is that of the smaller of the plain
    Hamming distance and the distance over the left pixel's like neighbours scaled to the
    whole window; a threshold every neighbour meets gives the plain census."""
    left = rng.integers(0, 256, size=(9, 14, 3), dtype=np.uint8)
    left[:, 7:] //= 6  # a dark half: its neighbours like each other
    right = np.roll(left, -2, axis=1)
    gl, gr = (rng.random((9, 14), dtype=np.float32) * 100 for _ in range(2))
    cl = cost.census_transform(left[..., 0].astype(np.float32))
    cr = cost.census_transform(right[..., 0].astype(np.float32))
    plain_cfg = CostConfig(lambda_census=15.0, lambda_gradient=20.0, lambda_ad=lam_ad)
    like_cfg = CostConfig(lambda_census=15.0, lambda_gradient=20.0, lambda_ad=lam_ad,
                          census_like=30)
    plain = cost.cost_volume(left, right, cl, cr, gl, gr, n_disp=5, cfg=plain_cfg)
    got = cost.cost_volume(left, right, cl, cr, gl, gr, n_disp=5, cfg=like_cfg)
    mask = _like_reference(left, 4, 3, 30)
    n_bits = 62
    want = plain.copy()
    for y in range(9):
        for x in range(14):
            like = bin(int(mask[y, x])).count("1")
            for d in range(min(5, x + 1)):
                differing = int(cl[y, x]) ^ int(cr[y, x - d])
                counted = bin(differing & int(mask[y, x])).count("1")
                hamming = bin(differing).count("1")
                scaled = counted * n_bits / like if like else hamming
                want[y, x, d] += (cost.rho(min(scaled, hamming), 15.0)
                                  - cost.rho(hamming, 15.0))
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6)
    assert np.any(got < plain - 1e-3)  # the dark half's like counts were the smaller
    everyone = CostConfig(lambda_census=15.0, lambda_gradient=20.0, lambda_ad=lam_ad,
                          census_like=255)
    np.testing.assert_array_equal(
        cost.cost_volume(left, right, cl, cr, gl, gr, n_disp=5, cfg=everyone), plain)
