import numpy as np
from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS
from .lanes import LANES, path_step_chunks_add, path_step_chunks_write, path_step_lanes
from .views import borrowed

# Path costs live in one flat array per walk (``paths``), each pixel's LANES or depth + 2
# of them from a flat index, and the volumes are read by flat index too: a view of a row
# or a pixel in the walk's loop costs two atomic reference counts a step, on a count that
# every thread shares (measured on coarse-to-fine's band kernels, one thread: rows 139 ->
# 51 ms, columns 156 -> 64 ms over four pairs, the same bytes).


@njit(inline="always")
def path_step(paths, at, d, p1, p2_total):
    """The least way into disparity d from the previous pixel's path costs (``paths``
    from flat index ``at``, at 1 + d, infinite at both ends): stay, step by one (+ P1), or
    jump from the previous minimum (``p2_total`` = P2 + that minimum). Selects, not
    ``min``: Numba's NaN-aware ``min`` compiles into branches that stop LLVM vectorising
    the loop."""
    a = paths[at + d]
    b = paths[at + d + 2]
    jump = (a if a < b else b) + p1
    stay = paths[at + d + 1]
    best = stay if stay < p2_total else p2_total
    return best if best < jump else jump


def _path_steps(write, lanes):
    """The two steps of the path recursion, adding ``weight`` x the path cost to ``out``,
    or with ``write`` (a constant to the compiler, so no test is left in the loops, which
    would stop LLVM vectorising them) writing it: the first walk of a volume writes every
    cell, so the volume needs no zeroing beforehand. With ``lanes`` (a constant too) a
    step takes :data:`LANES` candidates, one vector where a narrow band's short loop would
    not vectorise; those from the band's ``n`` on are infinite. ``cost`` and ``out`` are
    the volumes flat, the pixel's candidates from ``at``; ``paths`` the walk's path costs,
    the previous pixel's from ``prev_at``, this one's written from ``cur_at``."""

    @njit(inline="always")
    def keep(paths, cur_at, out, at, d, v, weight):
        """Candidate d's path cost ``v`` into the path costs (at 1 + d) and ``weight`` x
        it into ``out``."""
        paths[cur_at + d + 1] = v
        if write:
            out[at + d] = weight * v
        else:
            out[at + d] += weight * v

    @njit(inline="always")
    def first_step(cost, out, at, paths, cur_at, weight, n):
        """The path starts: its cost is the matching cost. Returns its minimum over d."""
        new_min = np.float32(np.inf)
        for d in range(LANES if lanes else n):
            v = cost[at + d]
            if lanes:
                v = v if d < n else np.float32(np.inf)
            keep(paths, cur_at, out, at, d, v, weight)
            new_min = v if v < new_min else new_min
        return new_min

    @njit(inline="always")
    def next_step(cost, out, at, paths, prev_at, cur_at, change_r, change_at, p1a, p1b, p2a,
                  p2b, prev_min, weight, n):
        """One step of the path recursion over all d; returns the new minimum over d.

        The path costs hold inf at both ends so that d - 1 and d + 1 need no tests.
        ``change_r[change_at + d]`` picks the penalties: (p1a, p2a) where the right image
        does not change at disparity d, (p1b, p2b) where it does. A narrow band
        (``lanes``) takes one vector of LANES, the whole range and wider bands their
        whole vectors (``_kernels.lanes``: the same operations lane by lane) and the rest
        one by one, with ``a if a < b else b`` rather than ``min``, whose NaN handling
        Numba compiles into branches.
        """
        if lanes:
            return path_step_lanes(cost, out, at, paths, prev_at, cur_at, change_r,
                                   change_at, p1a, p1b, p2a, p2b, prev_min, weight, n)
        chunks = n // LANES
        if write:
            new_min = path_step_chunks_write(cost, out, at, paths, prev_at, cur_at, change_r,
                                             change_at, p1a, p1b, p2a, p2b, prev_min, weight,
                                             chunks)
        else:
            new_min = path_step_chunks_add(cost, out, at, paths, prev_at, cur_at, change_r,
                                           change_at, p1a, p1b, p2a, p2b, prev_min, weight,
                                           chunks)
        for d in range(chunks * LANES, n):
            c = change_r[change_at + d]
            v = cost[at + d] + path_step(paths, prev_at, d, p1b if c else p1a,
                                         p2b if c else p2a) - prev_min
            keep(paths, cur_at, out, at, d, v, weight)
            new_min = v if v < new_min else new_min
        return new_min

    return first_step, next_step


