from numba import njit, prange

from . import KERNEL_OPTIONS
from .census import popcount64


@njit(**KERNEL_OPTIONS)
def matching_cost_volume(census_l, census_r, grad_l, grad_r, colour_l, colour_r,
                         census_table, grad_table, ad_table, max_cost, out):
    """C(p, d) = rho(Hamming) + rho(|G_L - G_R|) [+ rho(mean |I_L - I_R|)], layout (H, W, D).

    Every term is a table lookup: ``census_table[k]`` for k differing bits,
    ``grad_table[|g_L - g_R|]`` on gradients quantised to integers, ``ad_table[s]`` for the
    sum s of the channels' absolute differences. An empty table switches its term off.
    Where x - d < 0 the cost is ``max_cost``.
    """
    height, width, n_disp = out.shape
    use_grad = grad_table.shape[0] > 0
    use_ad = ad_table.shape[0] > 0
    channels = colour_l.shape[2]
    for y in prange(height):
        for x in range(width):
            cl = census_l[y, x]
            gl = grad_l[y, x]
            last = min(n_disp, x + 1)
            for d in range(last):
                xr = x - d
                c = census_table[popcount64(cl ^ census_r[y, xr])]
                if use_grad:
                    c += grad_table[abs(gl - grad_r[y, xr])]
                if use_ad:
                    if channels == 3:  # written out: the common case, and the hot one
                        s = (abs(colour_l[y, x, 0] - colour_r[y, xr, 0])
                             + abs(colour_l[y, x, 1] - colour_r[y, xr, 1])
                             + abs(colour_l[y, x, 2] - colour_r[y, xr, 2]))
                    else:
                        s = 0
                        for k in range(channels):
                            s += abs(colour_l[y, x, k] - colour_r[y, xr, k])
                    c += ad_table[s]
                out[y, x, d] = c
            for d in range(last, n_disp):
                out[y, x, d] = max_cost
