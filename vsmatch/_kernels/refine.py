import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS
from .arms import DOWN, LEFT, RIGHT, UP
from .disparity import VALID
from .rows import BLOCK_ROWS, dealt


@njit(**KERNEL_OPTIONS)
def vote_runs(disp, labels, votes, run_end):
    """Runs along each row for :func:`region_vote`: ``votes[y, x]`` is the disparity a
    pixel votes for (-1: none, it is not VALID) and ``run_end[y, x]`` the column after the
    last of the run of equal votes that holds (y, x)."""
    height, width = disp.shape
    for y in prange(height):
        for x in range(width):
            votes[y, x] = disp[y, x] if labels[y, x] == VALID else -1
        run_end[y, width - 1] = width
        for x in range(width - 2, -1, -1):
            run_end[y, x] = run_end[y, x + 1] if votes[y, x] == votes[y, x + 1] else x + 1


@njit(inline="always")
def _count_run(votes, run_end, hist, yy, xx, stop):
    """The run of row ``yy`` that holds column ``xx``, cut at ``stop``, into ``hist``;
    returns the column after it and how many pixels voted."""
    end = min(np.uint64(run_end[yy, xx]), stop)
    vote = votes[yy, xx]
    if vote < 0:
        return end, np.int64(0)
    hist[np.uint64(vote)] += np.int64(end - xx)
    return end, np.int64(end - xx)


@njit(inline="always")
def _count_runs(votes, run_end, hist, yy, xx, stop):
    """The runs of row ``yy`` from column ``xx`` to ``stop`` (excluded) into ``hist``;
    returns how many pixels voted."""
    total = np.int64(0)
    while xx < stop:
        xx, voted = _count_run(votes, run_end, hist, yy, xx, stop)
        total += voted
    return total


