import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS

#: Channels of the moments volume: weight, then weight times u, v, u^2, u v, v^2, d, u d, v d,
#: d^2.
N_MOMENTS = 10


@njit(**KERNEL_OPTIONS)
def plane_moments(disp, weight, out):
    """``out[y, x]`` = w (1, u, v, u^2, u v, v^2, d, u d, v d) with u, v the pixel's
    coordinates from the image centre, w = ``weight[y, x]`` (0 where the disparity is not
    finite)."""
    height, width = disp.shape
    cx = np.float32((width - 1) / 2.0)
    cy = np.float32((height - 1) / 2.0)
    for y in prange(height):
        v = np.float32(y) - cy
        for x in range(width):
            d = disp[y, x]
            w = weight[y, x]
            if not np.isfinite(d) or w <= 0:
                for k in range(10):
                    out[y, x, k] = 0.0
                continue
            u = np.float32(x) - cx
            out[y, x, 0] = w
            out[y, x, 1] = w * u
            out[y, x, 2] = w * v
            out[y, x, 3] = w * u * u
            out[y, x, 4] = w * u * v
            out[y, x, 5] = w * v * v
            out[y, x, 6] = w * d
            out[y, x, 7] = w * u * d
            out[y, x, 8] = w * v * d
            out[y, x, 9] = w * d * d


@njit(**KERNEL_OPTIONS)
def plane_values(means, min_weight, min_spread, out, spread):
    """The least-squares plane d = a u + b v + c through each pixel's support region
    (``means``: the moments averaged over it), evaluated at the pixel, and the standard
    deviation of the region's disparities about it (``spread``); NaN where the region's
    weight is below ``min_weight``. Where its pixels do not span a plane (the variance
    along u or v below ``min_spread``) a constant is fitted along that axis."""
    height, width, _ = means.shape
    cx = (width - 1) / 2.0
    cy = (height - 1) / 2.0
    for y in prange(height):
        v0 = y - cy
        for x in range(width):
            m = means[y, x]
            w = np.float64(m[0])
            if w < min_weight:
                out[y, x] = np.nan
                spread[y, x] = np.nan
                continue
            mu = m[1] / w
            mv = m[2] / w
            md = m[6] / w
            suu = m[3] / w - mu * mu
            suv = m[4] / w - mu * mv
            svv = m[5] / w - mv * mv
            sud = m[7] / w - mu * md
            svd = m[8] / w - mv * md
            a = 0.0
            b = 0.0
            det = suu * svv - suv * suv
            if suu >= min_spread and svv >= min_spread and det > 1e-6 * suu * svv:
                a = (sud * svv - svd * suv) / det
                b = (svd * suu - sud * suv) / det
            elif suu >= min_spread:
                a = sud / suu
            elif svv >= min_spread:
                b = svd / svv
            u0 = x - cx
            out[y, x] = np.float32(md + a * (u0 - mu) + b * (v0 - mv))
            sdd = m[9] / w - md * md
            spread[y, x] = np.float32(np.sqrt(max(sdd - a * sud - b * svd, 0.0)))


@njit(**KERNEL_OPTIONS)
def cut_arms_at_jumps(arms, disp, jump):
    """Shorten each arm (left, right, up, down) to end before the first step of more than
    ``jump`` between the disparities of the kept pixels along it: a support region then
    stays on one surface however alike its colours. Pixels without a kept disparity (NaN:
    rejected by the left-right check) neither end an arm nor count in a step."""
    height, width = disp.shape
    for y in prange(height):
        for x in range(width):
            for a in range(4):
                dx = -1 if a == 0 else (1 if a == 1 else 0)
                dy = -1 if a == 2 else (1 if a == 3 else 0)
                prev = disp[y, x]
                length = 0
                for k in range(1, np.int64(arms[a, y, x]) + 1):
                    d = disp[y + k * dy, x + k * dx]
                    if np.isfinite(d):
                        if np.isfinite(prev) and not (np.abs(d - prev) <= jump):
                            break
                        prev = d
                    length = k
                arms[a, y, x] = length