@njit(inline="always")
def _rebase(paths, prev_at, tmp, off, n_prev, n):
    """The previous pixel's path costs (``paths`` from ``prev_at``, at 1 + k over its band
    of ``n_prev`` candidates) re-indexed in place to this pixel's band of ``n``, whose
    candidate k is the previous band's k + ``off``: infinite where the previous band has no
    such candidate, for k from -1 to n (all that :func:`path_step` reads)."""
    for j in range(-1, n + 1):
        i = j + off
        tmp[j + 1] = paths[prev_at + i + 1] if 0 <= i < n_prev else np.float32(np.inf)
    for j in range(n + 2):
        paths[prev_at + j] = tmp[j]


def _walk_steps(banded, write):
    """One pixel's step of a path, compiled for bands (``banded``) or for the whole range
    at every pixel, where the band bookkeeping is left out of the loops' way; ``write``:
    the step writes its share of ``out`` rather than adds it. Both are constants to the
    compiler: each kernel holds the steps it takes and no more, which keeps compilation
    short."""
    first_whole, next_whole = _path_steps(write, False)
    first_lanes, next_lanes = _path_steps(write, True)

    @njit(inline="always")
    def walk_step(cost, out, depth, lo, count, change_l, change_r, padded, p1s, p2s, weight,
                  y, x, ey, ex, prev_lo, prev_n, m, paths, prev_at, cur_at, tmp):
        """Pixel (y, x) of a path; the edge crossed from the previous pixel is stored at
        (ey, ex); the previous pixel's band was ``prev_lo``, ``prev_n`` (-1 before the
        path starts) and its path minimum ``m``, its path costs in ``paths`` from
        ``prev_at``; this pixel's go from ``cur_at``. ``cost``, ``out``: the volumes
        flat, ``depth`` candidates a pixel; ``change_r``: the right view's change map,
        reversed and padded to rows of ``padded``, flat. Returns this pixel's band and
        minimum. A pixel without a band restarts the path."""
        width = lo.shape[1]
        base = np.int64(lo[y, x]) if banded else np.int64(0)
        n = np.int64(count[y, x]) if banded else depth
        if banded and n <= 0:
            return base, np.int64(-1), m
        at = (y * width + x) * depth
        # A narrow band in a volume deep enough takes one vector a step.
        lanes = banded and n <= LANES and depth >= LANES
        # ``not banded`` is tested first though its branch repeats the last one: a constant,
        # it spares the whole-range kernels the lanes step (``lanes`` is known at run time
        # only; without it the row kernel compiled 0.7 s longer, 4.3 -> 5.0 s).
        if prev_n < 0:  # the path starts: its cost is the matching cost
            if not banded:
                new_min = first_whole(cost, out, at, paths, cur_at, weight, n)
            elif lanes:
                new_min = first_lanes(cost, out, at, paths, cur_at, weight, n)
            else:
                new_min = first_whole(cost, out, at, paths, cur_at, weight, n)
        else:
            if banded and (base != prev_lo or n != prev_n):
                # A vector's step reads the path costs of all its lanes.
                _rebase(paths, prev_at, tmp, base - prev_lo, prev_n,
                        max(n, np.int64(LANES)) if lanes else n)
            cl = change_l[ey, ex]
            change_at = ey * padded + width - 1 - ex + base
            p1a, p1b, p2a, p2b = p1s[cl], p1s[cl + 1], m + p2s[cl], m + p2s[cl + 1]
            if not banded:
                new_min = next_whole(cost, out, at, paths, prev_at, cur_at, change_r,
                                     change_at, p1a, p1b, p2a, p2b, m, weight, n)
            elif lanes:
                new_min = next_lanes(cost, out, at, paths, prev_at, cur_at, change_r,
                                     change_at, p1a, p1b, p2a, p2b, m, weight, n)
            else:
                new_min = next_whole(cost, out, at, paths, prev_at, cur_at, change_r,
                                     change_at, p1a, p1b, p2a, p2b, m, weight, n)
        if banded:
            # Past the band's ends the path is infinite (an earlier, wider band may have
            # left values there); a vector's lanes past its band are already.
            paths[cur_at] = np.float32(np.inf)
            if lanes:
                paths[cur_at + LANES + 1] = np.float32(np.inf)
            else:
                paths[cur_at + n + 1] = np.float32(np.inf)
        return base, n, new_min

    return walk_step


