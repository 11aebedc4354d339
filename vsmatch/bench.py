"""Speed and memory of vsmatch against OpenCV's StereoSGBM (EVALUATION.md, "Speed").

Timings of the matching itself come from one process, vsmatch's configs and SGBM's modes
alternating on the same images after a warm-up call, the fastest of the rounds kept, so
the ratios hold on a shared, noisy machine: the standard pairs (the four middlebury2
pairs and the Middlebury 2014 pairs at quarter size in the data, each with its official
range), with each method's error on them (the time-error trade-off,
``--plot``). Start-up and memory are measured in child processes: a first call with an
empty compilation cache, the whole ``vsmatch run`` command with a warm cache, the peak
resident memory of a pair, and the size series: Adirondack (Middlebury 2014) as it is,
a KITTI 2015 frame with 192 disparities, Adirondack upscaled to 1.5 megapixels and 4x
(bicubic; ground truth x factor, nearest), matched by each config and by SGBM in its
5-direction and HH modes, with time, peak memory and bad (2 x factor) on the
non-occluded pixels, and the first config on the 4x pair with its upside-down copy below
it (twice as tall: does memory grow with the height?).
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

import cv2
import numpy as np

from . import datasets, evaluation, pipeline, volumes
from .config import load_config
from .peers import sgbm_fill_from_left, sgbm_matcher

#: The pairs timed against SGBM in one process.
STANDARD_DATASETS = ("middlebury2", "middlebury2014-quarter")
#: The configs ``vsmatch bench`` times unless told.
BENCH_CONFIGS = ("fast", "default")
#: SGBM's modes, as the benchmark names them (OpenCV's default is the 5-direction one).
SGBM_MODES = {"sgbm-5": cv2.STEREO_SGBM_MODE_SGBM, "sgbm-hh": cv2.STEREO_SGBM_MODE_HH,
              "sgbm-3way": cv2.STEREO_SGBM_MODE_SGBM_3WAY}
#: The size series: (label, dataset, scene, scale). A scale that is not whole gives the
#: size asked for: 1.5 megapixels, today's stereo cameras.
SIZE_SERIES = (("1x", "middlebury2014-quarter", "Adirondack", 1),
               ("KITTI", "kitti2015", "000000", 1),
               ("1.5 MP", "middlebury2014-quarter", "Adirondack", 2.05),
               ("4x", "middlebury2014-quarter", "Adirondack", 4))
SIZE_PEERS = ("sgbm-5", "sgbm-hh")


def standard_pairs(data_root=None) -> list[tuple[Any, evaluation.Scoring]]:
    """The standard pairs (every middlebury2 and Middlebury 2014 quarter pair in the data),
    each with its dataset's scoring."""
    return [(scene, evaluation.scoring_for(name)) for name in STANDARD_DATASETS
            for scene in datasets.load_dataset(name, data_root)]


@contextlib.contextmanager
def thread_count(count: int | None):
    """Numba's and OpenCV's threads set to ``count`` inside the block (None: as they are),
    and set back after it."""
    import numba

    if count is None:
        yield
        return
    before = numba.get_num_threads(), cv2.getNumThreads()
    numba.set_num_threads(count)
    cv2.setNumThreads(count)
    try:
        yield
    finally:
        numba.set_num_threads(before[0])
        cv2.setNumThreads(before[1])


def max_threads() -> int:
    """The most threads Numba can be set to in this process (NUMBA_NUM_THREADS)."""
    import numba

    return int(numba.config.NUMBA_NUM_THREADS)


