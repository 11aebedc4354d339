"""Running methods over a benchmark and scoring them (EVALUATION.md).

A report is the ``--json`` document: ``{"dataset", "metric", "threshold", "methods":
{name: {"scenes": {scene: {<mask>: headline, ..., "metrics": {<mask>: {measure: value}},
"seconds", "range"}}, "avg": {<mask>: mean headline, "metrics": {...}}}}}``.
"""

from __future__ import annotations

import dataclasses
import re
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from . import geometry, metrics, volumes
from .config import Config, config_from_dict, load_config
from .datasets import DATASETS, Scene
from .io import (all_or_none, imwrite_atomic, output_folder, write_confidence,
                 write_disparity, write_text_atomic)
from .peers import PEER_METHODS, sgbm_disparity
from .pipeline import run
from .preview import colour_disparity, error_image

# Re-exported: the bad-pixel functions evaluation has always offered.
bad_pixel_map = metrics.bad_pixel_map
bad_percent = metrics.bad_percent


@dataclasses.dataclass(frozen=True)
class Scoring:
    """How a dataset is scored: the headline measure and every measure per mask."""

    metric: str  # the headline measure's name: "bad1.0", "bad2.0", "D1", "out3"
    threshold: float  # its error threshold in pixels

    @classmethod
    def bad(cls, threshold: float) -> Scoring:
        """Middlebury scoring with bad-``threshold`` as the headline."""
        return cls(metrics.bad_name(threshold), float(threshold))

    @classmethod
    def of_report(cls, report: dict[str, Any]) -> Scoring:
        """The scoring a report was made with (bad 1.0 when it names none)."""
        return cls(report.get("metric", "bad1.0"), report.get("threshold", 1.0))

    @property
    def kitti(self) -> bool:
        return not self.metric.startswith("bad")

    def measures(self, disp: np.ndarray, gt: np.ndarray, mask: np.ndarray) -> dict:
        if self.kitti:
            return metrics.kitti_measures(disp, gt, mask)
        thresholds = sorted({*metrics.MIDDLEBURY_THRESHOLDS, self.threshold})
        return metrics.middlebury_measures(disp, gt, mask, thresholds)

    def bad_map(self, disp: np.ndarray, gt: np.ndarray) -> np.ndarray:
        if self.metric == "D1":
            return metrics.d1_map(disp, gt)
        return metrics.bad_pixel_map(disp, gt, self.threshold)


def scoring_for(dataset: str, threshold: float | None = None) -> Scoring:
    """The dataset's scoring; ``threshold`` changes a Middlebury headline's bad-x.

    A dataset outside the registry is scored like Middlebury v2 (bad 1.0).
    """
    spec = DATASETS.get(dataset)
    if spec is not None and spec.metric != "bad":
        if threshold is not None:
            raise ValueError(f"--threshold does not apply to {dataset}: its measure "
                             f"{spec.metric} has a fixed threshold")
        return Scoring(spec.metric, 3.0)
    if threshold is None:
        threshold = spec.threshold if spec is not None else 1.0
    return Scoring.bad(threshold)


def score_scene(disp: np.ndarray, scene: Scene,
                scoring: Scoring | float = 1.0) -> dict[str, Any]:
    """Headline figure per mask of the scene, and every measure under ``"metrics"``.

    ``scoring`` may be a bare bad-x threshold (Middlebury scoring).
    """
    if not isinstance(scoring, Scoring):
        scoring = Scoring.bad(scoring)
    per_mask = {m: scoring.measures(disp, scene.ground_truth, mask)
                for m, mask in scene.masks.items()}
    out: dict[str, Any] = {m: per_mask[m].get(scoring.metric, float("nan"))
                           for m in per_mask}
    out["metrics"] = per_mask
    return out


