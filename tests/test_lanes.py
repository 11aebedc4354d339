"""The vector steps of ``_kernels.lanes`` against the scalar loops they stand for, to the bit."""

import numpy as np
import pytest
from numba import njit

from vsmatch._kernels.disparity import _argmin
from vsmatch._kernels.lanes import (LANES, add_in_lanes, argmin_chunks, copy_lanes,
                                    divide_lanes, path_step_chunks_add,
                                    path_step_chunks_write, path_step_lanes)
from vsmatch._kernels.scanline import path_step


@njit(cache=False)
def _add_vector(total, size, src, src_at, held, held_at, first, stop, reach, reach_at, k):
    add_in_lanes(total, size, src, src_at, held, held_at, first, stop, reach, reach_at, k)


@njit(cache=False)
def _copy_and_divide(dst, dst_at, src, src_at, numerator, denominator, quotient, at):
    copy_lanes(dst, dst_at, src, src_at)
    divide_lanes(quotient, at, numerator, denominator)


@njit(cache=False)
def _step_vector(cost, out, at, prev, cur, change, change_at, p1a, p1b, p2a, p2b, m, weight,
                 n):
    return path_step_lanes(cost, out, at, prev, cur, change, change_at, p1a, p1b, p2a, p2b, m,
                           weight, n)


@njit(cache=False)
def _step_scalar(cost, out, at, prev, cur, change, change_at, p1a, p1b, p2a, p2b, m, weight,
                 n):
    for d in range(LANES):
        c = change[change_at + d]
        v = cost[at + d] + path_step(prev, d, p1b if c else p1a, p2b if c else p2a) - m
        v = v if d < n else np.float32(np.inf)
        cur[d + 1] = v
        out[at + d] += weight * v
    return cur[1:LANES + 1].min()


@njit(cache=False)
def _chunks_vector(src, dst, prev, cur, change, p1a, p1b, p2a, p2b, m, weight, chunks, write):
    if write:
        return path_step_chunks_write(src, dst, prev, cur, change, p1a, p1b, p2a, p2b, m,
                                      weight, chunks)
    return path_step_chunks_add(src, dst, prev, cur, change, p1a, p1b, p2a, p2b, m, weight,
                                chunks)


@njit(cache=False)
def _chunks_scalar(src, dst, prev, cur, change, p1a, p1b, p2a, p2b, m, weight, chunks, write):
    least = np.float32(np.inf)
    for d in range(chunks * LANES):
        c = change[d]
        v = src[d] + path_step(prev, d, p1b if c else p1a, p2b if c else p2a) - m
        cur[d + 1] = v
        dst[d] = weight * v if write else dst[d] + weight * v
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
    that moved leaves them), both penalties."""
    for _ in range(300):
        n = int(rng.integers(1, LANES + 1))
        prev = (rng.random(LANES + 2) * 4).astype(np.float32)
        prev[rng.random(LANES + 2) < 0.2] = np.inf
        cost = (rng.random(30) * 3).astype(np.float32)
        change = (rng.random(30) < 0.5).astype(np.uint8)
        at, change_at = int(rng.integers(0, 22)), int(rng.integers(0, 22))
        finite = prev[np.isfinite(prev)]
        m = np.float32(finite.min() if finite.size else 0.0)
        p1a, p1b = np.float32(0.5), np.float32(0.25)
        p2a, p2b = m + np.float32(2.0), m + np.float32(1.0)
        weight = np.float32(0.25)
        out_v = rng.random(30).astype(np.float32)
        out_s = out_v.copy()
        cur_v = np.full(LANES + 2, -1, np.float32)
        cur_s = cur_v.copy()
        args = (change, change_at, p1a, p1b, p2a, p2b, m, weight, n)
        got = _step_vector(cost, out_v, at, prev, cur_v, *args)
        want = _step_scalar(cost, out_s, at, prev, cur_s, *args)
        assert np.float32(got).tobytes() == np.float32(want).tobytes()
        assert cur_v.tobytes() == cur_s.tobytes()
        assert out_v.tobytes() == out_s.tobytes()


def test_a_path_step_over_whole_vectors_is_the_scalar_step(rng):
    """The whole range's step a vector at a time: each vector's neighbours from the next
    and the last one, the element past the vectors from memory (a band's infinite end or
    the next candidate, taken one by one after them), writing or adding."""
    for trial in range(200):
        chunks = int(rng.integers(0, 6))
        size = chunks * LANES + int(rng.integers(0, LANES)) + 2
        prev = (rng.random(size) * 4).astype(np.float32)
        prev[rng.random(size) < 0.15] = np.inf
        src = (rng.random(size) * 3).astype(np.float32)
        change = (rng.random(size) < 0.5).astype(np.uint8)
        # The previous minimum: no path cost falls below it (as the int32 minimum takes).
        finite = prev[np.isfinite(prev)]
        m = np.float32(finite.min() if finite.size else 0.0)
        args = (change, np.float32(0.5), np.float32(0.25), m + np.float32(2.0),
                m + np.float32(1.0), m, np.float32(0.25), chunks, trial % 2 == 0)
        dst_v = rng.random(size).astype(np.float32)
        dst_s = dst_v.copy()
        cur_v = np.full(size, -1, np.float32)
        cur_s = cur_v.copy()
        got = _chunks_vector(src, dst_v, prev, cur_v, *args)
        want = _chunks_scalar(src, dst_s, prev, cur_s, *args)
        assert np.float32(got).tobytes() == np.float32(want).tobytes()
        assert cur_v.tobytes() == cur_s.tobytes()
        assert dst_v.tobytes() == dst_s.tobytes()


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
