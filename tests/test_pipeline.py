import numpy as np
import pytest

import vsmatch
from vsmatch import pipeline, synthetic
from vsmatch.config import Config, config_from_dict

from conftest import random_pair


@pytest.mark.parametrize("config", ["paper", "census", "default"])
def test_identical_images_give_zero_disparity(rng, config):
    image = rng.integers(0, 256, size=(30, 40, 3), dtype=np.uint8)
    disp = vsmatch.match(image, image.copy(), max_disp=8, config=config)
    assert disp.dtype == np.float32 and disp.shape == (30, 40)
    assert np.all(disp == 0)


@pytest.mark.parametrize("shift", [1, 3, 6])
@pytest.mark.parametrize("config", ["paper", "census", "default"])
def test_shifted_right_image_gives_the_shift(rng, shift, config):
    left, right = random_pair(rng, height=30, width=48, shift=shift)
    disp = vsmatch.match(left, right, max_disp=10, config=config)
    interior = disp[5:-5, 15:-5]  # away from the border columns without a match
    if config == "census":
        # A pixel darker than its whole window has census 0, as may another nearby:
        # census alone has ties that only aggregation resolves.
        assert np.mean(interior == shift) > 0.99
    elif config == "default":  # sub-pixel: within half a pixel
        assert np.all(np.abs(interior - shift) < 0.5)
    else:
        assert np.all(interior == shift)


def test_grey_input_is_accepted(rng):
    left, right = random_pair(rng, height=24, width=40, shift=4, channels=1)
    disp = vsmatch.match(left[..., 0], right[..., 0], max_disp=8, config="paper")
    assert np.all(disp[5:-5, 15:-5] == 4)


def test_synthetic_pair_is_matched_well():
    pair = synthetic.make_pair()
    disp = vsmatch.match(pair.left, pair.right, max_disp=pair.max_disp)
    bad = np.abs(disp - pair.disparity) > 1.0
    assert bad[pair.nonocc].mean() < 0.001  # measured 0.02 %; a pipeline short of stages misses


def test_synthetic_pair_ground_truth_is_consistent():
    pair = synthetic.make_pair(width=200, height=120, seed=3)
    assert 0.8 < pair.nonocc.mean() < 1.0
    assert pair.disparity.min() >= 6 and pair.disparity.max() <= pair.max_disp


def test_without_fill_rejected_pixels_are_invalid(rng):
    left, right = random_pair(rng, height=24, width=40, shift=5)
    cfg = config_from_dict({"fill": {"enabled": False}}, base=vsmatch.load_config("paper"))
    result = pipeline.run(left, right, max_disp=8, config=cfg)
    rejected = result.labels != 0
    assert rejected[:, :5].mean() > 0.5  # no right pixel exists there at the true shift
    assert not rejected[:, 10:-10].any()
    assert np.all(np.isinf(result.disparity[rejected]))
    assert np.all(result.disparity[~rejected] == np.round(result.disparity[~rejected]))


def test_run_reports_stage_times(rng):
    left, right = random_pair(rng, height=16, width=24)
    result = pipeline.run(left, right, max_disp=4, config="paper")
    assert set(result.seconds) == {"cost", "arms", "aggregation", "wta", "consistency", "fill",
                                   "confidence"}


@pytest.mark.parametrize("kwargs,message", [
    (dict(max_disp=0), "max_disp = 0"),
    (dict(max_disp=40), "max_disp = 40"),
    (dict(max_disp=2.5), "max_disp must be an integer"),
])
def test_bad_max_disp_is_refused(rng, kwargs, message):
    image = rng.integers(0, 256, size=(20, 40, 3), dtype=np.uint8)
    with pytest.raises(ValueError, match=message):
        vsmatch.match(image, image, **kwargs)


def test_mismatched_sizes_and_tiny_images_are_refused(rng):
    a = rng.integers(0, 256, size=(20, 40, 3), dtype=np.uint8)
    with pytest.raises(ValueError, match="differ in size"):
        vsmatch.match(a, a[:, :30], max_disp=4)
    tiny = a[:5, :8]
    with pytest.raises(ValueError, match="smaller than the census window"):
        vsmatch.match(tiny, tiny, max_disp=2, config=Config())
    with pytest.raises(ValueError, match="must be uint8"):
        vsmatch.match(a.astype(np.float32), a.astype(np.float32), max_disp=4)


@pytest.mark.parametrize("aggregate, calls", [(True, 2), (False, 1)])
def test_bands_aggregation_switches_the_finer_levels_aggregation_only(rng, monkeypatch,
                                                                      aggregate, calls):
    from vsmatch import aggregation
    from vsmatch.config import load_config

    shapes = []
    real = aggregation.aggregate_cross

    def counted(volume, *args, **kwargs):
        shapes.append(volume.shape)
        return real(volume, *args, **kwargs)

    monkeypatch.setattr(aggregation, "aggregate_cross", counted)
    left, right = random_pair(rng, height=64, width=160, shift=6)
    cfg = config_from_dict({"bands": {"aggregation": aggregate}}, base=load_config("fast"))
    result = pipeline.run(left, right, max_disp=24, config=cfg)
    assert result.levels == 1 and len(shapes) == calls
    assert shapes[0][:2] == (32, 80)  # the coarse level's full search always aggregates


def _match_in_worker(seed):
    pair = synthetic.make_pair(width=96, height=64, seed=seed)
    return float(np.nanmean(vsmatch.match(pair.left, pair.right, max_disp=pair.max_disp,
                                          config="fast")))


def test_a_fork_pool_after_a_match_gets_an_error_not_a_hang():
    """On GNU OpenMP (Numba's layer unless TBB is there), a child forked after a match dies
    at its first kernel and a multiprocessing pool waits for ever. The match in such a
    child is refused, naming the way out, so the pool's caller gets the error; on a layer
    that survives fork() the child matches."""
    import multiprocessing

    import numba

    pair = synthetic.make_pair(width=96, height=64)
    vsmatch.match(pair.left, pair.right, max_disp=pair.max_disp, config="fast")
    gnu_openmp = numba.threading_layer() == "omp"
    if gnu_openmp:
        from numba.np.ufunc import omppool
        gnu_openmp = getattr(omppool, "openmp_vendor", "GNU") == "GNU"
    with multiprocessing.get_context("fork").Pool(1) as pool:
        outcome = pool.apply_async(_match_in_worker, (1,))
        if gnu_openmp:
            with pytest.raises(vsmatch.ForkedProcessError, match="get_context\\('spawn'\\)"):
                outcome.get(timeout=120)
        else:
            assert np.isfinite(outcome.get(timeout=120))
    # The process that matched first matches on.
    assert np.isfinite(_match_in_worker(2))
