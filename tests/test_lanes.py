"""The vector steps of ``_kernels.lanes`` against the scalar loops they stand for, to the bit."""

import numpy as np
import pytest
from numba import njit

from vsmatch._kernels.disparity import _argmin
from vsmatch._kernels.lanes import (LANES, add_arm_in_lanes, add_in_lanes, argmin_chunks,
                                    copy_lanes, divide_lanes, path_step_chunks_add,
                                    path_step_chunks_write, path_step_lanes)
from vsmatch._kernels.scanline import path_step


@njit(cache=False)
def _add_vector(total, size, src, src_at, held, held_at, first, stop, reach, reach_at, k):
    add_in_lanes(total, size, src, src_at, held, held_at, first, stop, reach, reach_at, k)


@njit(cache=False)
def _add_arm_vector(total, size, src, held, first_pass, lo, count, reach, reach_at, base, n,
                    pixel, stride, length):
    add_arm_in_lanes(total, size, src, held, first_pass, lo, count, reach, reach_at, base, n,
                     pixel, stride, length)


@njit(cache=False)
def _add_arm_each(total, size, src, held, first_pass, lo, count, reach, reach_at, base, n,
                  pixel, stride, length):
    """The arm a neighbour at a time, with :func:`add_in_lanes`, as the kernels took it."""
    depth = src.shape[2]
    ones = np.ones(LANES, np.float32)
    for k in range(1, length + 1):
        neighbour = pixel + k * stride
        off = base - np.int64(lo.flat[neighbour])
        if off <= -LANES or off >= LANES:
            continue
        first = max(np.int64(0), -off)
        stop = min(n, np.int64(count.flat[neighbour]) - off)
        at = neighbour * depth + off
        if first_pass:
            add_in_lanes(total, size, src, at, ones, 0, first, stop, reach, reach_at, k)
        else:
            add_in_lanes(total, size, src, at, held, at, first, stop, reach, reach_at, k)


@njit(cache=False)
def _copy_and_divide(dst, dst_at, src, src_at, numerator, denominator, quotient, at):
    copy_lanes(dst, dst_at, src, src_at)
    divide_lanes(quotient, at, numerator, denominator)


@njit(cache=False)
def _step_vector(cost, out, at, paths, prev_at, cur_at, change, change_at, p1a, p1b, p2a, p2b,
                 m, weight, n):
    return path_step_lanes(cost, out, at, paths, prev_at, cur_at, change, change_at, p1a, p1b,
                           p2a, p2b, m, weight, n)


@njit(cache=False)
def _step_scalar(cost, out, at, paths, prev_at, cur_at, change, change_at, p1a, p1b, p2a, p2b,
                 m, weight, n):
    least = np.float32(np.inf)
    for d in range(LANES):
        c = change[change_at + d]
        v = cost[at + d] + path_step(paths, prev_at, d, p1b if c else p1a,
                                     p2b if c else p2a) - m
        v = v if d < n else np.float32(np.inf)
        paths[cur_at + d + 1] = v
        out[at + d] += weight * v
        least = min(least, v)
    return least


@njit(cache=False)
def _chunks_vector(cost, out, at, paths, prev_at, cur_at, change, change_at, p1a, p1b, p2a,
                   p2b, m, weight, chunks, write):
    if write:
        return path_step_chunks_write(cost, out, at, paths, prev_at, cur_at, change,
                                      change_at, p1a, p1b, p2a, p2b, m, weight, chunks)
    return path_step_chunks_add(cost, out, at, paths, prev_at, cur_at, change, change_at,
                                p1a, p1b, p2a, p2b, m, weight, chunks)


@njit(cache=False)
def _chunks_scalar(cost, out, at, paths, prev_at, cur_at, change, change_at, p1a, p1b, p2a,
                   p2b, m, weight, chunks, write):
    least = np.float32(np.inf)
    for d in range(chunks * LANES):
        c = change[change_at + d]
        v = cost[at + d] + path_step(paths, prev_at, d, p1b if c else p1a,
                                     p2b if c else p2a) - m
        paths[cur_at + d + 1] = v
        out[at + d] = weight * v if write else out[at + d] + weight * v
        least = min(least, v)
    return least


