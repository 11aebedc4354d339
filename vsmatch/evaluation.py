"""Bad-pixel figures on Middlebury scenes (EVALUATION.md)."""

from __future__ import annotations

import dataclasses
import re
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .config import Config, config_from_dict, load_config
from .datasets import Scene
from .io import (colour_disparity, error_image, imwrite_atomic, write_disparity,
                 write_text_atomic)
from .pipeline import match

MASKS = ("nonocc", "all", "disc")


def bad_pixel_map(disp: np.ndarray, ground_truth: np.ndarray, threshold: float) -> np.ndarray:
    """True where the estimate is off by more than ``threshold``; invalid estimates are bad."""
    with np.errstate(invalid="ignore"):
        good = np.abs(disp.astype(np.float64) - ground_truth) <= threshold
    return ~good


def bad_percent(disp: np.ndarray, ground_truth: np.ndarray, mask: np.ndarray,
                threshold: float = 1.0) -> float:
    """Percentage of ``mask`` pixels that are bad (EVALUATION.md, "bad 1.0")."""
    count = int(mask.sum())
    if count == 0:
        return float("nan")
    return 100.0 * float(bad_pixel_map(disp, ground_truth, threshold)[mask].sum()) / count


def score_scene(disp: np.ndarray, scene: Scene, threshold: float = 1.0) -> dict[str, float]:
    """Bad-pixel percentage of ``disp`` for each of the scene's masks."""
    return {m: bad_percent(disp, scene.ground_truth, scene.masks[m], threshold) for m in MASKS}


def average(per_scene: dict[str, dict[str, float]]) -> dict[str, float]:
    """Plain mean over the scenes, mask by mask."""
    return {m: float(np.mean([s[m] for s in per_scene.values()])) for m in MASKS}


def evaluate(scenes: list[Scene], methods: dict, *, dataset: str, threshold: float = 1.0,
             out_dir: str | Path | None = None,
             on_done: Callable[[str, str], None] | None = None) -> dict[str, Any]:
    """Run each method on each scene and score it; the result is the ``--json`` document.

    ``methods`` maps a display name to a config (name, path or :class:`Config`).
    ``on_done(method, scene)`` is called after each run (progress reporting).
    With ``out_dir``, each disparity is saved as PFM, a colour-mapped PNG and an error
    image (bad ``nonocc`` pixels red), with the resolved config beside them.
    """
    report: dict[str, Any] = {"dataset": dataset, "threshold": threshold, "methods": {}}
    for name, config in methods.items():
        cfg = load_config(config)
        folder = None if out_dir is None else Path(out_dir) / _safe_name(name)
        per_scene = {}
        for scene in scenes:
            start = time.perf_counter()
            disp = match(scene.left, scene.right, max_disp=scene.max_disp, config=cfg)
            seconds = time.perf_counter() - start
            per_scene[scene.name] = {**score_scene(disp, scene, threshold), "seconds": seconds}
            if folder is not None:
                save_scene_outputs(folder, scene, disp, threshold)
            if on_done is not None:
                on_done(name, scene.name)
        if folder is not None:
            folder.mkdir(parents=True, exist_ok=True)
            write_text_atomic(folder / "config.yaml",
                              yaml.safe_dump(cfg.to_dict(), sort_keys=False))
        report["methods"][name] = {"scenes": per_scene, "avg": average(per_scene)}
    return report


def _safe_name(name: str) -> str:
    """A folder name for a method: a YAML path's stem, other characters made safe."""
    if name.endswith((".yaml", ".yml")):
        name = Path(name).stem
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("_") or "method"


def save_scene_outputs(folder: Path, scene: Scene, disp: np.ndarray, threshold: float) -> None:
    """Disparity (PFM), colour-mapped disparity and error image of one scene."""
    folder.mkdir(parents=True, exist_ok=True)
    write_disparity(folder / f"{scene.name}.pfm", disp)
    imwrite_atomic(folder / f"{scene.name}_disp.png", colour_disparity(disp, scene.max_disp))
    bad = bad_pixel_map(disp, scene.ground_truth, threshold)
    imwrite_atomic(folder / f"{scene.name}_error.png",
                   error_image(disp, bad, scene.masks["nonocc"], scene.max_disp))


