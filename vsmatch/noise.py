"""Adapting the method to image noise: estimate its level, then loosen what noise breaks.

Under noise, neighbouring pixels differ by more than the arm thresholds, so the support
regions collapse to single pixels and aggregation stops working; census bits flip in flat
regions; the colour-dependent scanline penalties switch off. :func:`adapt_to_noise` widens
the colour thresholds, softens the cost mappings and smooths both views in proportion to
how far the estimated noise exceeds a floor that clean images stay under, so a clean pair
is matched exactly as without it.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from .config import Config
from .images import to_grey

# Immerkaer's operator: the difference of two Laplacians, blind to planes and ramps.
_NOISE_KERNEL = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)


def estimate_noise(image: np.ndarray) -> float:
    """Standard deviation of additive noise in the grey levels of ``image`` (0..255 scale).

    J. Immerkaer, "Fast noise variance estimation", CVIU 1996, restricted to the half of
    the pixels with the weakest gradient so that texture and edges count less.
    """
    grey = to_grey(image)
    if min(grey.shape) < 3:
        return 0.0
    response = np.abs(cv2.filter2D(grey, -1, _NOISE_KERNEL))[1:-1, 1:-1]
    gx = cv2.Sobel(grey, cv2.CV_32F, 1, 0)[1:-1, 1:-1]
    gy = cv2.Sobel(grey, cv2.CV_32F, 0, 1)[1:-1, 1:-1]
    magnitude = np.hypot(gx, gy)
    flat = response[magnitude <= np.median(magnitude)]
    return float(np.sqrt(np.pi / 2.0) * flat.mean() / 6.0)


def adapt_to_noise(cfg: Config, sigma: float) -> Config:
    """``cfg`` with its noise-sensitive values scaled for an estimated noise ``sigma``.

    With ``excess = max(0, sigma - noise.floor)``: colour thresholds (arm tau1-3, scanline
    tau) and the colour-difference lambda are multiplied by ``1 + noise.tau_per_sigma *
    excess``; the census and gradient lambdas by ``1 + noise.lambda_per_sigma * excess``;
    both views are smoothed by a Gaussian of sigma ``noise.smooth_per_sigma * excess``
    (added to ``cost.presmooth_sigma``).
    """
    n = cfg.noise
    excess = max(0.0, sigma - n.floor)
    if not n.adapt or excess == 0.0:
        return cfg
    grow_tau = 1.0 + n.tau_per_sigma * excess
    grow_lambda = 1.0 + n.lambda_per_sigma * excess
    c, a = cfg.cost, cfg.arms
    cost = dataclasses.replace(
        c,
        lambda_census=c.lambda_census * grow_lambda,
        lambda_gradient=None if c.lambda_gradient is None else c.lambda_gradient * grow_lambda,
        lambda_ad=None if c.lambda_ad is None else c.lambda_ad * grow_tau,
        presmooth_sigma=c.presmooth_sigma + n.smooth_per_sigma * excess)
    arms = dataclasses.replace(a, tau1=a.tau1 * grow_tau, tau2=a.tau2 * grow_tau,
                               tau3=a.tau3 * grow_tau)
    scanline = dataclasses.replace(cfg.scanline, tau=cfg.scanline.tau * grow_tau)
    return dataclasses.replace(cfg, cost=cost, arms=arms, scanline=scanline)