def average(per_scene: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Plain mean over the scenes, mask by mask, of the headline and of every measure;
    only the masks every scene has."""
    scenes = list(per_scene.values())
    masks = [m for m in scenes[0]["metrics"] if all(m in s["metrics"] for s in scenes)]
    avg: dict[str, Any] = {m: float(np.mean([s[m] for s in scenes])) for m in masks}
    avg["metrics"] = {m: {k: float(np.mean([s["metrics"][m].get(k, np.nan) for s in scenes]))
                          for k in scenes[0]["metrics"][m]} for m in masks}
    return avg


def method_runner(method) -> tuple[Callable, Config | None]:
    """A method name, config path or Config as ``(run(left, right, min_disp, max_disp),
    config)``; the config is None for a peer method (:data:`PEER_METHODS`)."""
    run_full, cfg = full_runner(method)
    return (lambda left, right, lo, hi: run_full(left, right, lo, hi)[0]), cfg


def full_runner(method) -> tuple[Callable, Config | None]:
    """As :func:`method_runner`, the run giving ``(disparity, confidence or None)``."""
    if method in PEER_METHODS:
        return (lambda left, right, lo, hi: (sgbm_disparity(left, right, max_disp=hi,
                                                            min_disp=lo), None)), None
    cfg = load_config(method)
    pool = volumes.VolumePool()  # the scenes one after another reuse the volumes

    def run_vsmatch(left, right, lo, hi):
        with volumes.reused(pool):
            result = run(left, right, max_disp=hi, min_disp=lo, config=cfg)
        return result.disparity, result.confidence
    return run_vsmatch, cfg


def scene_ranges(scenes: list[Scene], auto: bool = False) -> dict[str, tuple[int, int]]:
    """Each scene's search range: the official one, or the one estimated from the pair."""
    if not auto:
        return {s.name: (s.min_disp, s.max_disp) for s in scenes}
    from .search_range import resolve_range

    ranges = {}
    for scene in scenes:
        searched = resolve_range(scene.left, scene.right)
        ranges[scene.name] = (searched.min_disp, searched.max_disp)
    return ranges


def evaluate(scenes: list[Scene], methods: dict, *, dataset: str,
             threshold: float | None = None, out_dir: str | Path | None = None,
             on_done: Callable[[str, str], None] | None = None,
             ranges: dict[str, tuple[int, int]] | None = None,
             disparities: dict | None = None) -> dict[str, Any]:
    """Run each method on each scene and score it; the result is the ``--json`` document.

    ``methods`` maps a display name to a config (name, path or :class:`Config`) or a
    peer method's name. ``ranges`` gives each scene's ``(min, max)`` disparity (default:
    the official ranges). ``on_done(method, scene)`` is called after each run (progress
    reporting); with ``disparities`` (a dict), each disparity is kept there under
    ``(method, scene)``. With ``out_dir``, each disparity is saved as PFM, a colour-mapped
    PNG and an error image (bad pixels red), with the resolved config beside them.
    """
    scoring = scoring_for(dataset, threshold)
    ranges = ranges or scene_ranges(scenes)
    report: dict[str, Any] = {"dataset": dataset, "metric": scoring.metric,
                              "threshold": scoring.threshold, "methods": {}}
    names = method_folders(list(methods))
    for name, method in methods.items():
        run_method, cfg = full_runner(method)
        folder = None if out_dir is None else Path(out_dir) / names[name]
        per_scene = {}
        for scene in scenes:
            low, high = ranges[scene.name]
            start = time.perf_counter()
            disp, conf = run_method(scene.left, scene.right, low, high)
            seconds = time.perf_counter() - start
            per_scene[scene.name] = {**score_scene(disp, scene, scoring), "seconds": seconds,
                                     "range": [low, high]}
            if conf is not None:
                per_scene[scene.name]["confidence"] = confidence_measures(disp, conf, scene,
                                                                          scoring)
            if folder is not None:
                save_scene_outputs(folder, scene, disp, scoring, conf)
            if disparities is not None:
                disparities[(name, scene.name)] = disp
            if on_done is not None:
                on_done(name, scene.name)
        if folder is not None and cfg is not None:
            folder.mkdir(parents=True, exist_ok=True)
            write_text_atomic(folder / "config.yaml",
                              yaml.safe_dump(cfg.to_file_dict(), sort_keys=False))
        report["methods"][name] = {"scenes": per_scene, "avg": average(per_scene)}
        measured = [s["confidence"] for s in per_scene.values() if "confidence" in s]
        if measured:
            report["methods"][name]["avg"]["confidence"] = {
                k: float(np.mean([m[k] for m in measured])) for k in measured[0]}
    return report


def confidence_measures(disp: np.ndarray, conf: np.ndarray, scene: Scene,
                        scoring: Scoring) -> dict[str, float]:
    """Hu and Mordohai's sparsification measures (:func:`vsmatch.confidence.sparsification`)
    over the scene's non-occluded pixels with ground truth, errors by its headline measure."""
    from .confidence import sparsification

    evaluated = headline_mask(scene) & np.isfinite(scene.ground_truth)
    correct = ~scoring.bad_map(disp, scene.ground_truth)
    return sparsification(conf, correct, evaluated)


def safe_name(name: str) -> str:
    """A folder name for a method: a YAML path's stem, other characters made safe."""
    if name.endswith((".yaml", ".yml")):
        name = Path(name).stem
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("_") or "method"


def method_folders(names: list[str]) -> dict[str, str]:
    """Each method's folder under ``--out-dir``: its safe name (:func:`safe_name`), and
    where two methods would share one (``a/fast.yaml`` and ``b/fast.yaml``, ``fast`` and
    ``fast.yaml``) the later ones numbered (``fast_2``), in the order given."""
    folders: dict[str, str] = {}
    taken: set[str] = set()
    for name in names:
        base = folder = safe_name(name)
        number = 1
        while folder.lower() in taken:  # one folder on a case-blind file system too
            number += 1
            folder = f"{base}_{number}"
        taken.add(folder.lower())
        folders[name] = folder
    return folders


def save_scene_outputs(folder: Path, scene: Scene, disp: np.ndarray,
                       scoring: Scoring, conf: np.ndarray | None = None) -> None:
    """Disparity (PFM), colour-mapped disparity and error image of one scene, and its
    confidence (PFM) when there is one: all of them or none."""
    with output_folder(folder), all_or_none():
        write_disparity(folder / f"{scene.name}.pfm", disp)
        if conf is not None:
            write_confidence(folder / f"{scene.name}_confidence.pfm", conf)
        imwrite_atomic(folder / f"{scene.name}_disp.png",
                       colour_disparity(disp, scene.max_disp))
        imwrite_atomic(folder / f"{scene.name}_error.png",
                       error_image(disp, scoring.bad_map(disp, scene.ground_truth),
                                   headline_mask(scene), scene.max_disp))


def headline_mask(scene: Scene) -> np.ndarray:
    """The pixels an error image shows as evaluated: non-occluded where known, else all."""
    return scene.masks.get("nonocc", scene.masks["all"])


#: A point of a cloud is wrong when its depth is more than this share off the truth's.
DEPTH_TOLERANCE = 0.03


def cloud_measures(written: np.ndarray, scene: Scene,
                   calib: geometry.Calibration) -> tuple[float, float]:
    """Of the points the disparity ``written`` (invalid where left out of the cloud) gives
    with ``calib``: the share more than :data:`DEPTH_TOLERANCE` off the ground truth's
    depth, among those whose ground truth is known (an unknown one reads 0, which gives a
    finite depth), and how many there are against the scene's non-occluded pixels."""
    depth = geometry.depth_from_disparity(written, calib)
    truth = geometry.depth_from_disparity(scene.ground_truth, calib)
    checked = np.isfinite(depth) & np.isfinite(truth) & scene.masks["all"]
    off = np.abs(depth[checked] - truth[checked]) > DEPTH_TOLERANCE * truth[checked]
    return float(off.mean()), float(np.isfinite(depth).sum() / scene.masks["nonocc"].sum())


def headline_figure(scored: dict[str, Any]) -> float:
    """A scene's headline figure among its scores (:func:`score_scene`): on the
    non-occluded pixels where the dataset has them, else on all (KITTI)."""
    return scored.get("nonocc", scored["all"])


def headline_figures(report: dict[str, Any], method: str) -> dict[str, float]:
    """Each scene's :func:`headline_figure` for ``method`` in an :func:`evaluate` report."""
    return {name: headline_figure(scored)
            for name, scored in report["methods"][method]["scenes"].items()}


def format_tables(report: dict[str, Any]) -> str:
    """One table per mask, shaped like the paper's Table 1: a row per method."""
    methods = report["methods"]
    if not methods:
        return ""
    first = next(iter(methods.values()))
    scenes = list(first["scenes"])
    masks = [m for m in first["avg"] if m not in ("metrics", "confidence")]
    width = max(20, *(len(m) + 2 for m in methods))
    cell = max(10, *(len(s) + 2 for s in scenes))
    lines = []
    for mask in masks:
        lines.append(f"{mask} {report['metric']} (%)".ljust(width)
                     + "".join(f"{s:>{cell}}" for s in scenes) + f"{'avg':>{cell}}")
        for name, result in methods.items():
            cells = [result["scenes"][s][mask] for s in scenes] + [result["avg"][mask]]
            lines.append(name.ljust(width) + "".join(f"{v:{cell}.2f}" for v in cells))
        lines.append("")
    # Sub-pixel precision beside the headline, on the headline's mask.
    mask = masks[0]
    for measure, label, digits in (("bad0.5", f"{mask} bad0.5 (%)", 2),
                                   ("integer_share", f"{mask} integer share", 3)):
        if all(measure in r["avg"]["metrics"].get(mask, {}) for r in methods.values()):
            lines.append(label.ljust(width) + "".join(f"{s:>{cell}}" for s in scenes)
                         + f"{'avg':>{cell}}")
            for name, result in methods.items():
                cells = [result["scenes"][s]["metrics"][mask][measure] for s in scenes]
                cells.append(result["avg"]["metrics"][mask][measure])
                lines.append(name.ljust(width) + "".join(f"{v:{cell}.{digits}f}"
                                                         for v in cells))
            lines.append("")
    rated = {n: r for n, r in methods.items() if "confidence" in r["avg"]}
    if rated:
        lines.append("confidence r (0 best)".ljust(width) + "".join(
            f"{s:>{cell}}" for s in scenes) + f"{'avg':>{cell}}")
        for name, result in rated.items():
            cells = [result["scenes"][s]["confidence"]["r"] for s in scenes]
            cells.append(result["avg"]["confidence"]["r"])
            lines.append(name.ljust(width) + "".join(f"{v:{cell}.3f}" for v in cells))
    return "\n".join(lines).rstrip() + "\n"


def ablation_configs(base: Config) -> dict[str, Config]:
    """The refinement chain built up stage by stage to ``base``, then alternatives.

    The first row is ``base`` with the exposure correction and every §5 stage off (§1-4);
    each next row switches one stage on with ``base``'s values for it, so the last of them
    is ``base`` itself. Then ``base`` with one thing changed each: the scanline's 4 or 8
    directions (whichever ``base`` does not use), the shrinking arm threshold, the other
    filling (16 search directions, the "proper interpolation" of §5.3, or 2 when ``base``
    uses more), and the direction factor ``kappa`` at 0 (or at 0.5 when ``base`` has 0).
    """
    def section(name: str, **changes) -> dict:
        return {name: {**dataclasses.asdict(getattr(base, name)), **changes}}

    steps = [
        ("§1-4: cost, aggregation, LR check, fill",
         {"scanline": {"enabled": False}, "voting": {"enabled": False},
          "discontinuity": {"enabled": False}, "subpixel": {"enabled": False, "median": False},
          "photometric": {"enabled": False}, "planes": {"enabled": False}}),
        ("+ scanline optimisation", section("scanline", enabled=True)),
        ("+ region voting", section("voting", enabled=True)),
        ("+ discontinuity adjustment", section("discontinuity", enabled=True)),
        ("+ sub-pixel", {"subpixel": {"enabled": True, "median": False}}),
        ("+ 3x3 median", {"subpixel": {"enabled": True, "median": True}}),
        ("+ exposure correction", section("photometric", enabled=True)),
        ("+ slanted planes", section("planes", enabled=True)),
    ]
    configs = {}
    cfg = base
    for label, change in steps:
        cfg = config_from_dict(change, base=cfg)
        configs[label] = cfg
    others = 8 if base.scanline.directions == 4 else 4
    configs[f"full chain, scanline in {others} directions"] = config_from_dict(
        {"scanline": {"directions": others}}, base=base)
    configs[f"full chain, shrinking arm threshold {'off' if base.arms.shrink else 'on'}"] = \
        config_from_dict({"arms": {"shrink": not base.arms.shrink}}, base=base)
    directions = 16 if base.fill.directions == 2 else 2
    configs[f"full chain, fill from {directions} directions"] = config_from_dict(
        {"fill": {"directions": directions}}, base=base)
    kappa = 0.0 if base.arms.kappa != 0 else 0.5
    configs[f"full chain, kappa = {kappa:g} (tuned: {base.arms.kappa:g})"] = config_from_dict(
        {"arms": {"kappa": kappa}}, base=base)
    return configs


def add_noise(image: np.ndarray, level: float, rng: np.random.Generator) -> np.ndarray:
    """Zero-mean Gaussian noise of sigma = ``level`` x 255, rounded and clipped to 0..255."""
    noisy = image.astype(np.float64) + rng.standard_normal(image.shape) * (level * 255.0)
    return np.clip(np.round(noisy), 0, 255).astype(np.uint8)


def noisy_pair(scene: Scene, scene_index: int, level: float,
               seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The scene's two views with independent noise, the same for a given (seed, scene).

    The noise pattern depends on the seed, the scene and the view, not on the level, so the
    levels differ only in strength (common random numbers).
    """
    return tuple(add_noise(view, level, np.random.default_rng((seed, scene_index, k)))
                 for k, view in enumerate((scene.left, scene.right)))


def with_sensor_noise(scene: Scene, scene_index: int, sigma: float, seed: int = 0) -> Scene:
    """``scene`` with sensor noise of ``sigma`` grey levels on each view (as
    :func:`noisy_pair`): a change of the input too small to matter, which a method that
    transfers reads about as the scene as it is (``scripts/perturbed.py``)."""
    left, right = noisy_pair(scene, scene_index, sigma / 255.0, seed)
    return dataclasses.replace(scene, left=left, right=right)


def without_left_columns(scene: Scene, columns: int) -> Scene:
    """``scene`` without the first ``columns`` columns of its views, ground truth and
    masks: the content moves against the pixel grid and the image's border."""
    def cut(array: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(array[:, columns:])
    return dataclasses.replace(scene, left=cut(scene.left), right=cut(scene.right),
                               ground_truth=cut(scene.ground_truth),
                               masks={name: cut(mask) for name, mask in scene.masks.items()})


def evaluate_noise(scenes: list[Scene], methods: dict, report: dict[str, Any], *,
                   levels: list[float], seeds: int,
                   on_done: Callable[[str, str], None] | None = None) -> dict[str, Any]:
    """Add the noise protocol of EVALUATION.md to ``report`` (made by :func:`evaluate`).

    For each method and level: the mean over ``seeds`` seeds (0 .. seeds-1) of the scene
    averages of the report's headline measure (bad 1.0 when it names none), under
    ``"noise": {"<level>": {"avg": ..., "per_seed": [...]}}``.
    """
    scoring = Scoring.of_report(report)
    for name, method in methods.items():
        run_method, _ = method_runner(method)
        noise = {}
        for level in levels:
            per_seed = []
            for seed in range(seeds):
                per_scene = {}
                for index, scene in enumerate(scenes):
                    left, right = noisy_pair(scene, index, level, seed)
                    disp = run_method(left, right, scene.min_disp, scene.max_disp)
                    per_scene[scene.name] = score_scene(disp, scene, scoring)
                    if on_done is not None:
                        on_done(name, f"{scene.name} noise {level:g} seed {seed}")
                per_seed.append({m: v for m, v in average(per_scene).items()
                                 if m != "metrics"})
            noise[f"{level:g}"] = {"avg": {m: float(np.mean([s[m] for s in per_seed]))
                                           for m in per_seed[0]},
                                   "per_seed": per_seed}
        report["methods"][name]["noise"] = noise
    return report


def format_noise_table(report: dict[str, Any], mask: str = "nonocc") -> str:
    """A row per method: the noise-free average, then the mean over seeds at each level."""
    methods = report["methods"]
    levels = list(next(iter(methods.values())).get("noise", {}))
    width = max(20, *(len(m) + 2 for m in methods))
    lines = [f"{mask} {report['metric']} (%) vs noise".ljust(width)
             + f"{'none':>10}" + "".join(f"{float(lv) * 100:>9g}%" for lv in levels)]
    for name, result in methods.items():
        cells = [result["avg"][mask]] + [result["noise"][lv]["avg"][mask] for lv in levels]
        lines.append(name.ljust(width) + "".join(f"{v:10.2f}" for v in cells))
    return "\n".join(lines) + "\n"
