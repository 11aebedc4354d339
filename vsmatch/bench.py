"""Speed and memory of vsmatch against OpenCV's StereoSGBM (EVALUATION.md, "Speed").

Timings of the matching itself come from one process, vsmatch and SGBM alternating on the
same images after a warm-up call, so the ratio holds on a shared, noisy machine. Start-up
and memory are measured in child processes: a first call with an empty compilation cache,
the whole ``vsmatch run`` command with a warm cache, and the peak resident memory of a
pair and of the scaling run (cones upsampled 3x, 180 disparities).
"""

from __future__ import annotations

import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import cv2

from . import datasets, pipeline
from .peers import sgbm_matcher
from .config import load_config

SCALING_FACTOR = 3
SCALING_LEVELS = 180


def time_pairs(scenes, config, repeats: int) -> dict[str, Any]:
    """Median seconds per scene of vsmatch (with stage times) and SGBM, alternating."""
    cfg = load_config(config)
    warm = scenes[0]
    pipeline.run(warm.left, warm.right, max_disp=warm.max_disp, config=cfg)  # compile
    per_scene = {}
    for scene in scenes:
        sgbm = sgbm_matcher(scene.max_disp)
        sgbm.compute(scene.left, scene.right)
        ours, theirs, stages = [], [], []
        for _ in range(repeats):
            start = time.perf_counter()
            result = pipeline.run(scene.left, scene.right, max_disp=scene.max_disp, config=cfg)
            ours.append(time.perf_counter() - start)
            stages.append(result.seconds)
            start = time.perf_counter()
            sgbm.compute(scene.left, scene.right)
            theirs.append(time.perf_counter() - start)
        per_scene[scene.name] = {
            "vsmatch": statistics.median(ours), "sgbm": statistics.median(theirs),
            "stages": {k: statistics.median(s[k] for s in stages) for k in stages[0]}}
    total_ours = sum(s["vsmatch"] for s in per_scene.values())
    total_sgbm = sum(s["sgbm"] for s in per_scene.values())
    stage_totals = {}
    for s in per_scene.values():
        for k, v in s["stages"].items():
            stage_totals[k] = stage_totals.get(k, 0.0) + v
    return {"scenes": per_scene, "total": {"vsmatch": total_ours, "sgbm": total_sgbm,
                                           "ratio": total_ours / total_sgbm,
                                           "stages": stage_totals}}


def _run_child(args: list[str], env: dict[str, str] | None = None) -> dict[str, Any]:
    """Run ``python -m vsmatch.bench ...`` and return the JSON it prints last."""
    proc = subprocess.run([sys.executable, "-m", "vsmatch.bench", *args], env=env,
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"benchmark child failed: {proc.stderr.strip().splitlines()[-1:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def cold_start(left: Path, right: Path, max_disp: int, config: str | None) -> dict[str, Any]:
    """First call in a fresh process with an empty compilation cache (compiles every
    kernel), and in a second process with that cache filled (loads them); the child makes
    that first call on a small crop, so the figure is start-up, not matching."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        args = ["match", str(left), str(right), str(max_disp), "--config", config or "default"]
        empty = _run_child(args, env)
        filled = _run_child(args, env)
    return {"empty_cache": empty, "warm_cache": filled}


def run_command(left: Path, right: Path, max_disp: int, config: str | None,
                repeats: int) -> dict[str, float]:
    """Wall time of the whole ``vsmatch run`` command (start-up, reading, matching,
    writing) with a warm compilation cache; the median of ``repeats`` after one warm-up."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "vsmatch", "--quiet", "run", str(left), str(right),
               "-o", str(Path(tmp) / "d.pfm"), "--max-disp", str(max_disp),
               "--config", config or "default"]
        times = []
        for _ in range(repeats + 1):
            start = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True)
            times.append(time.perf_counter() - start)
    return {"seconds": statistics.median(times[1:])}


def memory(left: Path, right: Path, max_disp: int, config: str | None,
           scale: int = 1) -> dict[str, Any]:
    """Time and peak resident memory of one match in a child process (warm cache)."""
    args = ["match", str(left), str(right), str(max_disp), "--config", config or "default",
            "--scale", str(scale)]
    _run_child(args)  # fill the cache for this shape of call
    return _run_child(args)