@njit(**ROW_OPTIONS)
def _region_vote_of_row(disp, labels, votes, run_end, arms, n_disp, min_votes, min_share,
                        classes, out_disp, out_labels, height, width, n_blocks, block):
    """:func:`region_vote` of the rows of block ``block`` (the ``dealt`` one)."""
    top = dealt(block, n_blocks, classes) * BLOCK_ROWS
    hist = np.zeros(n_disp, dtype=np.int32)
    for y in range(top, min(height, top + BLOCK_ROWS)):
        for x in range(width):
            out_disp[y, x] = disp[y, x]
            out_labels[y, x] = labels[y, x]
            if labels[y, x] == VALID:
                continue
            hist[:] = 0
            total = 0
            # Unsigned indexes: Numba tests a signed one for a negative value, a branch in
            # every look-up. Two rows' runs walked side by side: each run's end is read at
            # the last one's, a chain of loads a row, and two chains keep twice the loads
            # in flight (the counts are whole numbers: the same in any order).
            first = np.uint64(y - np.int64(arms[UP, y, x]))
            last = np.uint64(y + np.int64(arms[DOWN, y, x]))
            for pair in range((last - first + np.uint64(1)) // np.uint64(2)):
                ya = first + np.uint64(2) * np.uint64(pair)
                yb = ya + np.uint64(1)
                xa = np.uint64(x - np.int64(arms[LEFT, ya, x]))
                stop_a = np.uint64(x + np.int64(arms[RIGHT, ya, x]) + 1)
                xb = np.uint64(x - np.int64(arms[LEFT, yb, x]))
                stop_b = np.uint64(x + np.int64(arms[RIGHT, yb, x]) + 1)
                while xa < stop_a and xb < stop_b:
                    xa, voted_a = _count_run(votes, run_end, hist, ya, xa, stop_a)
                    xb, voted_b = _count_run(votes, run_end, hist, yb, xb, stop_b)
                    total += voted_a + voted_b
                total += _count_runs(votes, run_end, hist, ya, xa, stop_a)
                total += _count_runs(votes, run_end, hist, yb, xb, stop_b)
            if (last - first) % np.uint64(2) == np.uint64(0):  # an odd count: the last alone
                yy = last
                total += _count_runs(votes, run_end, hist, yy,
                                     np.uint64(x - np.int64(arms[LEFT, yy, x])),
                                     np.uint64(x + np.int64(arms[RIGHT, yy, x]) + 1))
            if total <= min_votes:
                continue
            # The first of the largest counts: the largest first, in a loop that vectorises.
            most = hist[0]
            for d in range(1, n_disp):
                most = hist[d] if hist[d] > most else most
            best = 0
            while hist[best] != most:
                best += 1
            if hist[best] > min_share * total:
                out_disp[y, x] = best
                out_labels[y, x] = VALID


@njit(**KERNEL_OPTIONS)
def region_vote(disp, labels, votes, run_end, arms, n_disp, min_votes, min_share, classes,
                out_disp, out_labels):
    """One round of region voting (Mei et al. 2011).

    A rejected pixel takes the most frequent disparity among the VALID pixels of its cross
    support region (its vertical arm, then each of those pixels' horizontal arms) when more
    than ``min_votes`` pixels vote and the winner's share exceeds ``min_share``; it then
    becomes VALID. Each row segment is counted run by run (:func:`vote_runs`), not pixel
    by pixel. Reads the inputs only, so the result is the same on any thread count.
    """
    height, width = disp.shape
    # Blocks of rows dealt out: only rejected pixels vote, and they gather (occlusions).
    n_blocks = (height + BLOCK_ROWS - 1) // BLOCK_ROWS
    for block in prange(n_blocks):
        _region_vote_of_row(disp, labels, votes, run_end, arms, n_disp, min_votes, min_share,
                            classes, out_disp, out_labels, height, width, n_blocks,
                            np.int64(block))


@njit(**ROW_OPTIONS)
def _adjust_row(disp, volume, lo, count, jump, out, y):
    """:func:`discontinuity_adjust` of row ``y``."""
    width = disp.shape[1]
    for x in range(width):
        d = disp[y, x]
        out[y, x] = d
        if not np.isfinite(d):
            continue
        base = np.int64(lo[y, x])
        n = np.int64(count[y, x])
        k = np.int64(d) - base
        if k < 0 or k >= n:
            continue
        best_cost = volume[y, x, k]
        for nx in (x - 1, x + 1):
            if nx < 0 or nx >= width:
                continue
            nd = disp[y, nx]
            kn = np.int64(nd) - base if np.isfinite(nd) else np.int64(-1)
            if np.isfinite(nd) and abs(nd - d) > jump and 0 <= kn < n:
                c = volume[y, x, kn]
                if c < best_cost:
                    best_cost = c
                    out[y, x] = nd


@njit(**KERNEL_OPTIONS)
def discontinuity_adjust(disp, volume, lo, count, jump, out):
    """On pixels where the disparity jumps by more than ``jump`` to a horizontal neighbour,
    take the neighbour's disparity if its matching cost at this pixel is lower (both
    disparities in the pixel's band ``lo .. lo + count - 1``, the volume's candidates)."""
    height = disp.shape[0]
    for y in prange(height):
        _adjust_row(disp, volume, lo, count, jump, out, np.int64(y))


#: Sub-pixel fits: none, a parabola, or the equiangular (symmetric V) fit, which suits
#: costs that grow linearly away from their minimum (census) and locks less to pixels.
FIT_NONE, FIT_PARABOLA, FIT_EQUIANGULAR, FIT_BLEND = 0, 1, 2, 3


@njit(inline="always")
def subpixel_offset(c0, c1, c2, fit):
    """The minimum's offset from d given the costs at d - 1, d, d + 1, within +-0.5; 0
    where the curve is flat there. ``FIT_BLEND``: the mean of the two fits."""
    parabola = 0.0
    denom = c0 + c2 - 2.0 * c1
    if denom > 1e-9:
        parabola = min(0.5, max(-0.5, (c0 - c2) / (2.0 * denom)))
    equiangular = 0.0
    rise = max(c0, c2) - c1
    if rise > 1e-9:
        equiangular = min(0.5, max(-0.5, (c0 - c2) / (2.0 * rise)))
    if fit == FIT_PARABOLA:
        return parabola
    if fit == FIT_EQUIANGULAR:
        return equiangular
    if fit == FIT_BLEND:
        return 0.5 * (parabola + equiangular)
    return 0.0


@njit(**ROW_OPTIONS)
def _subpixel_row(disp, volume, lo, count, fit, out, y):
    """:func:`subpixel_fit` of row ``y``."""
    width = disp.shape[1]
    for x in range(width):
        d = disp[y, x]
        out[y, x] = d
        if not np.isfinite(d):
            continue
        base = np.int64(lo[y, x])
        k = np.int64(d) - base
        if k <= 0 or k >= np.int64(count[y, x]) - 1:
            continue
        out[y, x] = base + k + subpixel_offset(volume[y, x, k - 1], volume[y, x, k],
                                               volume[y, x, k + 1], fit)


@njit(**KERNEL_OPTIONS)
def subpixel_fit(disp, volume, lo, count, fit, out):
    """``disp`` moved to the minimum of the fit (:func:`subpixel_offset`) through the costs
    at d - 1, d, d + 1 of each pixel's integer disparity d, where all three are in its
    band (``lo``, ``count``: the volume's candidates)."""
    height = volume.shape[0]
    for y in prange(height):
        _subpixel_row(disp, volume, lo, count, fit, out, np.int64(y))
