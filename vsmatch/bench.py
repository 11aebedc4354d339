"""Speed and memory of vsmatch against OpenCV's StereoSGBM (EVALUATION.md, "Speed").

Timings of the matching itself come from one process, vsmatch and SGBM alternating on the
same images after a warm-up call, so the ratio holds on a shared, noisy machine: the
twelve standard pairs (the four middlebury2 pairs and the eight Middlebury 2014 pairs at
quarter size, each with its official range). Start-up and memory are measured in child
processes: a first call with an empty compilation cache, the whole ``vsmatch run`` command
with a warm cache, the peak resident memory of a pair, and the size series: Adirondack
(Middlebury 2014) upscaled 1x, 2x and 4x (bicubic; ground truth x factor, nearest), matched
by vsmatch and by SGBM in its 5-direction and HH modes, with time, peak memory and bad
(2 x factor) on the non-occluded pixels, and vsmatch on the 4x pair with its upside-down
copy below it (twice as tall: does memory grow with the height?).
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
import numpy as np

from . import datasets, pipeline
from .peers import sgbm_matcher
from .config import load_config

#: The pairs timed against SGBM HH in one process.
STANDARD_DATASETS = ("middlebury2", "middlebury2014-quarter")
#: The size series: a scene upscaled by each factor, and the matchers run on it.
SIZE_DATASET, SIZE_SCENE = "middlebury2014-quarter", "Adirondack"
SIZE_FACTORS = (1, 2, 4)
SIZE_MATCHERS = ("vsmatch", "sgbm-5", "sgbm-hh")
SGBM_MODES = {"sgbm-5": cv2.STEREO_SGBM_MODE_SGBM, "sgbm-hh": cv2.STEREO_SGBM_MODE_HH}


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


def _peak_rss_mb() -> float:
    """Peak resident memory of this process (Linux: VmHWM). Not ru_maxrss: a child started
    by a large parent can report the parent's size there."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except (OSError, ValueError, IndexError):
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


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
    peak = _peak_rss_mb()
    volume_mb = left.shape[0] * left.shape[1] * (args.max_disp + 1) * 4 / 2 ** 20
    print(json.dumps({"size": [left.shape[1], left.shape[0]], "levels": args.max_disp + 1,
                      "first_call_seconds": first_call,
                      "match_seconds": done - ready, "process_seconds": done - start,
                      "peak_mb": peak, "before_match_mb": before,
                      "cost_volume_mb": volume_mb, "stages": result.seconds}))


def size_run(data_root, matcher: str, factor: int, config: str | None,
             tall: bool = False) -> dict[str, Any]:
    """One matcher on the size-series scene upscaled ``factor`` times (``tall``: with its
    upside-down copy below it, twice as tall), in a child process (warm cache): seconds,
    peak memory and bad (2 x factor) on non-occluded pixels."""
    args = ["size", "--matcher", matcher, "--factor", str(factor),
            "--config", config or "default"] + (["--tall"] if tall else [])
    if data_root is not None:
        args += ["--data-root", str(data_root)]
    if matcher == "vsmatch":
        _run_child(args)  # fill the cache for this shape of call
    return _run_child(args)


def upscaled_scene(scene, factor: int):
    """The scene ``factor`` times larger: views bicubic, ground truth and mask nearest,
    disparities and range times ``factor``."""
    if factor == 1:
        return scene.left, scene.right, scene.ground_truth, scene.masks["nonocc"], \
            scene.max_disp
    size = (scene.left.shape[1] * factor, scene.left.shape[0] * factor)
    left, right = (cv2.resize(v, size, interpolation=cv2.INTER_CUBIC)
                   for v in (scene.left, scene.right))
    gt = cv2.resize(scene.ground_truth, size, interpolation=cv2.INTER_NEAREST) * factor
    mask = cv2.resize(scene.masks["nonocc"].astype("uint8"), size,
                      interpolation=cv2.INTER_NEAREST) > 0
    return left, right, gt, mask, (scene.max_disp + 1) * factor - 1


