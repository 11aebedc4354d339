"""Adapting the method to image noise: estimate its level, then loosen what noise breaks.

Under noise, neighbouring pixels differ by more than the arm thresholds, so the support
regions collapse to single pixels and aggregation stops working; census bits flip in flat
regions; the colour-dependent scanline penalties switch off. :func:`adapt_to_noise` widens
the colour thresholds, softens the cost mappings and smooths both views in proportion to
how far the estimated noise exceeds a floor, so a pair whose estimate stays under the floor
is matched exactly as without it.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from ._kernels.noise import noise_block_means
from .config import Config
from .images import grey_levels, to_grey

# Immerkaer's operator: the difference of two Laplacians, blind to planes and ramps.
_NOISE_KERNEL = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)


# A low percentile of block estimates reads low on pure noise; this ratio (measured on
# white Gaussian noise of sigma 3 to 20, 8x8 blocks, 2nd percentile: 0.69-0.71) undoes it.
_PERCENTILE_BIAS = 0.70


def estimate_noise(image: np.ndarray, *, block: int = 8, percentile: float = 2.0) -> float:
    """Standard deviation of additive noise in the grey levels of ``image`` (0..255 scale).

    J. Immerkaer, "Fast noise variance estimation", CVIU 1996, taken block by block: a low
    ``percentile`` of the ``block`` x ``block`` estimates, divided by its bias on pure noise.
    Noise is in every block, texture and edges only in some, so the flattest blocks read
    the noise and not the texture (clean Middlebury views read at most 3.3 this way, the
    same views with 2 % noise at least 3.5).
    """
    rows, columns = ((n - 2) // block for n in image.shape[:2])
    if rows > 0 and columns > 0:
        # The operator's responses summed block by block as they are worked out.
        means = np.empty((rows, columns), np.float32)
        noise_block_means(np.ascontiguousarray(grey_levels(image)), block, means)
    else:  # smaller than a block: the mean response
        response = np.abs(cv2.filter2D(to_grey(image), -1, _NOISE_KERNEL))[1:-1, 1:-1]
        means = np.array([response.mean()]) if response.size else np.zeros(1)
    return float(np.sqrt(np.pi / 2.0) * np.percentile(means, percentile) / 6.0
                 / _PERCENTILE_BIAS)


def smoothed_noise_factor(sigma: float) -> float:
    """How much a Gaussian blur of ``sigma`` (as :func:`vsmatch.sensitivity.presmooth` does
    it on 8-bit images) scales the standard deviation of white noise: the root of the sum
    of the squared 2-D kernel weights, which is the sum of the squared 1-D weights."""
    if sigma <= 0:
        return 1.0
    size = int(round(sigma * 3 * 2 + 1)) | 1  # OpenCV's kernel size for 8-bit images
    weights = cv2.getGaussianKernel(size, sigma, cv2.CV_64F)[:, 0]
    return float(np.sum(weights ** 2))


#: How one pyramid level down (``cv2.pyrDown``: the 5 x 5 Gaussian of weights 1 4 6 4 1
#: over 16 a row and a column, every other pixel kept) scales white noise's deviation:
#: the root of the sum of the squared 2-D weights, (1 + 16 + 36 + 16 + 1) / 256.
LEVEL_NOISE_FACTOR = 70 / 256


def estimate_pair_noise(left: np.ndarray, right: np.ndarray) -> float:
    """The noise of a pair: the mean of its two views' estimates."""
    return 0.5 * (estimate_noise(left) + estimate_noise(right))


def adapt_to_noise(cfg: Config, sigma: float) -> Config:
    """``cfg`` with its noise-sensitive values changed for an estimated noise ``sigma``.

    Nothing changes while ``sigma <= noise.floor``; above it the changes fade in over
    ``noise.ramp`` grey levels (``gain`` from 0 to 1). Both views are first smoothed by a
    Gaussian of sigma ``gain * noise.smooth_per_sigma * sigma`` (added to
    ``cost.presmooth_sigma``). The noise left after that, ``residual`` (``sigma`` scaled by
    :func:`smoothed_noise_factor`), sets the rest: ``gain * noise.tau_per_sigma * residual``
    grey levels are added to every colour threshold (arm tau1-3, scanline tau, the census's
    like neighbours' ``cost.census_like`` where it is on) and to the
    colour-difference lambda, since noise spreads every colour difference by the same
    amount whatever the threshold; the census and gradient lambdas are multiplied by
    ``1 + gain * noise.lambda_per_sigma * residual``, and the census dead band grows by
    ``gain * noise.band_per_sigma * residual``. With ``noise.arms_l2`` set, the longest
    arm moves from ``arms.l2`` towards it by ``gain``; once ``gain`` reaches one half, the
    sub-pixel fit becomes ``noise.subpixel_fit`` (unless "same") and the planes stay on only
    with ``noise.planes``.
    """
    n = cfg.noise
    if not n.adapt or sigma <= n.floor:
        return cfg
    gain = min(1.0, (sigma - n.floor) / n.ramp)
    smooth = cfg.cost.presmooth_sigma + gain * n.smooth_per_sigma * sigma
    residual = sigma * smoothed_noise_factor(smooth)
    widen = gain * n.tau_per_sigma * residual
    grow_lambda = 1.0 + gain * n.lambda_per_sigma * residual
    c, a = cfg.cost, cfg.arms
    cost = dataclasses.replace(
        c,
        lambda_census=c.lambda_census * grow_lambda,
        lambda_gradient=None if c.lambda_gradient is None else c.lambda_gradient * grow_lambda,
        lambda_ad=None if c.lambda_ad is None else c.lambda_ad + widen,
        census_band=c.census_band + gain * n.band_per_sigma * residual,
        census_like=c.census_like + widen if c.census_like > 0 else 0.0,
        presmooth_sigma=smooth)
    l2 = a.l2 if n.arms_l2 == 0 else int(round(a.l2 + gain * (n.arms_l2 - a.l2)))
    arms = dataclasses.replace(a, tau1=a.tau1 + widen, tau2=a.tau2 + widen,
                               tau3=a.tau3 + widen, l2=l2)
    scanline = dataclasses.replace(cfg.scanline, tau=cfg.scanline.tau + widen)
    cfg = dataclasses.replace(cfg, cost=cost, arms=arms, scanline=scanline)
    if gain >= 0.5:  # the switches of noisy views, once the changes are half faded in
        if n.subpixel_fit != "same":
            cfg = dataclasses.replace(cfg, subpixel=dataclasses.replace(
                cfg.subpixel, fit=n.subpixel_fit))
        if not n.planes:
            cfg = dataclasses.replace(cfg, planes=dataclasses.replace(cfg.planes,
                                                                      enabled=False))
    return cfg