# The steps each kernel may take. Module globals, not closure cells: a kernel's closure
# holds only its ``banded`` flag, which Numba folds before inlining (the branch not taken
# is never compiled) and which keys its on-disk cache the same way in every process. The
# kernels spell each call out: Numba does not inline a call with *args, and packing the
# arguments into tuples changed `fast`'s output (not found why; left as it is).
_walk_whole_write = _walk_steps(False, True)
_walk_whole_add = _walk_steps(False, False)
_walk_band_add = _walk_steps(True, False)


def _compiled(function, name, banded, options):
    """``function`` compiled with ``options`` under a name of its own, the band version's
    or the whole range's. Numba names compiled code after the function's qualified name and
    a counter of the process that compiled it: two closures of one name cached by
    different processes clash when both are loaded (the band kernel ran the whole range's
    walks)."""
    function.__name__ = function.__qualname__ = f"{'band' if banded else 'whole'}_{name}"
    return njit(**options)(function)


def _row_walks(banded):
    """Both walks along row ``y``, for bands or for the whole range: a kernel's loop body."""

    def walks(cost, lo, count, change_l, change_r_rev, p1s, p2s, weight, y, out, paths, tmp):
        """``paths``: two pixels' path costs, ``2 * (depth + 2)`` infinite, used in turn as
        previous and current; ``tmp``: ``depth + 2`` for the rebase."""
        width, depth = cost.shape[1], np.int64(cost.shape[2])
        flat_cost, flat_out = borrowed(cost.reshape(-1)), borrowed(out.reshape(-1))
        change_r, padded = borrowed(change_r_rev.reshape(-1)), change_r_rev.shape[1]
        lo, count, change_l = borrowed(lo), borrowed(count), borrowed(change_l)
        p1s, p2s, paths, tmp = borrowed(p1s), borrowed(p2s), borrowed(paths), borrowed(tmp)
        out = borrowed(out)
        prev_lo, prev_n, m = np.int64(0), np.int64(-1), np.float32(0.0)
        if banded:
            out[y] = np.float32(0.0)
        for direction in (1, -1):
            start = 0 if direction == 1 else width - 1
            prev_n = np.int64(-1)
            for step in range(width):
                x = start + direction * step
                if banded and count[y, x] <= 0:  # no band: the path restarts after it
                    prev_n = np.int64(-1)
                    continue
                now = step % 2
                prev_at, cur_at = (1 - now) * (depth + 2), now * (depth + 2)
                # The edge crossed from the previous pixel: stored at the later of the two.
                ex = x if direction == 1 else x + 1
                # The whole range's first walk writes every cell (no zeroing beforehand),
                # the second adds; bands add to their zeroed row: a writing step for bands
                # took 7 s of compiling for a row of 8 floats.
                if direction == 1 and not banded:
                    prev_lo, prev_n, m = _walk_whole_write(
                        flat_cost, flat_out, depth, lo, count, change_l, change_r, padded, p1s,
                        p2s, weight, y, x, y, ex, prev_lo, prev_n, m, paths, prev_at, cur_at,
                        tmp)
                elif banded:
                    prev_lo, prev_n, m = _walk_band_add(
                        flat_cost, flat_out, depth, lo, count, change_l, change_r, padded, p1s,
                        p2s, weight, y, x, y, ex, prev_lo, prev_n, m, paths, prev_at, cur_at,
                        tmp)
                else:
                    prev_lo, prev_n, m = _walk_whole_add(
                        flat_cost, flat_out, depth, lo, count, change_l, change_r, padded, p1s,
                        p2s, weight, y, x, y, ex, prev_lo, prev_n, m, paths, prev_at, cur_at,
                        tmp)

    return _compiled(walks, "row_walks", banded, ROW_OPTIONS)