def test_lanes_add_only_the_candidates_inside_the_range_and_the_arm(rng):
    for _ in range(300):
        src = rng.random(40).astype(np.float32)
        src[rng.random(40) < 0.1] = np.nan  # past a band: never added
        held = (rng.random(40) * 5).astype(np.float32)
        reach = rng.integers(0, 9, 30).astype(np.uint8)
        src_at, held_at, reach_at = (int(rng.integers(0, 23)) for _ in range(3))
        first, stop, k = int(rng.integers(0, 8)), int(rng.integers(0, 9)), int(rng.integers(1, 9))
        total = rng.random(LANES).astype(np.float32)
        size = rng.random(LANES).astype(np.float32)
        want_total, want_size = total.copy(), size.copy()
        for d in range(first, stop):
            if k <= reach[reach_at + d]:
                want_total[d] += src[src_at + d]
                want_size[d] += held[held_at + d]
        _add_vector(total, size, src, src_at, held, held_at, first, stop, reach, reach_at, k)
        assert total.tobytes() == want_total.tobytes()
        assert size.tobytes() == want_size.tobytes()


def test_lanes_copy_and_divide_elementwise(rng):
    src = rng.random((3, 4, LANES)).astype(np.float32)
    dst = np.zeros((2, LANES * 2), np.float32)
    numerator, denominator = (rng.random(LANES).astype(np.float32) for _ in range(2))
    quotient = np.zeros((5, LANES), np.float32)
    _copy_and_divide(dst, 11, src, 9, numerator, denominator, quotient, 16)
    assert np.array_equal(dst.reshape(-1)[11:11 + LANES], src.reshape(-1)[9:9 + LANES])
    assert np.count_nonzero(dst) == LANES
    assert quotient[2].tobytes() == (numerator / denominator).tobytes()
    assert np.count_nonzero(quotient) == LANES


def test_a_path_step_in_lanes_is_the_scalar_step(rng):
    """Bands of every width, path costs with infinite lanes and finite ends (as a band
    that moved leaves them), both penalties; the previous and current path costs anywhere
    in one array."""
    for _ in range(300):
        n = int(rng.integers(1, LANES + 1))
        paths = (rng.random(40) * 4).astype(np.float32)
        paths[rng.random(40) < 0.2] = np.inf
        prev_at = int(rng.integers(0, 40 - LANES - 2))
        cur_at = int(rng.integers(0, 40 - LANES - 2))
        while abs(cur_at - prev_at) < LANES + 2:  # the two do not overlap
            cur_at = int(rng.integers(0, 40 - LANES - 2))
        cost = (rng.random(30) * 3).astype(np.float32)
        change = (rng.random(30) < 0.5).astype(np.uint8)
        at, change_at = int(rng.integers(0, 22)), int(rng.integers(0, 22))
        prev = paths[prev_at:prev_at + LANES + 2]
        finite = prev[np.isfinite(prev)]
        m = np.float32(finite.min() if finite.size else 0.0)
        p1a, p1b = np.float32(0.5), np.float32(0.25)
        p2a, p2b = m + np.float32(2.0), m + np.float32(1.0)
        weight = np.float32(0.25)
        out_v = rng.random(30).astype(np.float32)
        out_s = out_v.copy()
        paths_s = paths.copy()
        args = (change, change_at, p1a, p1b, p2a, p2b, m, weight, n)
        got = _step_vector(cost, out_v, at, paths, prev_at, cur_at, *args)
        want = _step_scalar(cost, out_s, at, paths_s, prev_at, cur_at, *args)
        assert np.float32(got).tobytes() == np.float32(want).tobytes()
        assert paths.tobytes() == paths_s.tobytes()
        assert out_v.tobytes() == out_s.tobytes()


