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