def _column_walks(banded):
    """Both walks down columns ``x0 .. x0 + n - 1`` side by side: a kernel's loop body."""

    def walks(cost, lo, count, change_l, change_r_rev, p1s, p2s, weight, x0, n, out, paths,
              tmp, prev_lo, prev_n, mins):
        """``paths``: each column's path costs, ``depth + 2`` a column, in two halves used
        in turn as the previous row's and the current one's (``2 * n * (depth + 2)``,
        infinite); ``tmp``: ``depth + 2``; ``prev_lo``, ``prev_n``, ``mins``: the columns'
        last bands and minima (``n`` each, ``prev_lo`` and ``mins`` zero)."""
        height, depth = cost.shape[0], np.int64(cost.shape[2])
        flat_cost, flat_out = borrowed(cost.reshape(-1)), borrowed(out.reshape(-1))
        change_r, padded = borrowed(change_r_rev.reshape(-1)), change_r_rev.shape[1]
        lo, count, change_l = borrowed(lo), borrowed(count), borrowed(change_l)
        p1s, p2s, paths, tmp = borrowed(p1s), borrowed(p2s), borrowed(paths), borrowed(tmp)
        prev_lo, prev_n, mins = borrowed(prev_lo), borrowed(prev_n), borrowed(mins)
        line = depth + 2
        half = 0  # the previous row's half
        for direction in (1, -1):
            prev_n[:] = -1
            for step in range(height):
                y = step if direction == 1 else height - 1 - step
                ey = y if direction == 1 else y + 1  # the edge crossed, at the later row
                for k in range(n):
                    x = x0 + k
                    if banded and count[y, x] <= 0:  # no band: the path restarts
                        prev_n[k] = -1
                        continue
                    prev_at = (half * n + k) * line
                    cur_at = ((1 - half) * n + k) * line
                    if banded:
                        prev_lo[k], prev_n[k], mins[k] = _walk_band_add(
                            flat_cost, flat_out, depth, lo, count, change_l, change_r,
                            padded, p1s, p2s, weight, y, x, ey, x, prev_lo[k], prev_n[k],
                            mins[k], paths, prev_at, cur_at, tmp)
                    else:
                        prev_lo[k], prev_n[k], mins[k] = _walk_whole_add(
                            flat_cost, flat_out, depth, lo, count, change_l, change_r,
                            padded, p1s, p2s, weight, y, x, ey, x, prev_lo[k], prev_n[k],
                            mins[k], paths, prev_at, cur_at, tmp)
                half = 1 - half

    return _compiled(walks, "column_walks", banded, ROW_OPTIONS)


