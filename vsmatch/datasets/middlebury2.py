"""Middlebury v2 (2001/2003): tsukuba, venus, teddy, cones with the official masks."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io import read_image
from .base import Scene, check_names, read_grey

# name: (scale of groundtruth.png, largest disparity of the official range)
SCENES = {"tsukuba": (16, 15), "venus": (8, 19), "teddy": (4, 59), "cones": (4, 59)}


def load(folder: Path, names=None) -> list[Scene]:
    """The four scenes, ``groundtruth.png / scale``, masks ``nonocc``, ``all``, ``disc``."""
    scenes = []
    for name in check_names(list(SCENES), names, folder):
        scale, max_disp = SCENES[name]
        d = folder / name
        gt = read_grey(d / "groundtruth.png").astype(np.float32) / scale
        masks = {m: read_grey(d / f"{m}.png") == 255 for m in ("nonocc", "all", "disc")}
        scenes.append(Scene(name, read_image(d / "imL.png"), read_image(d / "imR.png"),
                            gt, masks, max_disp))
    return scenes
