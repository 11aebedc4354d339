import numpy as np
import pytest

from vsmatch import evaluation
from vsmatch.datasets import Scene


def test_add_noise_has_the_asked_sigma_and_stays_in_range():
    image = np.full((200, 200, 3), 128, np.uint8)
    noisy = evaluation.add_noise(image, 0.05, np.random.default_rng(0))
    assert noisy.dtype == np.uint8
    assert abs(noisy.astype(float).std() - 0.05 * 255) < 0.3
    assert abs(noisy.astype(float).mean() - 128) < 0.2
    clipped = evaluation.add_noise(np.full((50, 50), 250, np.uint8), 0.15,
                                   np.random.default_rng(0))
    assert clipped.max() == 255


def test_noisy_pairs_repeat_and_differ_by_seed_and_view():
    base = np.full((20, 30, 3), 100, np.uint8)
    scene = Scene("s", base, base, np.zeros((20, 30), np.float32), {}, 4)
    a1, b1 = evaluation.noisy_pair(scene, 0, 0.1, seed=0)
    a2, b2 = evaluation.noisy_pair(scene, 0, 0.1, seed=0)
    a3, _ = evaluation.noisy_pair(scene, 0, 0.1, seed=1)
    np.testing.assert_array_equal(a1, a2)
    np.testing.assert_array_equal(b1, b2)
    assert not np.array_equal(a1, b1) and not np.array_equal(a1, a3)


@pytest.mark.data
def test_noise_report_shape(data_dir):
    from vsmatch import datasets

    scenes = datasets.load_dataset("middlebury2", data_dir, names=["tsukuba"])
    report = evaluation.evaluate(scenes, {"census": "census"}, dataset="middlebury2")
    evaluation.evaluate_noise(scenes, {"census": "census"}, report, levels=[0.05], seeds=2)
    noise = report["methods"]["census"]["noise"]
    assert list(noise) == ["0.05"] and len(noise["0.05"]["per_seed"]) == 2
    per_seed = [s["nonocc"] for s in noise["0.05"]["per_seed"]]
    assert noise["0.05"]["avg"]["nonocc"] == pytest.approx(np.mean(per_seed))
    assert noise["0.05"]["avg"]["nonocc"] > report["methods"]["census"]["avg"]["nonocc"]
    assert "vs noise" in evaluation.format_noise_table(report)


@pytest.mark.parametrize("sigma", [0.0, 3.0, 8.0, 20.0])
def test_estimate_noise_recovers_added_grey_noise(sigma):
    from vsmatch.noise import estimate_noise

    rng = np.random.default_rng(0)
    ys, xs = np.mgrid[0:200, 0:240]
    clean = 60 + 0.3 * xs + 0.2 * ys  # a smooth ramp: no noise of its own
    noisy = clean + rng.standard_normal(clean.shape) * sigma
    image = np.clip(np.round(noisy), 0, 255).astype(np.uint8)
    assert estimate_noise(image) == pytest.approx(sigma, abs=0.15 * sigma + 0.5)


def test_adapt_to_noise_changes_nothing_below_the_floor_or_when_off():
    from vsmatch.config import config_from_dict
    from vsmatch.noise import adapt_to_noise, smoothed_noise_factor

    cfg = config_from_dict({"noise": {"adapt": True, "floor": 3.0, "tau_per_sigma": 2.0,
                                      "lambda_per_sigma": 0.1, "smooth_per_sigma": 0.1},
                            "cost": {"lambda_ad": 30.0, "lambda_gradient": 100.0}})
    assert adapt_to_noise(cfg, 2.9) == cfg
    off = config_from_dict({"noise": {"adapt": False}})
    assert adapt_to_noise(off, 20.0) == off
    noisy = adapt_to_noise(cfg, 7.0)  # past the ramp: full gain, smoothing 0.7
    residual = 7.0 * smoothed_noise_factor(0.7)
    assert noisy.cost.presmooth_sigma == pytest.approx(0.7)
    assert noisy.arms.tau1 == pytest.approx(cfg.arms.tau1 + 2.0 * residual)
    assert noisy.arms.tau3 == pytest.approx(cfg.arms.tau3 + 2.0 * residual)
    assert noisy.scanline.tau == pytest.approx(cfg.scanline.tau + 2.0 * residual)
    assert noisy.cost.lambda_ad == pytest.approx(30.0 + 2.0 * residual)
    assert noisy.cost.lambda_census == pytest.approx(cfg.cost.lambda_census
                                                     * (1 + 0.1 * residual))
    half = adapt_to_noise(cfg, 3.5)  # halfway up the ramp (floor 3, ramp 1)
    assert half.cost.presmooth_sigma == pytest.approx(0.5 * 0.1 * 3.5)
    assert noisy.arms.l2 == cfg.arms.l2  # noise.arms_l2 unset: the arms keep their length
    assert noisy.cost.census_like == 0  # off stays off
    like = config_from_dict({"noise": {"adapt": True, "floor": 3.0, "tau_per_sigma": 2.0,
                                       "smooth_per_sigma": 0.1}, "cost": {"census_like": 20}})
    assert adapt_to_noise(like, 7.0).cost.census_like == pytest.approx(20 + 2.0 * residual)