def _child_size(argv: list[str]) -> None:
    """Child entry: one size-series run, printed as JSON."""
    import argparse

    from .metrics import bad_percent

    ap = argparse.ArgumentParser()
    ap.add_argument("--matcher", choices=SIZE_MATCHERS, required=True)
    ap.add_argument("--factor", type=int, required=True)
    ap.add_argument("--config", default="default")
    ap.add_argument("--data-root", default=None)
    ap.add_argument("--tall", action="store_true")
    args = ap.parse_args(argv)
    [scene] = datasets.load_dataset(SIZE_DATASET, args.data_root, names=[SIZE_SCENE])
    left, right, gt, mask, max_disp = upscaled_scene(scene, args.factor)
    del scene
    if args.tall:  # flipped upside down, a rectified pair stays rectified
        left, right, gt, mask = (np.ascontiguousarray(np.concatenate([a, a[::-1]]))
                                 for a in (left, right, gt, mask))
    if args.matcher == "vsmatch":
        crop = (slice(0, 48), slice(0, 64))  # load the kernels before the baseline
        pipeline.run(left[crop], right[crop], max_disp=16, config=args.config)
    before = _current_rss_mb()
    start = time.perf_counter()
    if args.matcher == "vsmatch":
        disp = pipeline.match(left, right, max_disp=max_disp, config=args.config)
    else:
        from .peers import sgbm_fill_from_left

        raw = sgbm_matcher(max_disp, mode=SGBM_MODES[args.matcher]).compute(left, right)
        disp = sgbm_fill_from_left(raw)
    seconds = time.perf_counter() - start
    peak = _peak_rss_mb()
    threshold = 2.0 * args.factor
    print(json.dumps({"matcher": args.matcher, "factor": args.factor, "tall": args.tall,
                      "size": [left.shape[1], left.shape[0]], "levels": max_disp + 1,
                      "seconds": seconds, "peak_mb": peak, "before_match_mb": before,
                      "threshold": threshold,
                      "bad_nonocc": bad_percent(disp, gt, mask, threshold)}))


def run_benchmark(data_root=None, config: str | None = None, repeats: int = 5,
                  cold: bool = True, size: bool = True) -> dict[str, Any]:
    """Everything :mod:`vsmatch.bench` measures, as one JSON-ready dict."""
    import numba

    scenes = [s for name in STANDARD_DATASETS for s in datasets.load_dataset(name, data_root)]
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
    if size:
        report["size"] = [size_run(data_root, matcher, factor, config)
                          for factor in SIZE_FACTORS for matcher in SIZE_MATCHERS]
        report["size"].append(size_run(data_root, "vsmatch", SIZE_FACTORS[-1], config,
                                       tall=True))
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
    if "size" in report:
        lines += ["", f"size series: {SIZE_SCENE} upscaled (bicubic), each in a child process",
                  f"{'factor':<8}{'size':>11}{'levels':>8}{'matcher':>10}{'seconds':>9}"
                  f"{'peak MB':>9}{'bad':>8}"]
        for run in report["size"]:
            factor = f"{run['factor']}" + (" tall" if run.get("tall") else "")
            lines.append(f"{factor:<8}{run['size'][0]:>6}x{run['size'][1]:<4}"
                         f"{run['levels']:>8}{run['matcher']:>10}{run['seconds']:9.2f}"
                         f"{run['peak_mb']:9.0f}{run['bad_nonocc']:8.2f}")
        lines.append("bad = % of non-occluded pixels off by more than 2 x factor; tall = "
                     "the pair with its upside-down copy below it")
        big = SIZE_FACTORS[-1]
        runs = {(r["matcher"], r.get("tall", False)): r for r in report["size"]
                if r["factor"] == big}
        ours = runs.get(("vsmatch", False))
        if ours is not None and ("vsmatch", True) in runs:
            tall = runs[("vsmatch", True)]
            lines.append(f"twice as tall: {tall['peak_mb'] / ours['peak_mb']:.2f} x the "
                         f"peak memory, {tall['seconds'] / ours['seconds']:.2f} x the time")
        for peer in ("sgbm-5", "sgbm-hh"):
            if ours is not None and (peer, False) in runs:
                ratio = ours["seconds"] / runs[(peer, False)]["seconds"]
                lines.append(f"{big}x: vsmatch / {peer} time {ratio:.2f}")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "match":
        _child_match(sys.argv[2:])
    elif len(sys.argv) > 1 and sys.argv[1] == "size":
        _child_size(sys.argv[2:])
    else:
        sys.exit("usage: python -m vsmatch.bench match LEFT RIGHT MAX_DISP [--config C] "
                 "[--scale N] | size --matcher M --factor F  (the CLI entry is "
                 "'vsmatch bench')")