def time_pairs(pairs, configs=BENCH_CONFIGS, rounds: int = 5,
               peers=tuple(SGBM_MODES), threads=None,
               on_done: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Each config and SGBM mode on each ``(scene, scoring)`` pair, one after the other
    for ``rounds`` rounds; the fastest time of each, the stage times of that run, and its
    error (the scoring's headline on the non-occluded pixels: bad 1.0 on middlebury2,
    bad 2.0 on Middlebury 2014). Ratios are against SGBM HH, 5-direction and 3-way, over
    the sums.

    ``threads``: thread counts (Numba's and OpenCV's both) to time each method at, taken
    in turn within every round so that the machine's moods fall on all of them alike; the
    result's ``by_threads`` holds each count's ``scenes`` and ``total``, and ``scenes``
    and ``total`` are the last count's. Default: the threads as they are set.
    ``on_done(name)`` is called after each pair (progress)."""
    scenes = [scene for scene, _ in pairs]
    cfgs = {name: load_config(name) for name in configs}
    warm = scenes[0]
    for cfg in cfgs.values():  # compile, or load the kernels
        pipeline.run(warm.left, warm.right, max_disp=warm.max_disp, config=cfg)
    methods = [*cfgs, *peers]
    counts = list(threads) if threads else [None]
    by_threads: dict[Any, dict[str, Any]] = {n: {} for n in counts}
    # Each config keeps its volumes from round to round, as StereoMatcher does from frame
    # to frame and each SGBM matcher its buffer.
    pools = {name: volumes.VolumePool() for name in cfgs}
    for scene, scoring in pairs:
        channels = 1 if scene.left.ndim == 2 else scene.left.shape[2]
        sgbm = {peer: sgbm_matcher(scene.max_disp, channels, min_disp=scene.min_disp,
                                   mode=SGBM_MODES[peer]) for peer in peers}
        for matcher in sgbm.values():  # OpenCV's own first-call costs
            matcher.compute(scene.left, scene.right)
        runs = [(n, name) for n in counts for name in methods]
        best = dict.fromkeys(runs, float("inf"))
        stages: dict[Any, dict[str, float]] = {}
        disparities: dict[str, np.ndarray] = {}
        for _ in range(rounds):
            for n, name in runs:
                with thread_count(n):
                    start = time.perf_counter()
                    if name in cfgs:
                        with volumes.reused(pools[name]):
                            result = pipeline.run(scene.left, scene.right,
                                                  max_disp=scene.max_disp,
                                                  min_disp=scene.min_disp, config=cfgs[name])
                    else:
                        raw = sgbm[name].compute(scene.left, scene.right)
                    seconds = time.perf_counter() - start
                if seconds < best[n, name]:
                    best[n, name] = seconds
                    if name in cfgs:
                        stages[n, name] = result.seconds
                # The same every round and thread count (deterministic). SGBM's holes are
                # filled for the score only, outside its time: the filling is
                # EVALUATION.md's, not SGBM's.
                disparities[name] = result.disparity if name in cfgs else \
                    sgbm_fill_from_left(raw, scene.min_disp)
        mask = evaluation.headline_mask(scene)
        scores = {}
        for name in methods:
            measures = scoring.measures(disparities[name], scene.ground_truth, mask)
            scores[name] = {"error": measures[scoring.metric], "bad0.5": measures["bad0.5"],
                            "integer_share": measures["integer_share"]}
        for n in counts:
            by_threads[n][scene.name] = {
                name: {"seconds": best[n, name], "stages": stages.get((n, name), {}),
                       **scores[name]} for name in methods}
        if on_done is not None:
            on_done(scene.name)
    series = {("as set" if n is None else n): {"scenes": per_scene,
                                               "total": _totals(per_scene, methods)}
              for n, per_scene in by_threads.items()}
    last = series[list(series)[-1]]
    return {"rounds": rounds, "methods": methods, "configs": list(cfgs),
            "threads": list(series), "by_threads": series, **last}


def _totals(per_scene: dict[str, Any], methods: list[str]) -> dict[str, Any]:
    """Each method's seconds and stage seconds summed over the pairs, its mean error, and
    its time over each SGBM mode's."""
    totals = {}
    for name in methods:
        seconds = sum(s[name]["seconds"] for s in per_scene.values())
        stage_totals: dict[str, float] = {}
        for s in per_scene.values():
            for k, v in s[name]["stages"].items():
                stage_totals[k] = stage_totals.get(k, 0.0) + v
        totals[name] = {"seconds": seconds, "stages": stage_totals,
                        **{key: float(np.mean([s[name][key] for s in per_scene.values()]))
                           for key in ("error", "bad0.5", "integer_share")}}
    for name in methods:
        for peer in SGBM_MODES:
            if peer in totals:
                totals[name][f"x_{peer}"] = totals[name]["seconds"] / totals[peer]["seconds"]
    return totals


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


def _system_seconds() -> float:
    """CPU seconds the operating system has spent for this process (all its threads)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_stime


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
    from . import compilation, io
    from ._kernels import cache_is_cold

    left, right = io.read_image(args.left), io.read_image(args.right)
    if args.scale != 1:
        size = (left.shape[1] * args.scale, left.shape[0] * args.scale)
        left = cv2.resize(left, size, interpolation=cv2.INTER_CUBIC)
        right = cv2.resize(right, size, interpolation=cv2.INTER_CUBIC)
    # Load every compiled kernel on a small crop first, so that ``before`` holds the code
    # and the peak above it is what matching this pair needs.
    crop = (slice(0, 48), slice(0, 64))
    first = time.perf_counter()
    if cache_is_cold():  # as the command line does: a share of the kernels a core
        compilation.compile_ahead(args.config)
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


def size_run(data_root, matcher: str, entry: tuple, config: str | None = None,
             tall: bool = False) -> dict[str, Any]:
    """One matcher (``vsmatch`` with ``config``, or an SGBM mode) on a size-series entry
    (:data:`SIZE_SERIES`; ``tall``: with its upside-down copy below it, twice as tall),
    in a child process (warm cache), twice: the faster time, peak memory and bad
    (2 x scale) on the non-occluded pixels."""
    label, dataset, scene, scale = entry
    args = ["size", "--matcher", matcher, "--dataset", dataset, "--scene", scene,
            "--scale", str(scale), "--config", config or "default"] + (
        ["--tall"] if tall else [])
    if data_root is not None:
        args += ["--data-root", str(data_root)]
    # Twice, the faster time kept: one run in a child process is at the mercy of a busy
    # machine. Memory and error from the second, whose compilation cache the first filled
    # for this shape of call (a child that compiles peaks higher).
    first, second = _run_child(args), _run_child(args)
    faster = min(first, second, key=lambda run: run["seconds"])
    second["seconds"], second["system_seconds"] = faster["seconds"], faster["system_seconds"]
    return {"label": label, "config": config if matcher == "vsmatch" else None, **second}


def upscaled_scene(scene, scale: float):
    """The scene ``scale`` times larger: views bicubic, ground truth and masks nearest,
    disparities times ``scale``, the range so that it still covers them."""
    mask = scene.masks["nonocc"] if "nonocc" in scene.masks else scene.masks["all"]
    if scale == 1:
        return scene.left, scene.right, scene.ground_truth, mask, scene.max_disp
    size = (round(scene.left.shape[1] * scale), round(scene.left.shape[0] * scale))
    left, right = (cv2.resize(v, size, interpolation=cv2.INTER_CUBIC)
                   for v in (scene.left, scene.right))
    gt = cv2.resize(scene.ground_truth, size, interpolation=cv2.INTER_NEAREST) * np.float32(
        scale)
    mask = cv2.resize(mask.astype("uint8"), size, interpolation=cv2.INTER_NEAREST) > 0
    return left, right, gt, mask, int(np.ceil((scene.max_disp + 1) * scale)) - 1


def _child_size(argv: list[str]) -> None:
    """Child entry: one size-series run, printed as JSON."""
    import argparse

    from .metrics import bad_percent

    ap = argparse.ArgumentParser()
    ap.add_argument("--matcher", choices=("vsmatch", *SGBM_MODES), required=True)
    ap.add_argument("--dataset", default=SIZE_SERIES[0][1])
    ap.add_argument("--scene", default=SIZE_SERIES[0][2])
    ap.add_argument("--scale", type=float, required=True)
    ap.add_argument("--config", default="default")
    ap.add_argument("--data-root", default=None)
    ap.add_argument("--tall", action="store_true")
    args = ap.parse_args(argv)
    [scene] = datasets.load_dataset(args.dataset, args.data_root, names=[args.scene])
    left, right, gt, mask, max_disp = upscaled_scene(scene, args.scale)
    del scene
    if args.tall:  # flipped upside down, a rectified pair stays rectified
        left, right, gt, mask = (np.ascontiguousarray(np.concatenate([a, a[::-1]]))
                                 for a in (left, right, gt, mask))
    if args.matcher == "vsmatch":
        crop = (slice(0, 48), slice(0, 64))  # load the kernels before the baseline
        pipeline.run(left[crop], right[crop], max_disp=16, config=args.config)
    before = _current_rss_mb()
    if args.matcher == "vsmatch":
        system, start = _system_seconds(), time.perf_counter()
        disp = pipeline.match(left, right, max_disp=max_disp, config=args.config)
        seconds, system = time.perf_counter() - start, _system_seconds() - system
    else:
        matcher = sgbm_matcher(max_disp, mode=SGBM_MODES[args.matcher])
        system, start = _system_seconds(), time.perf_counter()
        raw = matcher.compute(left, right)
        seconds, system = time.perf_counter() - start, _system_seconds() - system
        disp = sgbm_fill_from_left(raw)  # for the score only, as in time_pairs
    peak = _peak_rss_mb()
    threshold = 2.0 * args.scale
    print(json.dumps({"matcher": args.matcher, "scale": args.scale, "tall": args.tall,
                      "size": [left.shape[1], left.shape[0]], "levels": max_disp + 1,
                      "seconds": seconds, "system_seconds": system, "peak_mb": peak,
                      "before_match_mb": before,
                      "threshold": threshold,
                      "bad_nonocc": bad_percent(disp, gt, mask, threshold)}))


def run_benchmark(data_root=None, configs=BENCH_CONFIGS, rounds: int = 5,
                  cold: bool = True, size: bool = True, threads=None,
                  on_done: Callable[[str], None] | None = None,
                  on_total: Callable[[int], None] | None = None) -> dict[str, Any]:
    """Everything :mod:`vsmatch.bench` measures, as one JSON-ready dict. Start-up,
    the whole command and memory are measured for the first config; ``threads``: the
    thread counts the standard pairs are timed at (:func:`time_pairs`); ``on_done(name)``
    after each pair and each step after them, ``on_total(count)`` once before the work
    with how many there will be (progress)."""
    import numba

    pairs = standard_pairs(data_root)
    sized = [entry for entry in SIZE_SERIES if _has_scene(data_root, entry)] if size else []
    if on_total is not None:  # the pairs, command and memory, start-up, sizes and the tall
        on_total(len(pairs) + 1 + cold + (len(sized) + 1 if size else 0))
    configs = list(configs)
    first = configs[0]
    folder = datasets.dataset_folder("middlebury2", data_root) / "cones"
    left, right = folder / "imL.png", folder / "imR.png"
    cones_disp = datasets.middlebury2.SCENES["cones"][1]
    report: dict[str, Any] = {
        "configs": configs,
        "threads": {"numba": numba.get_num_threads(), "opencv": cv2.getNumThreads()},
        "pairs": time_pairs(pairs, configs, rounds, threads=threads, on_done=on_done),
        "run_command_cones": run_command(left, right, cones_disp, first, 3),
        "memory_cones": memory(left, right, cones_disp, first)}
    done = on_done or (lambda name: None)
    done("whole command and memory")
    if cold:
        report["cold_start_cones"] = cold_start(left, right, cones_disp, first)
        done("start-up")
    if size:
        runs = []
        for entry in sized:  # those this machine has (e.g. no KITTI)
            runs += [size_run(data_root, "vsmatch", entry, c) for c in configs]
            runs += [size_run(data_root, peer, entry) for peer in SIZE_PEERS]
            done(f"size {entry[0]}")
        runs.append(size_run(data_root, "vsmatch", SIZE_SERIES[-1], first, tall=True))
        done("size 4x twice as tall")
        report["size"] = runs
    return report


def _has_scene(data_root, entry) -> bool:
    try:
        datasets.load_dataset(entry[1], data_root, names=[entry[2]])
    except datasets.DatasetError:
        return False
    return True


def tradeoff_figure(report: dict[str, Any]) -> np.ndarray:
    """Time against error on the standard pairs, a point per config and SGBM mode."""
    from .figure import tradeoff_plot

    total = report["pairs"]["total"]
    points = {name: (total[name]["seconds"], total[name]["error"])
              for name in report["pairs"]["methods"]}
    count = len(report["pairs"]["scenes"])
    return tradeoff_plot(points, x_label=f"seconds, the {count} standard pairs (fastest of "
                         f"{report['pairs']['rounds']})", y_label="error (%)",
                         title="time against error: lower left is better")


def format_threads(pairs: dict[str, Any]) -> list[str]:
    """The thread series: each method's seconds at each count, each config's ratios to
    SGBM's modes and speed-up over the first count, and its stages' shares and speed-ups."""
    counts = pairs["threads"]
    series = pairs["by_threads"]
    first = counts[0]
    head = "".join(f"{f'{n} threads':>12}" for n in counts)
    lines = ["", f"by thread count (Numba's and OpenCV's both), seconds over the "
                 f"{len(pairs['scenes'])} pairs:", f"{'':<22}{head}"]
    for name in pairs["methods"]:
        lines.append(f"{name:<22}" + "".join(f"{series[n]['total'][name]['seconds']:12.3f}"
                                             for n in counts))
    for name in pairs["configs"]:
        for peer in SGBM_MODES:
            if peer in pairs["methods"]:
                lines.append(f"{name + ' x ' + peer:<22}" + "".join(
                    f"{series[n]['total'][name][f'x_{peer}']:12.2f}" for n in counts))
        base = series[first]["total"][name]["seconds"]
        lines.append(f"{name + ' speed-up':<22}" + "".join(
            f"{base / series[n]['total'][name]['seconds']:12.2f}" for n in counts))
    for name in pairs["configs"]:
        lines += ["", f"{name}: stage seconds (share of the time) and speed-up over "
                      f"{first} thread{'s' if first != 1 else ''}:",
                  f"  {'stage':<14}" + "".join(f"{f'{n} threads':>16}" for n in counts)
                  + "".join(f"{f'x at {n}':>9}" for n in counts[1:])]
        stages = {n: series[n]["total"][name]["stages"] for n in counts}
        sums = {n: sum(stages[n].values()) or 1.0 for n in counts}
        for stage in sorted(stages[counts[-1]], key=lambda k: -stages[counts[-1]][k]):
            cells = "".join(f"{stages[n].get(stage, 0):9.3f}"
                            f"{f'({100 * stages[n].get(stage, 0) / sums[n]:.0f}%)':>7}"
                            for n in counts)
            ups = "".join(f"{stages[first].get(stage, 0) / max(stages[n].get(stage, 0), 1e-9):9.2f}"
                          for n in counts[1:])
            lines.append(f"  {stage:<14}{cells}{ups}")
    return lines


def _memory_line(name: str, mem: dict[str, Any]) -> str:
    extra = mem["peak_mb"] - mem["before_match_mb"]
    return (f"{name} peak memory: {mem['peak_mb']:.0f} MB; matching adds {extra:.0f} MB "
            f"= {extra / mem['cost_volume_mb']:.1f} x the cost volume "
            f"({mem['cost_volume_mb']:.0f} MB)")


def _size_name(run: dict[str, Any]) -> str:
    return run["config"] if run["matcher"] == "vsmatch" else run["matcher"]


def format_report(report: dict[str, Any]) -> str:
    """The printed tables."""
    pairs = report["pairs"]
    methods = pairs["methods"]
    series = "" if len(pairs["threads"]) < 2 else \
        f"; the pairs at {', '.join(map(str, pairs['threads']))} threads, the table below at " \
        f"{pairs['threads'][-1]}"
    lines = [f"configs {', '.join(report['configs'])}; threads: numba "
             f"{report['threads']['numba']}, opencv {report['threads']['opencv']}{series}; "
             f"fastest of {pairs['rounds']} alternating rounds", "",
             "seconds per pair:", f"{'pair':<12}" + "".join(f"{m:>11}" for m in methods)]
    for name, s in pairs["scenes"].items():
        lines.append(f"{name:<12}" + "".join(f"{s[m]['seconds']:11.3f}" for m in methods))
    total = pairs["total"]
    lines.append(f"{'total':<12}" + "".join(f"{total[m]['seconds']:11.3f}" for m in methods))
    lines.append(f"{'x SGBM HH':<12}" + "".join(f"{total[m].get('x_sgbm-hh', 0):11.2f}"
                                              for m in methods))
    lines.append(f"{'x SGBM 5-dir':<12}" + "".join(f"{total[m].get('x_sgbm-5', 0):11.2f}"
                                                 for m in methods))
    if "sgbm-3way" in methods:
        lines.append(f"{'x SGBM 3-way':<12}" + "".join(
            f"{total[m].get('x_sgbm-3way', 0):11.2f}" for m in methods))
    lines.append(f"{'error':<12}" + "".join(f"{total[m]['error']:11.2f}" for m in methods))
    if all("bad0.5" in total[m] for m in methods):
        lines.append(f"{'bad 0.5':<12}" + "".join(f"{total[m]['bad0.5']:11.2f}"
                                                   for m in methods))
        lines.append(f"{'integer':<12}" + "".join(f"{total[m]['integer_share']:11.3f}"
                                                   for m in methods))
    lines.append("error: mean over the pairs of nonocc bad 1.0 (middlebury2) and bad 2.0 "
                 "(Middlebury 2014); bad 0.5 and integer (the share of estimates within 0.1 "
                 "px of a whole number: 0.2 for an even spread) on the same pixels")
    if len(pairs["threads"]) > 1:
        lines += format_threads(pairs)
    else:
        for name in pairs["configs"]:
            lines += ["", f"{name}: stage seconds, sum over the pairs:"]
            for stage, sec in sorted(total[name]["stages"].items(), key=lambda kv: -kv[1]):
                lines.append(f"  {stage:<14}{sec:8.3f}")
    run = report["run_command_cones"]
    mem = report["memory_cones"]
    first = report["configs"][0]
    lines += ["", f"vsmatch run --config {first} on cones, warm cache, whole command: "
                  f"{run['seconds']:.2f} s", _memory_line("cones", mem)]
    if "cold_start_cones" in report:
        cold = report["cold_start_cones"]
        lines.append(f"first call in a fresh process (a small crop): empty compilation cache "
                     f"{cold['empty_cache']['first_call_seconds']:.1f} s, cache filled "
                     f"{cold['warm_cache']['first_call_seconds']:.2f} s")
    if "size" in report:
        lines += ["", "size series, each in a child process, the faster of two runs",
                  f"{'pair':<8}{'size':>11}{'levels':>8}{'matcher':>10}{'seconds':>9}"
                  f"{'system':>8}{'peak MB':>9}{'bad':>8}"]
        for run in report["size"]:
            label = run["label"] + (" tall" if run.get("tall") else "")
            lines.append(f"{label:<8}{run['size'][0]:>6}x{run['size'][1]:<4}"
                         f"{run['levels']:>8}{_size_name(run):>10}{run['seconds']:9.2f}"
                         f"{run.get('system_seconds', float('nan')):8.2f}"
                         f"{run['peak_mb']:9.0f}{run['bad_nonocc']:8.2f}")
        lines.append("system = CPU seconds the operating system spent for the match (mostly "
                     "mapping and zeroing fresh memory: it moves with the machine's memory "
                     "state, not the method); bad = % of non-occluded pixels off by more "
                     "than 2 x scale; tall = the pair with its upside-down copy below it")
        for label in dict.fromkeys(r["label"] for r in report["size"]):
            runs = {_size_name(r): r for r in report["size"]
                    if r["label"] == label and not r.get("tall")}
            for name in report["configs"]:
                if name in runs:
                    ratios = [f"{runs[name]['seconds'] / runs[p]['seconds']:.2f} x {p}"
                              for p in SIZE_PEERS if p in runs]
                    lines.append(f"{label}: {name} {', '.join(ratios)}")
        tall = [r for r in report["size"] if r.get("tall")]
        ours = [r for r in report["size"] if r["label"] == SIZE_SERIES[-1][0]
                and r["matcher"] == "vsmatch" and r["config"] == first and not r.get("tall")]
        if tall and ours:
            lines.append(f"twice as tall: {tall[0]['peak_mb'] / ours[0]['peak_mb']:.2f} x the "
                         f"peak memory, {tall[0]['seconds'] / ours[0]['seconds']:.2f} x the time")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "match":
        _child_match(sys.argv[2:])
    elif len(sys.argv) > 1 and sys.argv[1] == "size":
        _child_size(sys.argv[2:])
    else:
        sys.exit("usage: python -m vsmatch.bench match LEFT RIGHT MAX_DISP [--config C] "
                 "[--scale N] | size --matcher M --scale S [--dataset D --scene S]  (the "
                 "CLI entry is 'vsmatch bench')")
