"""The benchmark code works; it asserts no speed (timings are for vsmatch bench)."""

import json
import subprocess
import sys

import cv2

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