def _diagonal_walks(banded):
    """Both walks along diagonal ``line`` (see :func:`scanline_diagonal_pass`): a kernel's
    loop body."""

    def walks(cost, lo, count, change_l, change_r_rev, p1s, p2s, step_x, weight, line, out,
              paths, tmp):
        """``paths``, ``tmp``: as the row walks'."""
        height, width = cost.shape[0], cost.shape[1]
        depth = np.int64(cost.shape[2])
        flat_cost, flat_out = borrowed(cost.reshape(-1)), borrowed(out.reshape(-1))
        change_r, padded = borrowed(change_r_rev.reshape(-1)), change_r_rev.shape[1]
        lo, count, change_l = borrowed(lo), borrowed(count), borrowed(change_l)
        p1s, p2s, paths, tmp = borrowed(p1s), borrowed(p2s), borrowed(paths), borrowed(tmp)
        # Line starts on the top row, then down the first column (last for step_x = -1).
        if line < width:
            y0, x0 = 0, line if step_x == 1 else width - 1 - line
        else:
            y0, x0 = line - width + 1, 0 if step_x == 1 else width - 1
        room_x = width - 1 - x0 if step_x == 1 else x0
        length = min(height - y0, room_x + 1)
        prev_lo, prev_n, m = np.int64(0), np.int64(-1), np.float32(0.0)
        for direction in (1, -1):
            start = 0 if direction == 1 else length - 1
            prev_n = np.int64(-1)
            for step in range(length):
                i = start + direction * step
                y = y0 + i
                x = x0 + i * step_x
                if banded and count[y, x] <= 0:  # no band: the path restarts after it
                    prev_n = np.int64(-1)
                    continue
                now = step % 2
                prev_at, cur_at = (1 - now) * (depth + 2), now * (depth + 2)
                # The edge crossed is stored at the later pixel of the two, top to bottom.
                ey = y if direction == 1 else y + 1
                ex = x if direction == 1 else x + step_x
                if banded:
                    prev_lo, prev_n, m = _walk_band_add(
                        flat_cost, flat_out, depth, lo, count, change_l, change_r, padded, p1s,
                        p2s, weight, y, x, ey, ex, prev_lo, prev_n, m, paths, prev_at, cur_at,
                        tmp)
                else:
                    prev_lo, prev_n, m = _walk_whole_add(
                        flat_cost, flat_out, depth, lo, count, change_l, change_r, padded, p1s,
                        p2s, weight, y, x, ey, ex, prev_lo, prev_n, m, paths, prev_at, cur_at,
                        tmp)

    return _compiled(walks, "diagonal_walks", banded, ROW_OPTIONS)


# Module globals, as the steps: a kernel's closure holds only its ``banded`` flag.
_whole_row_walks, _band_row_walks = _row_walks(False), _row_walks(True)
_whole_column_walks, _band_column_walks = _column_walks(False), _column_walks(True)
_whole_diagonal_walks, _band_diagonal_walks = _diagonal_walks(False), _diagonal_walks(True)


def _row_kernel(banded):
    """:func:`scanline_rows`' kernel for bands or for the whole range."""

    def rows(cost, lo, count, change_l, change_r_rev, p1s, p2s, weight, out):
        depth = cost.shape[2]
        for y in prange(cost.shape[0]):
            paths = np.full(2 * (depth + 2), np.inf, dtype=np.float32)
            tmp = np.empty(depth + 2, dtype=np.float32)
            if banded:
                _band_row_walks(cost, lo, count, change_l, change_r_rev, p1s, p2s, weight,
                                np.int64(y), out, paths, tmp)
            else:
                _whole_row_walks(cost, lo, count, change_l, change_r_rev, p1s, p2s, weight,
                                 np.int64(y), out, paths, tmp)

    return _compiled(rows, "rows", banded, KERNEL_OPTIONS)


def _column_kernel(banded):
    """:func:`scanline_columns`' kernel for bands or for the whole range."""

    def columns(cost, lo, count, change_l, change_r_rev, p1s, p2s, weight, chunk, out):
        width = cost.shape[1]
        n_chunks = (width + chunk - 1) // chunk
        depth = cost.shape[2]
        for c in prange(n_chunks):
            x0 = c * chunk
            n = min(width, x0 + chunk) - x0
            paths = np.full(2 * n * (depth + 2), np.inf, dtype=np.float32)
            tmp = np.empty(depth + 2, dtype=np.float32)
            prev_lo = np.zeros(n, dtype=np.int64)
            prev_n = np.empty(n, dtype=np.int64)
            mins = np.zeros(n, dtype=np.float32)
            if banded:
                _band_column_walks(cost, lo, count, change_l, change_r_rev, p1s, p2s, weight,
                                   x0, n, out, paths, tmp, prev_lo, prev_n, mins)
            else:
                _whole_column_walks(cost, lo, count, change_l, change_r_rev, p1s, p2s,
                                    weight, x0, n, out, paths, tmp, prev_lo, prev_n, mins)

    return _compiled(columns, "columns", banded, KERNEL_OPTIONS)