def format_tables(report: dict[str, Any]) -> str:
    """One table per mask, shaped like the paper's Table 1: a row per method."""
    methods = report["methods"]
    if not methods:
        return ""
    scenes = list(next(iter(methods.values()))["scenes"])
    width = max(20, *(len(m) + 2 for m in methods))
    lines = []
    for mask in MASKS:
        lines.append(f"{mask} bad {report['threshold']:.1f} (%)".ljust(width)
                     + "".join(f"{s:>10}" for s in scenes) + f"{'avg':>10}")
        for name, result in methods.items():
            cells = [result["scenes"][s][mask] for s in scenes] + [result["avg"][mask]]
            lines.append(name.ljust(width) + "".join(f"{v:10.2f}" for v in cells))
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def ablation_configs(base: Config) -> dict[str, Config]:
    """The refinement chain built up stage by stage to ``base``, then two alternatives.

    The first row is ``base`` with every §5 stage off (§1-4); each next row switches one
    stage on with ``base``'s values for it, so the last of them is ``base`` itself. Then
    ``base`` with the other filling (16 search directions, the "proper interpolation" of
    §5.3, or 2 when ``base`` uses more), and ``base`` with the direction factor ``kappa``
    at 0 (or at 0.5 when ``base`` has 0).
    """
    def section(name: str, **changes) -> dict:
        return {name: {**dataclasses.asdict(getattr(base, name)), **changes}}

    steps = [
        ("§1-4: cost, aggregation, LR check, fill",
         {"scanline": {"enabled": False}, "voting": {"enabled": False},
          "discontinuity": {"enabled": False}, "subpixel": {"enabled": False, "median": False}}),
        ("+ scanline optimisation", section("scanline", enabled=True)),
        ("+ region voting", section("voting", enabled=True)),
        ("+ discontinuity adjustment", section("discontinuity", enabled=True)),
        ("+ sub-pixel", {"subpixel": {"enabled": True, "median": False}}),
        ("+ 3x3 median", {"subpixel": {"enabled": True, "median": True}}),
    ]
    configs = {}
    cfg = base
    for label, change in steps:
        cfg = config_from_dict(change, base=cfg)
        configs[label] = cfg
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


def evaluate_noise(scenes: list[Scene], methods: dict, report: dict[str, Any], *,
                   levels: list[float], seeds: int, threshold: float = 1.0,
                   on_done: Callable[[str, str], None] | None = None) -> dict[str, Any]:
    """Add the noise protocol of EVALUATION.md to ``report`` (made by :func:`evaluate`).

    For each method and level: the mean over ``seeds`` seeds (0 .. seeds-1) of the
    four-scene averages, under ``"noise": {"<level>": {"avg": ..., "per_seed": [...]}}``.
    """
    for name, config in methods.items():
        cfg = load_config(config)
        noise = {}
        for level in levels:
            per_seed = []
            for seed in range(seeds):
                per_scene = {}
                for index, scene in enumerate(scenes):
                    left, right = noisy_pair(scene, index, level, seed)
                    disp = match(left, right, max_disp=scene.max_disp, config=cfg)
                    per_scene[scene.name] = score_scene(disp, scene, threshold)
                    if on_done is not None:
                        on_done(name, f"{scene.name} noise {level:g} seed {seed}")
                per_seed.append(average(per_scene))
            noise[f"{level:g}"] = {"avg": {m: float(np.mean([s[m] for s in per_seed]))
                                           for m in MASKS},
                                   "per_seed": per_seed}
        report["methods"][name]["noise"] = noise
    return report


def format_noise_table(report: dict[str, Any], mask: str = "nonocc") -> str:
    """A row per method: the noise-free average, then the mean over seeds at each level."""
    methods = report["methods"]
    levels = list(next(iter(methods.values())).get("noise", {}))
    width = max(20, *(len(m) + 2 for m in methods))
    lines = [f"{mask} bad {report['threshold']:.1f} (%) vs noise".ljust(width)
             + f"{'none':>10}" + "".join(f"{float(lv) * 100:>9g}%" for lv in levels)]
    for name, result in methods.items():
        cells = [result["avg"][mask]] + [result["noise"][lv]["avg"][mask] for lv in levels]
        lines.append(name.ljust(width) + "".join(f"{v:10.2f}" for v in cells))
    return "\n".join(lines) + "\n"
