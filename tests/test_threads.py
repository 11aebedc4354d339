"""Work shared between threads: the same bytes at any thread count, and the helpers that
deal the work out."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from vsmatch import datasets, pipeline
from vsmatch._kernels.rows import dealt
from vsmatch.bench import thread_count
from vsmatch.images import mirrored, upsample_nearest


@pytest.mark.parametrize("classes", [1, 2, 3, 16])
@pytest.mark.parametrize("count", [*range(1, 40), 375, 496, 1001])
def test_dealt_items_are_each_taken_once_and_each_thread_reaches_the_whole_height(count,
                                                                                  classes):
    items = [dealt(i, count, classes) for i in range(count)]
    assert sorted(items) == list(range(count))
    if classes == 1:
        assert items == list(range(count))  # one thread: in order
    elif count >= 4 * classes:  # each class, a thread's share: top to bottom in steps
        sizes = [count // classes + (k < count % classes) for k in range(classes)]
        for k, first in enumerate(np.cumsum([0] + sizes[:-1])):
            part = items[first:first + sizes[k]]
            assert part[0] == k and part[-1] >= count - classes
            assert np.all(np.diff(part) == classes)


@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.int32, np.float32, np.float64,
                                   np.bool_, np.int64])
@pytest.mark.parametrize("lead", [(), (4,), (2, 3)])
def test_upsample_nearest_takes_each_coarse_pixel(dtype, lead):
    coarse = (np.random.default_rng(0).random(lead + (19, 23)) * 100).astype(dtype)
    for shape in ((38, 46), (37, 45), (38, 45), (10, 12), (30, 40)):
        rows = np.minimum(np.arange(shape[0]) // 2, coarse.shape[-2] - 1)
        cols = np.minimum(np.arange(shape[1]) // 2, coarse.shape[-1] - 1)
        fine = upsample_nearest(coarse, shape)
        assert fine.dtype == coarse.dtype and fine.flags.c_contiguous
        np.testing.assert_array_equal(fine, coarse[..., rows[:, None], cols[None, :]])


@pytest.mark.parametrize("dtype", [np.uint8, np.int32])
@pytest.mark.parametrize("shape", [(4, 5, 7), (3, 1), (6, 9)])
def test_mirrored_reverses_the_last_axis_then_pads(dtype, shape):
    array = (np.random.default_rng(1).random(shape) * 200).astype(dtype)
    for view in (array, array[..., ::2]):  # contiguous or not
        for pad, fill in ((0, 0), (5, 255)):
            padding = np.full(view.shape[:-1] + (pad,), fill, dtype)
            got = mirrored(view, pad=pad, fill=fill)
            assert got.dtype == dtype and got.flags.c_contiguous
            np.testing.assert_array_equal(got, np.concatenate([view[..., ::-1], padding], -1))


@pytest.mark.data
@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs two threads")
@pytest.mark.parametrize("config", ["fast", "default", "accurate"])
def test_every_config_gives_the_same_bytes_on_one_thread_and_two(data_dir, config):
    """The kernels whose rows are dealt out (edges, filling, repeats) and the rest."""
    scene = datasets.load_dataset("middlebury2", data_dir, names=["cones"])[0]
    results = []
    for threads in (1, 2):
        with thread_count(threads):
            result = pipeline.run(scene.left, scene.right, max_disp=scene.max_disp,
                                  config=config)
        results.append((result.disparity.tobytes(), result.confidence.tobytes()))
    assert results[0] == results[1]


def test_a_match_runs_opencv_on_its_own_thread_and_sets_the_count_back(monkeypatch):
    import cv2

    from vsmatch import confidence, synthetic

    seen = []
    original = confidence.confidence_map

    def watched(*args, **kwargs):
        seen.append(cv2.getNumThreads())
        return original(*args, **kwargs)

    monkeypatch.setattr(confidence, "confidence_map", watched)
    pair = synthetic.make_pair(width=96, height=64)
    before = cv2.getNumThreads()
    cv2.setNumThreads(2)
    try:
        pipeline.run(pair.left, pair.right, max_disp=pair.max_disp, config="fast")
        assert seen == [1] and cv2.getNumThreads() == 2
    finally:
        cv2.setNumThreads(before)


def test_overlapping_blocks_set_opencv_back_when_the_last_one_ends():
    import threading

    import cv2

    from vsmatch.threads import opencv_on_this_thread

    before = cv2.getNumThreads()
    cv2.setNumThreads(2)
    first_in, second_in, first_out = threading.Event(), threading.Event(), threading.Event()
    inside = []

    def first():
        with opencv_on_this_thread():
            first_in.set()
            second_in.wait(5)
        first_out.set()

    def second():
        first_in.wait(5)
        with opencv_on_this_thread():
            second_in.set()
            first_out.wait(5)
            inside.append(cv2.getNumThreads())  # the first has ended, this one has not

    try:
        threads = [threading.Thread(target=first), threading.Thread(target=second)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join(10)
        assert inside == [1] and cv2.getNumThreads() == 2
    finally:
        cv2.setNumThreads(before)


def test_planes_are_taken_where_numpys_masks_take_them():
    from vsmatch._kernels.planes import take_planes

    rng = np.random.default_rng(2)
    shape = (29, 31)
    disp = (rng.random(shape) * 20).astype(np.float32)
    plane = disp + rng.normal(0, 1.5, shape).astype(np.float32)
    plane[rng.random(shape) < 0.2] = np.nan
    spread = (rng.random(shape) * 2).astype(np.float32)
    kept = rng.random(shape) < 0.6
    for fill in (True, False):
        out = np.empty_like(disp)
        take_planes(disp, kept, plane, spread, np.float32(1.0), np.float32(1.0), fill, out)
        with np.errstate(invalid="ignore"):
            take = (np.isfinite(plane) & (spread <= 1.0)
                    & ((~kept & fill) | (np.abs(disp - plane) <= 1.0)))
        assert out.tobytes() == np.where(take, plane, disp).tobytes()
        assert 0 < take.sum() < take.size