def _diagonal_kernel(banded):
    """:func:`scanline_diagonal_pass`' kernel for bands or for the whole range."""

    def diagonal(cost, lo, count, change_l, change_r_rev, p1s, p2s, step_x, weight, out):
        n_lines = cost.shape[0] + cost.shape[1] - 1
        depth = cost.shape[2]
        for index in prange(n_lines):
            line = np.int64(index)  # prange's index may be unsigned: keep the sums signed
            paths = np.full(2 * (depth + 2), np.inf, dtype=np.float32)
            tmp = np.empty(depth + 2, dtype=np.float32)
            if banded:
                _band_diagonal_walks(cost, lo, count, change_l, change_r_rev, p1s, p2s,
                                     step_x, weight, line, out, paths, tmp)
            else:
                _whole_diagonal_walks(cost, lo, count, change_l, change_r_rev, p1s, p2s,
                                      step_x, weight, line, out, paths, tmp)

    return _compiled(diagonal, "diagonal", banded, KERNEL_OPTIONS)


#: One pixel's path costs over a band in a volume LANES deep: LANES, and an end either side.
_LANE_PATHS = LANES + 2


@njit(inline="always")
def _lanes_step(cost, out, y, x, ey, ex, n, base, prev_lo, prev_n, m, started, paths, prev_at,
                cur_at, tmp, change_l, change_r_rev, p1s, p2s, weight):
    """One pixel's step of a path over a band of ``n`` <= LANES candidates from ``base`` in
    a volume LANES deep, adding ``weight`` x its path costs to ``out``; returns the path's
    minimum. The steps of ``_walk_band_add`` for such a band, the same sums in the same
    order, as one vector (``_kernels.lanes``) and without the bookkeeping of wider bands
    and volumes. ``paths`` from ``prev_at``: the previous pixel's path costs (band
    ``prev_lo``, ``prev_n``; ``started`` False: none); this pixel's go from ``cur_at``."""
    inf = np.float32(np.inf)
    if not started:  # the path starts: its cost is the matching cost
        new_min = inf
        for d in range(LANES):
            v = cost[y, x, d]
            v = v if d < n else inf
            paths[cur_at + d + 1] = v
            out[y, x, d] += weight * v
            new_min = v if v < new_min else new_min
    else:
        # Two bands from one ``lo`` need no rebase: a step leaves its lanes past its band,
        # and both ends, infinite.
        if base != prev_lo:
            _rebase(paths, prev_at, tmp, base - prev_lo, prev_n, np.int64(LANES))
        cl = change_l[ey, ex]
        start = cost.shape[1] - 1 - ex + base  # change_r_rev's column of disparity base
        p1a, p1b, p2a, p2b = p1s[cl], p1s[cl + 1], m + p2s[cl], m + p2s[cl + 1]
        new_min = path_step_lanes(cost, out, (y * cost.shape[1] + x) * LANES, paths, prev_at,
                                  cur_at, change_r_rev, ey * change_r_rev.shape[1] + start,
                                  p1a, p1b, p2a, p2b, m, weight, n)
    # Lanes from ``n`` on are infinite already: only the ends are set.
    paths[cur_at] = inf
    paths[cur_at + LANES + 1] = inf
    return new_min


@njit(inline="always")
def _lanes_walk_step(cost, out, lo, count, y, x, ex, started, prev_lo, prev_n, m, paths,
                     prev_at, cur_at, tmp, change_l, change_r_rev, p1s, p2s, weight):
    """Pixel (y, x) of a row's walk over bands (:func:`_lanes_step`), the walk's state in
    and out: whether it has started, its last band and its minimum. A pixel without a band
    restarts the path after it."""
    n = np.int64(count[y, x])
    if n <= 0:
        return False, prev_lo, prev_n, m
    base = np.int64(lo[y, x])
    m = _lanes_step(cost, out, y, x, y, ex, n, base, prev_lo, prev_n, m, started, paths,
                    prev_at, cur_at, tmp, change_l, change_r_rev, p1s, p2s, weight)
    return True, base, n, m


