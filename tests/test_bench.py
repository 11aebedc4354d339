"""The benchmark code works; it asserts no speed (timings are for vsmatch bench)."""

import json
import subprocess
import sys

import cv2
import pytest

from vsmatch import bench, synthetic
from vsmatch.datasets import Scene


def test_time_pairs_reports_both_matchers_per_scene():
    pair = synthetic.make_pair(width=96, height=64)
    scene = Scene("synthetic", pair.left, pair.right, pair.disparity,
                  {"nonocc": pair.nonocc}, 40)
    result = bench.time_pairs([scene], "paper", repeats=1)
    timing = result["scenes"]["synthetic"]
    assert timing["vsmatch"] > 0 and timing["sgbm"] > 0
    assert {"cost", "aggregation", "wta"} <= set(timing["stages"])
    assert result["total"]["ratio"] == timing["vsmatch"] / timing["sgbm"]


def test_sgbm_range_covers_the_disparities():
    assert bench.sgbm_matcher(59).getNumDisparities() == 64
    assert bench.sgbm_matcher(15).getNumDisparities() == 16


def test_child_reports_time_and_memory(tmp_path):
    pair = synthetic.make_pair(width=96, height=64)
    cv2.imwrite(str(tmp_path / "l.png"), pair.left)
    cv2.imwrite(str(tmp_path / "r.png"), pair.right)
    proc = subprocess.run([sys.executable, "-m", "vsmatch.bench", "match",
                           str(tmp_path / "l.png"), str(tmp_path / "r.png"), "40",
                           "--scale", "2"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout.splitlines()[-1])
    assert report["size"] == [192, 128] and report["levels"] == 41
    assert report["peak_mb"] >= report["before_match_mb"] > 0
    assert report["first_call_seconds"] > 0 and report["match_seconds"] > 0
    assert report["cost_volume_mb"] == 192 * 128 * 41 * 4 / 2 ** 20
    text = bench._memory_line("x", report)
    assert "x the cost volume" in text


def test_upscaled_scene_scales_views_truth_and_range():
    import numpy as np

    pair = synthetic.make_pair(width=40, height=30)
    scene = Scene("s", pair.left, pair.right, pair.disparity, {"nonocc": pair.nonocc}, 12)
    left, right, gt, mask, max_disp = bench.upscaled_scene(scene, 2)
    assert left.shape == (60, 80, 3) and right.shape == left.shape
    assert max_disp == 25  # 13 levels become 26
    np.testing.assert_array_equal(gt[::2, ::2], pair.disparity * 2)
    np.testing.assert_array_equal(mask[1::2, 1::2], pair.nonocc)


@pytest.mark.data
def test_size_child_reports_time_memory_and_accuracy(data_dir):
    proc = subprocess.run([sys.executable, "-m", "vsmatch.bench", "size", "--matcher",
                           "sgbm-5", "--factor", "1", "--data-root", str(data_dir)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout.splitlines()[-1])
    assert report["size"] == [718, 496] and report["levels"] == 73
    assert report["threshold"] == 2.0 and 5 < report["bad_nonocc"] < 40
    assert report["peak_mb"] >= report["before_match_mb"] > 0 and report["seconds"] > 0
    tall = subprocess.run([sys.executable, "-m", "vsmatch.bench", "size", "--matcher",
                           "sgbm-5", "--factor", "1", "--tall", "--data-root", str(data_dir)],
                          capture_output=True, text=True)
    assert tall.returncode == 0, tall.stderr
    tall_report = json.loads(tall.stdout.splitlines()[-1])
    assert tall_report["size"] == [718, 992] and tall_report["tall"] is True
    # The lower half is the upper one upside down: the same errors, the same share.
    assert abs(tall_report["bad_nonocc"] - report["bad_nonocc"]) < 1.0


def test_a_child_does_not_report_its_parents_memory():
    import numpy as np

    held = np.ones((400, 1024, 1024), np.uint8)  # this process: 400 MB more
    code = "from vsmatch import bench; print(bench._peak_rss_mb())"
    peak = float(subprocess.run([sys.executable, "-c", code], capture_output=True,
                                text=True, check=True).stdout)
    assert 0 < peak < 300 and held.sum() > 0
