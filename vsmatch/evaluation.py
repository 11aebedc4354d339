"""Bad-pixel figures on Middlebury scenes (EVALUATION.md)."""

from __future__ import annotations

import numpy as np

from .datasets import Scene

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