@njit(**KERNEL_OPTIONS)
def rows_over_lanes(cost, lo, count, change_l, change_r_rev, p1s, p2s, weight, out):
    """:func:`scanline_rows` over bands in a volume :data:`LANES` deep (coarse-to-fine's):
    the same sums, 1.4x faster than the general band kernel (cones' bands).

    Two rows walked side by side: a band's step is one vector, and each step waits on the
    last one's least path cost (a reduction across the lanes), so a row's walk is one chain
    of latencies; two rows keep two in flight (each row's sums as alone)."""
    height, width, depth = cost.shape
    for pair in prange((height + 1) // 2):
        ya = 2 * pair
        yb = min(ya + 1, height - 1)
        both = yb > ya
        # Each row's path costs, previous and current: row b's from 2 _LANE_PATHS.
        paths = np.full(4 * _LANE_PATHS, np.inf, dtype=np.float32)
        tmp = np.empty(_LANE_PATHS, dtype=np.float32)
        out[ya] = np.float32(0.0)  # both walks add
        out[yb] = np.float32(0.0)
        for direction in (1, -1):
            start = 0 if direction == 1 else width - 1
            started_a = started_b = False
            lo_a, n_a, m_a = np.int64(0), np.int64(0), np.float32(0.0)
            lo_b, n_b, m_b = np.int64(0), np.int64(0), np.float32(0.0)
            for step in range(width):
                x = start + direction * step
                now = step % 2
                ex = x if direction == 1 else x + 1  # the edge crossed, at the later pixel
                started_a, lo_a, n_a, m_a = _lanes_walk_step(
                    cost, out, lo, count, ya, x, ex, started_a, lo_a, n_a, m_a, paths,
                    (1 - now) * _LANE_PATHS, now * _LANE_PATHS, tmp, change_l, change_r_rev,
                    p1s, p2s, weight)
                if both:
                    started_b, lo_b, n_b, m_b = _lanes_walk_step(
                        cost, out, lo, count, yb, x, ex, started_b, lo_b, n_b, m_b, paths,
                        (3 - now) * _LANE_PATHS, (2 + now) * _LANE_PATHS, tmp, change_l,
                        change_r_rev, p1s, p2s, weight)


@njit(**KERNEL_OPTIONS)
def columns_over_lanes(cost, lo, count, change_l, change_r_rev, p1s, p2s, weight, chunk, out):
    """:func:`scanline_columns` over bands in a volume :data:`LANES` deep: the same sums,
    1.3x faster than the general band kernel (cones' bands)."""
    height, width, depth = cost.shape
    n_chunks = (width + chunk - 1) // chunk
    for c in prange(n_chunks):
        x0 = c * chunk
        n_cols = min(width, x0 + chunk) - x0
        # Each column's path costs, in two halves used in turn as the previous row's and
        # the current one's.
        paths = np.full(2 * n_cols * _LANE_PATHS, np.inf, dtype=np.float32)
        tmp = np.empty(_LANE_PATHS, dtype=np.float32)
        prev_lo = np.zeros(n_cols, dtype=np.int64)
        prev_n = np.zeros(n_cols, dtype=np.int64)
        started = np.zeros(n_cols, dtype=np.bool_)
        mins = np.zeros(n_cols, dtype=np.float32)
        half = 0  # the previous row's half
        for direction in (1, -1):
            started[:] = False
            for step in range(height):
                y = step if direction == 1 else height - 1 - step
                ey = y if direction == 1 else y + 1  # the edge crossed, at the later row
                for k in range(n_cols):
                    x = x0 + k
                    n = np.int64(count[y, x])
                    if n <= 0:  # no band: the path restarts
                        started[k] = False
                        continue
                    base = np.int64(lo[y, x])
                    mins[k] = _lanes_step(cost, out, y, x, ey, x, n, base, prev_lo[k],
                                          prev_n[k], mins[k], started[k], paths,
                                          (half * n_cols + k) * _LANE_PATHS,
                                          ((1 - half) * n_cols + k) * _LANE_PATHS, tmp,
                                          change_l, change_r_rev, p1s, p2s, weight)
                    started[k] = True
                    prev_lo[k] = base
                    prev_n[k] = n
                half = 1 - half


#: The kernels for the whole range and for bands, each compiled on its first call.
_ROWS = {False: _row_kernel(False), True: _row_kernel(True)}
_COLUMNS = {False: _column_kernel(False), True: _column_kernel(True)}
_DIAGONALS = {False: _diagonal_kernel(False), True: _diagonal_kernel(True)}


def scanline_rows(cost, lo, count, banded, change_l, change_r_rev, p1s, p2s, weight, out):
    """Write ``weight`` x the path costs of both directions along every row to ``out``
    (every cell of the bands).

    C_r(p, d) = C(p, d) + min(C_r(p-r, d), C_r(p-r, d+-1) + P1,
                              min_k C_r(p-r, k) + P2) - min_k C_r(p-r, k).

    ``cost[y, x, k]`` is the cost of disparity ``lo[y, x] + k`` for ``k < count[y, x]``
    (the pixel's band; the whole range: ``lo`` 0, ``count`` D, ``banded`` False); a
    disparity outside the previous pixel's band has an infinite path cost there.
    ``change_l[y, x]`` is 1 where the left image's colour changes by ``tau`` or more
    between (y, x) and its predecessor along the pass ((y, x - 1) here, (y - 1, x) in
    :func:`scanline_columns`; 1 where there is none). ``change_r_rev`` is the same map of
    the right image, reversed along x and padded with ones: ``change_r_rev[y, W - 1 - x +
    d]`` is the change at the right pixel (y, x - d) of (y, x), 1 where x - d < 0.
    ``p1s[k]``, ``p2s[k]`` are the penalties where ``k`` (0, 1 or 2) of the two images
    change.
    """
    if banded and cost.shape[2] == LANES:
        rows_over_lanes(cost, lo, count, change_l, change_r_rev, p1s, p2s, weight, out)
    else:
        _ROWS[bool(banded)](cost, lo, count, change_l, change_r_rev, p1s, p2s, weight, out)


def scanline_columns(cost, lo, count, banded, change_l, change_r_rev, p1s, p2s, weight, chunk,
                     out):
    """:func:`scanline_rows` down and up every column, adding to ``out``.

    The columns go in chunks of ``chunk``, walked side by side a row at a time: each step
    reads the chunk's pixels of one row, neighbours in memory, where one column at a time
    read one pixel a row (measured on the twelve standard pairs: 0.6-0.7x the time). Each
    column's sums are its own, so the chunk size does not change the result.
    """
    if banded and cost.shape[2] == LANES:
        columns_over_lanes(cost, lo, count, change_l, change_r_rev, p1s, p2s, weight, chunk,
                           out)
    else:
        _COLUMNS[bool(banded)](cost, lo, count, change_l, change_r_rev, p1s, p2s, weight,
                               chunk, out)


def scanline_diagonal_pass(cost, lo, count, banded, change_l, change_r_rev, p1s, p2s, step_x,
                           weight, out):
    """:func:`scanline_rows` along the diagonals that step (1, ``step_x``), both ways, adding.

    ``change_l[y, x]``: 1 where the colour changes by ``tau`` or more between (y, x) and
    (y - 1, x - step_x), and where there is no such pixel; ``change_r_rev`` the same of the
    right image, reversed along x and padded with ones.
    """
    _DIAGONALS[bool(banded)](cost, lo, count, change_l, change_r_rev, p1s, p2s, step_x, weight,
                             out)
