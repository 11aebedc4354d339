"""The benchmark code works; it asserts no speed (timings are for vsmatch bench)."""

import json
import os
import subprocess
import sys

import cv2
import numpy as np
import pytest

from vsmatch import bench, synthetic
from vsmatch.datasets import Scene
from vsmatch.evaluation import Scoring


def _synthetic_report(configs):
    pair = synthetic.make_pair(width=96, height=64)
    scene = Scene("synthetic", pair.left, pair.right, pair.disparity,
                  {"nonocc": pair.nonocc, "all": pair.nonocc}, 40)
    return bench.time_pairs([(scene, Scoring.bad(1.0))], configs, rounds=1)


def test_time_pairs_reports_each_config_and_sgbm_mode_per_scene():
    result = _synthetic_report(["paper", "fast"])
    assert result["methods"] == ["paper", "fast", "sgbm-5", "sgbm-hh", "sgbm-3way"]
    timing = result["scenes"]["synthetic"]
    assert all(timing[m]["seconds"] > 0 for m in result["methods"])
    assert {"cost", "aggregation", "wta"} <= set(timing["paper"]["stages"])
    assert "bands" in timing["fast"]["stages"]  # fast searches bands at full size
    total = result["total"]
    assert total["paper"]["x_sgbm-hh"] == timing["paper"]["seconds"] / timing["sgbm-hh"][
        "seconds"]
    # The synthetic pair is easy for vsmatch, and SGBM's empty left margin counts as bad.
    assert total["paper"]["error"] < 5 < total["sgbm-hh"]["error"]
    # Sub-pixel precision beside the headline (issue 27): bad 0.5 and the integer share.
    assert total["paper"]["error"] <= total["paper"]["bad0.5"] <= 100
    assert 0 <= total["fast"]["integer_share"] <= 1


def test_the_tradeoff_plot_names_every_method(tmp_path):
    result = _synthetic_report(["paper"])
    image = bench.tradeoff_figure({"pairs": result})
    assert image.ndim == 3 and image.dtype == np.uint8
    blue = (image[..., 0] > 150) & (image[..., 2] < 50)  # vsmatch's points and names
    grey = (image[..., 0] == 150) & (image[..., 1] == 150)  # SGBM's
    assert blue.sum() > 50 and grey.sum() > 150


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
    left, _, gt_half, _, max_disp = bench.upscaled_scene(scene, 2.5)
    assert left.shape == (75, 100, 3) and max_disp == 32  # 13 levels cover 32.5
    assert gt_half.max() == pytest.approx(pair.disparity.max() * 2.5)
    np.testing.assert_array_equal(gt[::2, ::2], pair.disparity * 2)
    np.testing.assert_array_equal(mask[1::2, 1::2], pair.nonocc)