def _current_rss_mb() -> float:
    """Resident memory now (Linux), else the peak so far."""
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20
    except (OSError, ValueError, IndexError):
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _child_match(argv: list[str]) -> None:
    """Child entry: match one pair and print time and memory as JSON."""
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("left")
    ap.add_argument("right")
    ap.add_argument("max_disp", type=int)
    ap.add_argument("--config", default="default")
    ap.add_argument("--scale", type=int, default=1)
    args = ap.parse_args(argv)
    start = time.perf_counter()
    from . import io

    left, right = io.read_image(args.left), io.read_image(args.right)
    if args.scale != 1:
        size = (left.shape[1] * args.scale, left.shape[0] * args.scale)
        left = cv2.resize(left, size, interpolation=cv2.INTER_CUBIC)
        right = cv2.resize(right, size, interpolation=cv2.INTER_CUBIC)
    # Load every compiled kernel on a small crop first, so that ``before`` holds the code
    # and the peak above it is what matching this pair needs.
    crop = (slice(0, 48), slice(0, 64))
    first = time.perf_counter()
    pipeline.run(left[crop], right[crop], max_disp=min(args.max_disp, 16), config=args.config)
    first_call = time.perf_counter() - first  # compiles, or loads from the cache, every kernel
    before = _current_rss_mb()
    ready = time.perf_counter()
    result = pipeline.run(left, right, max_disp=args.max_disp, config=args.config)
    done = time.perf_counter()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    volume_mb = left.shape[0] * left.shape[1] * (args.max_disp + 1) * 4 / 2 ** 20
    print(json.dumps({"size": [left.shape[1], left.shape[0]], "levels": args.max_disp + 1,
                      "first_call_seconds": first_call,
                      "match_seconds": done - ready, "process_seconds": done - start,
                      "peak_mb": peak, "before_match_mb": before,
                      "cost_volume_mb": volume_mb, "stages": result.seconds}))


def run_benchmark(data_root=None, config: str | None = None, repeats: int = 5,
                  cold: bool = True, scaling: bool = True) -> dict[str, Any]:
    """Everything :mod:`vsmatch.bench` measures, as one JSON-ready dict."""
    import numba

    scenes = datasets.load_dataset("middlebury2", data_root)
    folder = datasets.dataset_folder("middlebury2", data_root) / "cones"
    left, right = folder / "imL.png", folder / "imR.png"
    cones_disp = datasets.middlebury2.SCENES["cones"][1]
    report: dict[str, Any] = {
        "config": config or "default",
        "threads": {"numba": numba.get_num_threads(), "opencv": cv2.getNumThreads()},
        "pairs": time_pairs(scenes, config, repeats),
        "run_command_cones": run_command(left, right, cones_disp, config, 3),
        "memory_cones": memory(left, right, cones_disp, config)}
    if cold:
        report["cold_start_cones"] = cold_start(left, right, cones_disp, config)
    if scaling:
        report["scaling"] = memory(left, right, SCALING_LEVELS - 1, config, SCALING_FACTOR)
    return report


def _memory_line(name: str, mem: dict[str, Any]) -> str:
    extra = mem["peak_mb"] - mem["before_match_mb"]
    return (f"{name} peak memory: {mem['peak_mb']:.0f} MB; matching adds {extra:.0f} MB "
            f"= {extra / mem['cost_volume_mb']:.1f} x the cost volume "
            f"({mem['cost_volume_mb']:.0f} MB)")


def format_report(report: dict[str, Any]) -> str:
    """The printed tables."""
    lines = [f"config {report['config']}; threads: numba {report['threads']['numba']}, "
             f"opencv {report['threads']['opencv']}", "",
             f"{'pair':<10}{'vsmatch s':>11}{'SGBM HH s':>11}{'ratio':>8}"]
    pairs = report["pairs"]
    for name, s in pairs["scenes"].items():
        lines.append(f"{name:<10}{s['vsmatch']:11.3f}{s['sgbm']:11.3f}"
                     f"{s['vsmatch'] / s['sgbm']:8.2f}")
    t = pairs["total"]
    lines.append(f"{'total':<10}{t['vsmatch']:11.3f}{t['sgbm']:11.3f}{t['ratio']:8.2f}")
    lines += ["", "stage seconds, sum over the pairs:"]
    for name, sec in sorted(t["stages"].items(), key=lambda kv: -kv[1]):
        lines.append(f"  {name:<14}{sec:8.3f}")
    run = report["run_command_cones"]
    mem = report["memory_cones"]
    lines += ["", f"vsmatch run on cones, warm cache, whole command: {run['seconds']:.2f} s",
              _memory_line("cones", mem)]
    if "cold_start_cones" in report:
        cold = report["cold_start_cones"]
        lines.append(f"first call in a fresh process (a small crop): empty compilation cache "
                     f"{cold['empty_cache']['first_call_seconds']:.1f} s, cache filled "
                     f"{cold['warm_cache']['first_call_seconds']:.2f} s")
    if "scaling" in report:
        sc = report["scaling"]
        lines.append(f"scaling, cones x{SCALING_FACTOR} ({sc['size'][0]}x{sc['size'][1]}, "
                     f"{sc['levels']} disparities): {sc['match_seconds']:.1f} s")
        lines.append(_memory_line("scaling", sc))
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "match":
        _child_match(sys.argv[2:])
    else:
        sys.exit("usage: python -m vsmatch.bench match LEFT RIGHT MAX_DISP [--config C] "
                 "[--scale N]  (the CLI entry is 'vsmatch bench')")
