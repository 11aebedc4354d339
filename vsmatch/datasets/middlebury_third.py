"""Middlebury 2005/2006 at third size: nine scenes, masks from left-right consistency."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np

from ..io import read_image
from .base import Scene, check_names, read_grey

SCENES = ("Aloe", "Art", "Baby1", "Books", "Cloth1", "Dolls", "Laundry", "Moebius",
          "Reindeer")
SCALE = 3


def consistency_masks(gt_left: np.ndarray, gt_right: np.ndarray) -> dict[str, np.ndarray]:
    """Masks of a scene that has left and right ground truth but no official masks.

    ``nonocc``: known, and the right ground truth at x - d agrees within 1 pixel;
    ``all``: known; ``disc``: non-occluded pixels within 4 pixels of a ground-truth jump
    larger than 2 pixels (Middlebury's rule, approximated).
    """
    known = gt_left > 0
    ys, xs = np.nonzero(known)
    xr = np.round(xs - gt_left[ys, xs]).astype(int)
    inside = xr >= 0
    agree = np.zeros_like(known)
    ok = inside.copy()
    ok[inside] = (gt_right[ys[inside], xr[inside]] > 0) & (
        np.abs(gt_right[ys[inside], xr[inside]] - gt_left[ys[inside], xs[inside]]) <= 1.0)
    agree[ys[ok], xs[ok]] = True
    filled = np.where(known, gt_left, 0).astype(np.float32)
    kernel = np.ones((3, 3), np.uint8)
    jump = (cv2.dilate(filled, kernel) - cv2.erode(np.where(known, filled, 1e4).astype(
        np.float32), kernel)) > 2.0
    jump &= known
    near = cv2.dilate(jump.astype(np.uint8), np.ones((9, 9), np.uint8)) > 0
    return {"nonocc": agree, "all": known, "disc": agree & near}


def load(folder: Path, names=None) -> list[Scene]:
    """``view1``/``view5``, ground truth ``disp1 / 3``, range ``0 .. ceil(max gt)``."""
    scenes = []
    for name in check_names(list(SCENES), names, folder):
        d = folder / name
        gt_l = read_grey(d / "disp1.png").astype(np.float32) / SCALE
        gt_r = read_grey(d / "disp5.png").astype(np.float32) / SCALE
        max_disp = int(math.ceil(gt_l.max()))
        scenes.append(Scene(name, read_image(d / "view1.png"), read_image(d / "view5.png"),
                            gt_l, consistency_masks(gt_l, gt_r), max_disp))
    return scenes
