"""A picture of an evaluation, like the seed paper's Figure 1.

One row per scene: the left view, the ground truth, then for each method its
colour-mapped disparity and its error map (bad pixels red, pixels not evaluated dark),
with the scene's headline figure printed on the error map.
"""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from .datasets import Scene
from .evaluation import Scoring, headline_mask
from .io import colour_disparity, error_image

#: Height of a row, pixels; each tile keeps its scene's aspect ratio.
ROW_HEIGHT = 200
TITLE_HEIGHT = 28
GAP = 4


def results_figure(scenes: list[Scene], report: dict[str, Any],
                   disparities: dict) -> np.ndarray:
    """The figure as a BGR uint8 image; ``disparities[(method, scene)]`` from evaluate."""
    scoring = Scoring.of_report(report)
    methods = list(report["methods"])
    titles = ["left view", "ground truth"]
    for method in methods:
        titles += [method, f"{method}: {report['metric']} {_mask_name(scenes)}"]
    rows = []
    for scene in scenes:
        gt = np.where(scene.ground_truth > 0, scene.ground_truth, np.inf).astype(np.float32)
        # Colours span the true disparities, not the search range (KITTI searches 0..191
        # for disparities up to about 80).
        top = float(scene.ground_truth.max()) or float(max(scene.max_disp, 1))
        tiles = [scene.left, colour_disparity(gt, top)]
        mask = headline_mask(scene)
        for method in methods:
            disp = disparities[(method, scene.name)]
            tiles.append(colour_disparity(disp, top))
            errors = error_image(disp, scoring.bad_map(disp, scene.ground_truth), mask, top)
            figure = report["methods"][method]["scenes"][scene.name]
            headline = figure.get("nonocc", figure.get("all"))
            tiles.append(_label(errors, f"{scene.name} {headline:.2f} %"))
        rows.append(tiles)
    return _grid(titles, rows)


def confidence_figure(scenes: list[Scene], results: dict, scoring: Scoring,
                      threshold: float) -> np.ndarray:
    """How to read the confidence, one row per scene: the left view, the disparity, the
    confidence (black 0 .. white 1), and the errors it flags at ``threshold``: wrong
    pixels below it green (flagged), wrong pixels above it red (missed), right pixels
    below it blue (left out though right); the rest grey. ``results[scene name]`` is a
    :class:`vsmatch.pipeline.MatchResult`."""
    titles = ["left view", "disparity", "confidence (black 0, white 1)",
              f"errors < {threshold:g}: green flagged, red missed; blue right, cut"]
    rows = []
    for scene in scenes:
        result = results[scene.name]
        top = float(scene.ground_truth.max()) or float(max(scene.max_disp, 1))
        conf = (np.clip(result.confidence, 0, 1) * 255).astype(np.uint8)
        bad = scoring.bad_map(result.disparity, scene.ground_truth)
        known = headline_mask(scene) & np.isfinite(scene.ground_truth)
        low = result.confidence < threshold
        grey = cv2.cvtColor(cv2.cvtColor(scene.left, cv2.COLOR_BGR2GRAY)
                            if scene.left.ndim == 3 else scene.left, cv2.COLOR_GRAY2BGR)
        flags = (grey // 2 + 64).astype(np.uint8)
        flags[~known] //= 3
        flags[known & bad & low] = (0, 200, 0)
        flags[known & bad & ~low] = (0, 0, 255)
        flags[known & ~bad & low] = (255, 120, 0)
        flagged = (known & bad & low).sum() / max(1, (known & bad).sum())
        rows.append([scene.left, colour_disparity(result.disparity, top), conf,
                     _label(flags, f"{scene.name}: {100 * flagged:.0f} % of errors flagged")])
    return _grid(titles, rows)


def _grid(titles: list[str], rows: list[list[np.ndarray]]) -> np.ndarray:
    """Tiles in rows of one height under a header of titles, white gaps between."""
    rows = [[_fit(t, ROW_HEIGHT) for t in row] for row in rows]
    widths = [max(row[k].shape[1] for row in rows) for k in range(len(titles))]
    header = np.full((TITLE_HEIGHT, sum(widths) + GAP * (len(widths) - 1), 3), 255, np.uint8)
    x = 0
    for title, width in zip(titles, widths):
        _text(header, title, (x + 4, TITLE_HEIGHT - 9), scale=0.5, colour=(0, 0, 0))
        x += width + GAP
    lines = [header]
    for row in rows:
        line = np.full((ROW_HEIGHT + GAP, header.shape[1], 3), 255, np.uint8)
        x = 0
        for tile, width in zip(row, widths):
            line[:ROW_HEIGHT, x:x + tile.shape[1]] = tile
            x += width + GAP
        lines.append(line)
    return np.vstack(lines)


def _mask_name(scenes: list[Scene]) -> str:
    return "nonocc" if all("nonocc" in s.masks for s in scenes) else "all"


def _fit(image: np.ndarray, height: int) -> np.ndarray:
    if image.ndim == 2:
        image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    width = max(1, round(image.shape[1] * height / image.shape[0]))
    return cv2.resize(image, (width, height), interpolation=cv2.INTER_AREA)


def _label(image: np.ndarray, text: str) -> np.ndarray:
    """``text`` in white on a dark band at the top, legible at the figure's row height."""
    out = image.copy()
    scale = max(0.5, image.shape[0] / 400)
    band = int(30 * scale)
    out[:band] = (out[:band] * 0.35).astype(np.uint8)
    _text(out, text, (6, int(22 * scale)), scale=scale, colour=(255, 255, 255))
    return out


def _text(image, text, origin, *, scale, colour) -> None:
    cv2.putText(image, text, origin, cv2.FONT_HERSHEY_SIMPLEX, scale, colour,
                max(1, round(scale * 1.6)), cv2.LINE_AA)