def test_a_path_step_over_whole_vectors_is_the_scalar_step(rng):
    """The whole range's step a vector at a time: each vector's neighbours from the next
    and the last one, the element past the vectors from memory (a band's infinite end or
    the next candidate, taken one by one after them), writing or adding; the pixel's
    costs, changes and path costs at offsets of their arrays."""
    for trial in range(200):
        chunks = int(rng.integers(0, 6))
        size = chunks * LANES + int(rng.integers(0, LANES)) + 2
        room = 2 * size + 8
        paths = (rng.random(room) * 4).astype(np.float32)
        paths[rng.random(room) < 0.15] = np.inf
        prev_at, cur_at = (int(rng.integers(0, 4)), size + int(rng.integers(0, 4)))
        if trial % 3 == 0:
            prev_at, cur_at = cur_at, prev_at
        at, change_at = int(rng.integers(0, 9)), int(rng.integers(0, 9))
        cost = (rng.random(size + 9) * 3).astype(np.float32)
        change = (rng.random(size + 9) < 0.5).astype(np.uint8)
        # The previous minimum: no path cost falls below it (as the int32 minimum takes).
        prev = paths[prev_at:prev_at + size]
        finite = prev[np.isfinite(prev)]
        m = np.float32(finite.min() if finite.size else 0.0)
        args = (change, change_at, np.float32(0.5), np.float32(0.25), m + np.float32(2.0),
                m + np.float32(1.0), m, np.float32(0.25), chunks, trial % 2 == 0)
        out_v = rng.random(size + 9).astype(np.float32)
        out_s = out_v.copy()
        paths_s = paths.copy()
        got = _chunks_vector(cost, out_v, at, paths, prev_at, cur_at, *args)
        want = _chunks_scalar(cost, out_s, at, paths_s, prev_at, cur_at, *args)
        assert np.float32(got).tobytes() == np.float32(want).tobytes()
        assert paths.tobytes() == paths_s.tobytes()
        assert out_v.tobytes() == out_s.tobytes()


def test_an_arm_in_lanes_adds_as_its_neighbours_one_by_one(rng):
    """Bands that meet or not at every offset, neighbours before and after the pixel,
    right arms shorter and longer than k, both passes (counting ones, and adding sizes)."""
    for trial in range(300):
        height, width, depth = 6, 9, int(rng.choice([LANES, LANES + 4]))
        src = rng.random((height, width, depth)).astype(np.float32)
        held = (rng.random((height, width, depth)) * 5).astype(np.float32)
        lo = rng.integers(0, 12, (height, width)).astype(np.int32)
        count = rng.integers(0, LANES + 1, (height, width)).astype(np.int32)
        reach = rng.integers(0, 6, 40).astype(np.uint8)
        pixel = int(rng.integers(12, height * width - 12))
        stride = int(rng.choice([1, -1, width, -width]))
        length = int(rng.integers(0, 2))  # 0 or 1 neighbour ...
        length = int(rng.integers(0, 5)) if trial % 2 else length  # ... or up to 4
        # As the kernel calls it: every neighbour lies inside the volume, past its first
        # pixel and before its last (a column's arm from the third row up read before it).
        room = next(k for k in range(height * width)
                    if not 0 < pixel + (k + 1) * stride < height * width - 1)
        length = min(length, room)
        base, n = int(lo.flat[pixel]), int(rng.integers(1, LANES + 1))
        reach_at, first_pass = int(rng.integers(0, 30)), bool(trial % 3 == 0)
        total = rng.random(LANES).astype(np.float32)
        size = rng.random(LANES).astype(np.float32)
        want_total, want_size = total.copy(), size.copy()
        args = (src, held, first_pass, lo, count, reach, reach_at, base, n, pixel, stride,
                length)
        _add_arm_each(want_total, want_size, *args)
        _add_arm_vector(total, size, *args)
        assert total.tobytes() == want_total.tobytes()
        assert size.tobytes() == want_size.tobytes()


@njit(cache=False)
def _least_place(costs, n):
    return argmin_chunks(costs, n // LANES), _argmin(costs, n)


def test_the_least_in_lanes_is_the_first_least(rng):
    """Ties (many equal costs, +0 and -0, infinities) take the first, as a walk with ``<``
    does: within the vectors and with the rest after them."""
    for _ in range(300):
        n = int(rng.integers(LANES, 6 * LANES))
        costs = rng.integers(0, 4, n).astype(np.float32)  # many ties
        costs[rng.random(n) < 0.1] = np.inf
        costs[rng.random(n) < 0.1] = -0.0
        in_vectors, whole = _least_place(costs, n)
        vectors = n // LANES * LANES
        first = next(d for d in range(vectors) if costs[d] == costs[:vectors].min())
        assert in_vectors == first
        assert whole == next(d for d in range(n) if costs[d] == costs.min())


def test_lanes_refuse_arrays_they_cannot_read_by_flat_index():
    """A float64 or strided array would be read as float32 lanes: refused when compiled."""
    from numba.core.errors import TypingError

    doubles = np.zeros(16)
    strided = np.zeros(32, np.float32)[::2]
    for dst in (doubles, strided):
        with pytest.raises(TypingError, match="C-contiguous float32"):
            _copy_and_divide(dst, 0, np.zeros(8, np.float32), 0, np.ones(8, np.float32),
                             np.ones(8, np.float32), np.zeros(8, np.float32), 0)
