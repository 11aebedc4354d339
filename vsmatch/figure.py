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
from .evaluation import Scoring, headline_figure, headline_mask
from .preview import colour_disparity, error_image

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
            headline = headline_figure(report["methods"][method]["scenes"][scene.name])
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


def tradeoff_plot(points: dict[str, tuple[float, float]], *, x_label: str, y_label: str,
                  title: str, size: tuple[int, int] = (760, 480)) -> np.ndarray:
    """A scatter plot of ``name: (seconds, error)`` with each point named: the time
    against error trade-off (``vsmatch bench --plot``). Points whose name starts with
    ``sgbm`` are drawn grey, the others blue; lower left is better. BGR uint8."""
    width, height = size
    left, right, top, bottom = 70, 150, 40, 50
    image = np.full((height, width, 3), 255, np.uint8)
    xs = [x for x, _ in points.values()]
    ys = [y for _, y in points.values()]
    x_max = max(xs) * 1.1
    y_max = max(ys) * 1.1

    def to_pixel(x: float, y: float) -> tuple[int, int]:
        return (round(left + x / x_max * (width - left - right)),
                round(height - bottom - y / y_max * (height - top - bottom)))

    black, grey = (0, 0, 0), (150, 150, 150)
    cv2.line(image, to_pixel(0, 0), to_pixel(x_max, 0), black, 1)
    cv2.line(image, to_pixel(0, 0), to_pixel(0, y_max), black, 1)
    for k in range(6):  # ticks at sixths of the ranges
        x, y = x_max * k / 6, y_max * k / 6
        px, py = to_pixel(x, 0)
        cv2.line(image, (px, py), (px, py + 4), black, 1)
        _text(image, f"{x:.2f}", (px - 14, py + 18), scale=0.4, colour=black)
        qx, qy = to_pixel(0, y)
        cv2.line(image, (qx - 4, qy), (qx, qy), black, 1)
        _text(image, f"{y:.1f}", (qx - 40, qy + 4), scale=0.4, colour=black)
    _text(image, x_label, (left, height - 10), scale=0.45, colour=black)
    _text(image, y_label, (8, top - 12), scale=0.45, colour=black)
    _text(image, title, (left + 120, top - 12), scale=0.5, colour=black)
    placed: list[tuple[int, int]] = []
    for name, (x, y) in sorted(points.items(), key=lambda item: item[1][1]):
        colour = grey if name.startswith("sgbm") else (200, 80, 0)
        centre = to_pixel(x, y)
        cv2.circle(image, centre, 6, colour, -1, cv2.LINE_AA)
        label = [centre[0] + 9, centre[1] + 5]
        while any(abs(label[0] - a) < 90 and abs(label[1] - b) < 15 for a, b in placed):
            label[1] -= 15  # names of close points stack upwards instead of overlapping
        placed.append((label[0], label[1]))
        _text(image, name, tuple(label), scale=0.5, colour=colour)
    return image