def test_noisy_views_get_the_longer_arms_of_noise_arms_l2():
    from vsmatch.config import ConfigError, config_from_dict
    from vsmatch.noise import adapt_to_noise

    cfg = config_from_dict({"noise": {"adapt": True, "floor": 3.0, "ramp": 1.0,
                                      "arms_l2": 40}, "arms": {"l1": 7, "l2": 20}})
    assert adapt_to_noise(cfg, 2.9).arms.l2 == 20
    assert adapt_to_noise(cfg, 3.5).arms.l2 == 30  # halfway up the ramp
    assert adapt_to_noise(cfg, 9.0).arms.l2 == 40
    with pytest.raises(ConfigError, match="noise.arms_l2"):
        config_from_dict({"noise": {"arms_l2": 5}, "arms": {"l1": 7, "l2": 20}})


@pytest.mark.parametrize("blur", [0.5, 1.0, 2.0])
def test_smoothed_noise_factor_matches_a_blurred_noise_field(blur):
    import cv2

    from vsmatch.noise import smoothed_noise_factor

    noise = np.random.default_rng(0).standard_normal((400, 400)).astype(np.float32) * 20
    blurred = cv2.GaussianBlur(noise, (int(round(blur * 6 + 1)) | 1,) * 2, blur)
    measured = blurred[20:-20, 20:-20].std() / noise.std()
    assert smoothed_noise_factor(blur) == pytest.approx(measured, rel=0.05)
    assert smoothed_noise_factor(0.0) == 1.0


def test_pipeline_reports_the_adapted_config(rng):
    from vsmatch import pipeline
    from vsmatch.config import config_from_dict

    from conftest import random_pair

    left, right = random_pair(rng, height=40, width=60, shift=3)
    cfg = config_from_dict({"noise": {"adapt": True, "floor": 0.0}})
    result = pipeline.run(left, right, max_disp=6, config=cfg)
    assert result.noise_sigma > 0 and result.config.arms.tau1 > cfg.arms.tau1


def test_the_noise_is_measured_once_per_pair_whatever_the_levels_and_stripes(rng, monkeypatch):
    """Measured on the input views only: every level and stripe adapts to that one figure
    (a level down, scaled as ``cv2.pyrDown`` scales white noise)."""
    from vsmatch import noise, pipeline, scale
    from vsmatch.config import config_from_dict, load_config

    from conftest import random_pair

    measured = []
    real = noise.estimate_noise
    monkeypatch.setattr(noise, "estimate_noise", lambda image: measured.append(image.shape)
                        or real(image))
    left, right = random_pair(rng, height=96, width=160, shift=3)
    cfg = config_from_dict({"noise": {"adapt": True, "floor": 0.0},
                            "pyramid": {"min_levels": 1}, "memory": {"overlap": 8}},
                           base=load_config("fast"))
    monkeypatch.setattr(scale, "stripe_rows", lambda *args: 40)  # stripes of a small pair
    result = pipeline.run(left, right, max_disp=24, config=cfg)
    assert result.levels == 1 and result.stripes > 1
    assert measured == [left.shape, right.shape]
    sigma = noise.estimate_pair_noise(left, right)
    assert result.noise_sigma == sigma
    assert result.config == noise.adapt_to_noise(cfg, sigma)  # the full size's, reported


def test_a_level_down_white_noise_shrinks_as_the_pyramid_factor_says():
    import cv2

    from vsmatch.noise import LEVEL_NOISE_FACTOR

    field = np.random.default_rng(0).standard_normal((600, 600)).astype(np.float32) * 20
    measured = cv2.pyrDown(field)[10:-10, 10:-10].std() / field.std()
    assert LEVEL_NOISE_FACTOR == pytest.approx(measured, rel=0.03)


@pytest.mark.parametrize("shape", [(61, 83, 3), (40, 40), (9, 200, 3), (12, 7)])
def test_the_block_means_kernel_gives_numpys_estimate(rng, shape):
    """The noise estimate's block means come from a parallel kernel that works out the
    operator's responses as it sums them; on 8-bit views (integer responses, exact sums)
    the estimate is NumPy's (OpenCV's filter, then block means) to the last bit."""
    import cv2

    from vsmatch import noise
    from vsmatch.images import to_grey

    view = np.clip(rng.normal(120, 40, shape), 0, 255).astype(np.uint8)
    response = np.abs(cv2.filter2D(to_grey(view), -1, noise._NOISE_KERNEL))[1:-1, 1:-1]
    height, width = (n - n % 8 for n in response.shape)
    if height and width:
        means = response[:height, :width].reshape(height // 8, 8, width // 8, 8).mean(
            axis=(1, 3))
    else:
        means = np.array([response.mean()])
    expected = np.sqrt(np.pi / 2) * np.percentile(means, 2.0) / 6.0 / noise._PERCENTILE_BIAS
    assert noise.estimate_noise(view) == float(expected)
