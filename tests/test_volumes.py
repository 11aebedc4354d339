import numpy as np

from vsmatch import pipeline, volumes
from vsmatch.matcher import StereoMatcher

from conftest import random_pair


def test_a_pool_hands_out_its_memory_again_and_grows_when_asked():
    pool = volumes.VolumePool()
    with volumes.reused(pool):
        first = volumes.volume("cost", (4, 5, 6))
        again = volumes.volume("cost", (3, 5, 6))
        other = volumes.volume("work", (4, 5, 6))
        bigger = volumes.volume("cost", (9, 5, 6))
    assert np.shares_memory(first, again) and not np.shares_memory(first, other)
    assert bigger.shape == (9, 5, 6) and bigger.flags.c_contiguous
    outside = volumes.volume("cost", (4, 5, 6))  # no pool: a new array
    assert not np.shares_memory(outside, bigger)


def test_reused_volumes_give_the_same_bytes(rng):
    """Larger, then smaller, then a different range: the stale cells of the last match
    must never show through."""
    pairs = [random_pair(rng, height=40, width=64, shift=5),
             random_pair(rng, height=30, width=48, shift=3),
             random_pair(rng, height=30, width=48, shift=2)]
    ranges = [12, 6, 9]
    fresh = [pipeline.run(a, b, max_disp=m, config="default") for (a, b), m in zip(pairs, ranges)]
    with volumes.reused():
        again = [pipeline.run(a, b, max_disp=m, config="default")
                 for (a, b), m in zip(pairs, ranges)]
    for a, b in zip(fresh, again):
        assert a.disparity.tobytes() == b.disparity.tobytes()
        assert a.confidence.tobytes() == b.confidence.tobytes()


def test_a_stream_matcher_keeps_its_volumes_between_frames(rng):
    left, right = random_pair(rng, height=30, width=48, shift=3)
    matcher = StereoMatcher(max_disp=8)
    first = matcher.compute(left, right).copy()
    held = dict(matcher._volumes._held)
    second = matcher.compute(left, right)
    assert held and all(matcher._volumes._held[k] is v for k, v in held.items())
    assert first.tobytes() == second.tobytes()
