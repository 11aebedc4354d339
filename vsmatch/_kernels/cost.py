from numba import njit, prange

from . import KERNEL_OPTIONS
from .census import popcount64


@njit(**KERNEL_OPTIONS)
def matching_cost_volume(census_l, census_r_rev, grad_l, grad_r_rev, colour_l, colour_r_rev,
                         census_table, grad_table, ad_table, max_cost, out):
    """C(p, d) = rho(Hamming) + rho(|G_L - G_R|) [+ rho(mean |I_L - I_R|)], layout (H, W, D).

    Every term is a table lookup: ``census_table[k]`` for k differing bits,
    ``grad_table[|g_L - g_R|]`` on gradients quantised to integers, ``ad_table[s]`` for the
    sum s of the channels' absolute differences. An empty table switches its term off.
    Where x - d < 0 the cost is ``max_cost``. The right view's arrays are reversed along x.
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
            # The right view comes reversed along x: right pixel x - d is at W - 1 - x + d,
            # forward from x's place (and Numba knows these indexes are >= 0).
            start = width - 1 - x
            census_r = census_r_rev[y, start:]
            grad_r = grad_r_rev[y, start:]
            colour_r = colour_r_rev[y, start:]
            costs = out[y, x]
            for d in range(last):
                c = census_table[popcount64(cl ^ census_r[d])]
                if use_grad:
                    c += grad_table[abs(gl - grad_r[d])]
                if use_ad:
                    if channels == 3:  # written out: the common case, and the hot one
                        s = (abs(colour_l[y, x, 0] - colour_r[d, 0])
                             + abs(colour_l[y, x, 1] - colour_r[d, 1])
                             + abs(colour_l[y, x, 2] - colour_r[d, 2]))
                    else:
                        s = 0
                        for k in range(channels):
                            s += abs(colour_l[y, x, k] - colour_r[d, k])
                    c += ad_table[s]
                costs[d] = c
            for d in range(last, n_disp):
                costs[d] = max_cost
