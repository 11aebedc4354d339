import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS
from .census import popcount64


@njit(**KERNEL_OPTIONS)
def matching_cost_volume(census_l, census_r, grad_l, grad_r, colour_l, colour_r,
                         census_table, inv_lambda_grad, inv_lambda_ad, max_cost, out):
    """C(p, d) = rho(Hamming) + rho(|G_L - G_R|) [+ rho(mean |I_L - I_R|)], layout (H, W, D).

    ``census_table[k]`` holds rho(k, lambda_s) for k set bits. A term whose inverse lambda
    is negative is off. Where x - d < 0 the cost is ``max_cost``.
    """
    height, width, n_disp = out.shape
    use_grad = inv_lambda_grad >= 0.0
    use_ad = inv_lambda_ad >= 0.0
    channels = colour_l.shape[2]
    for y in prange(height):
        for x in range(width):
            cl = census_l[y, x]
            gl = grad_l[y, x]
            for d in range(n_disp):
                xr = x - d
                if xr < 0:
                    out[y, x, d] = max_cost
                    continue
                c = census_table[popcount64(cl ^ census_r[y, xr])]
                if use_grad:
                    c += 1.0 - np.exp(-abs(gl - grad_r[y, xr]) * inv_lambda_grad)
                if use_ad:
                    s = 0.0
                    for k in range(channels):
                        s += abs(np.float32(colour_l[y, x, k]) - np.float32(colour_r[y, xr, k]))
                    c += 1.0 - np.exp(-(s / channels) * inv_lambda_ad)
                out[y, x, d] = c