@pytest.mark.data
def test_size_child_reports_time_memory_and_accuracy(data_dir):
    proc = subprocess.run([sys.executable, "-m", "vsmatch.bench", "size", "--matcher",
                           "sgbm-5", "--scale", "1", "--data-root", str(data_dir)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout.splitlines()[-1])
    assert report["size"] == [718, 496] and report["levels"] == 73
    assert report["threshold"] == 2.0 and 5 < report["bad_nonocc"] < 40
    assert report["peak_mb"] >= report["before_match_mb"] > 0 and report["seconds"] > 0
    # The system's share, within the match's time on at most this machine's cores.
    assert 0 <= report["system_seconds"] <= report["seconds"] * (os.cpu_count() or 1) + 0.05
    tall = subprocess.run([sys.executable, "-m", "vsmatch.bench", "size", "--matcher",
                           "sgbm-5", "--scale", "1", "--tall", "--data-root", str(data_dir)],
                          capture_output=True, text=True)
    assert tall.returncode == 0, tall.stderr
    tall_report = json.loads(tall.stdout.splitlines()[-1])
    assert tall_report["size"] == [718, 992] and tall_report["tall"] is True
    # The lower half is the upper one upside down: the same errors, the same share.
    assert abs(tall_report["bad_nonocc"] - report["bad_nonocc"]) < 1.0
    label, dataset, scene, scale = bench.SIZE_SERIES[1]
    kitti = subprocess.run([sys.executable, "-m", "vsmatch.bench", "size", "--matcher",
                            "sgbm-5", "--dataset", dataset, "--scene", scene, "--scale",
                            str(scale), "--data-root", str(data_dir)],
                           capture_output=True, text=True)
    assert kitti.returncode == 0, kitti.stderr
    kitti_report = json.loads(kitti.stdout.splitlines()[-1])
    assert label == "KITTI" and kitti_report["size"] == [1242, 375]
    assert kitti_report["levels"] == 192 and 5 < kitti_report["bad_nonocc"] < 60


def test_a_child_does_not_report_its_parents_memory():
    import numpy as np

    held = np.ones((400, 1024, 1024), np.uint8)  # this process: 400 MB more
    code = "from vsmatch import bench; print(bench._peak_rss_mb())"
    peak = float(subprocess.run([sys.executable, "-c", code], capture_output=True,
                                text=True, check=True).stdout)
    assert 0 < peak < 300 and held.sum() > 0


def test_bench_refuses_a_plot_that_is_not_png_before_any_work(tmp_path):
    from click.testing import CliRunner

    from vsmatch.cli import main

    result = CliRunner().invoke(main, ["bench", "--plot", str(tmp_path / "p.jpg")])
    assert result.exit_code == 2 and "--plot" in result.output and ".png" in result.output
    result = CliRunner().invoke(main, ["bench", "--config", "nonesuch", "--no-size"])
    assert result.exit_code == 1 and "nonesuch" in result.output
    assert not list(tmp_path.iterdir())


def test_thread_series_times_each_count_and_sets_the_threads_back():
    """--threads: every method at every count, the counts taken in turn within a round;
    each count's totals, the speed-ups and each stage's in the printed table; and the
    threads as they were afterwards."""
    import numba

    before = numba.get_num_threads(), cv2.getNumThreads()
    pair = synthetic.make_pair(width=96, height=64)
    scene = Scene("synthetic", pair.left, pair.right, pair.disparity,
                  {"nonocc": pair.nonocc, "all": pair.nonocc}, 40)
    counts = sorted({1, bench.max_threads()})
    done = []
    result = bench.time_pairs([(scene, Scoring.bad(1.0)), (scene, Scoring.bad(1.0))], ["fast"],
                              rounds=1, threads=counts, on_done=done.append)
    assert done == ["synthetic", "synthetic"]  # the progress: a call a pair
    assert (numba.get_num_threads(), cv2.getNumThreads()) == before
    assert result["threads"] == counts
    series = result["by_threads"]
    for n in counts:
        assert series[n]["total"]["fast"]["seconds"] > 0
        assert "x_sgbm-3way" in series[n]["total"]["fast"]
        assert "aggregation" in series[n]["total"]["fast"]["stages"]
    assert result["total"] is series[counts[-1]]["total"]
    lines = bench.format_threads(result)
    assert any(line.startswith("fast speed-up") for line in lines)
    stage_rows = [line for line in lines if line.strip().startswith("aggregation")]
    assert len(stage_rows) == 1 and stage_rows[0].count("%") == len(counts)


def test_bench_refuses_thread_counts_it_cannot_set_before_any_work(tmp_path):
    from click.testing import CliRunner

    from vsmatch.cli import main

    runner = CliRunner()
    for value, message in (("1,x", "'x' is not a thread count"),
                           (f"1,{bench.max_threads() + 1}", "this process can use 1 to")):
        result = runner.invoke(main, ["bench", "--threads", value, "--json",
                                      str(tmp_path / "b.json")])
        assert result.exit_code == 2 and message in result.output
        assert not (tmp_path / "b.json").exists()


def test_the_progress_counts_every_step_of_the_benchmark(data_dir, monkeypatch):
    """`vsmatch bench` runs for minutes: its bar's total is the calls run_benchmark makes."""
    calls = []

    def time_pairs(pairs, *args, on_done=None, **kwargs):  # the pairs' calls, no timing
        for scene, _ in pairs:
            on_done(scene.name)
        return {}

    monkeypatch.setattr(bench, "time_pairs", time_pairs)
    monkeypatch.setattr(bench, "run_command", lambda *a: {})
    monkeypatch.setattr(bench, "memory", lambda *a: {})
    monkeypatch.setattr(bench, "cold_start", lambda *a: {})
    monkeypatch.setattr(bench, "size_run", lambda *a, **k: {})
    totals = []
    bench.run_benchmark(data_dir, ["fast"], 1, on_done=calls.append, on_total=totals.append)
    assert totals == [len(calls)] and len(calls) > len(bench.standard_pairs(data_dir))
