"""Middlebury 2014 (MiddEval3 training layout), at quarter, half or full size.

One folder per scene: ``im0.png``, ``im1.png``, ``calib.txt``, ``disp0GT.pfm``,
``mask0nocc.png`` (255 non-occluded, 128 occluded, 0 unknown). The range is
``0 .. ndisp - 1`` from ``calib.txt``.
"""

from __future__ import annotations

from pathlib import Path

from ..geometry import read_calibration
from ..io import read_image
from .base import (DatasetError, Scene, check_names, midd_eval3_masks, read_grey,
                   read_pfm_disparity)

#: The files a training scene must have (the ground truth comes from a second archive).
SCENE_FILES = ("im0.png", "im1.png", "calib.txt", "disp0GT.pfm", "mask0nocc.png")


def scene_names(folder: Path) -> list[str]:
    """The sub-folders that hold a view (``im0.png`` or ``im1.png``), sorted: one that
    lacks the other is an error when it is read, never skipped."""
    return sorted(p.name for p in folder.iterdir()
                  if (p / "im0.png").is_file() or (p / "im1.png").is_file())


def load(folder: Path, names=None) -> list[Scene]:
    scenes = []
    for name in check_names(scene_names(folder), names, folder):
        d = folder / name
        calib = read_calibration(d / "calib.txt")
        if calib.ndisp is None:
            raise DatasetError(f"{d / 'calib.txt'}: no ndisp")
        gt = read_pfm_disparity(d / "disp0GT.pfm")
        masks = midd_eval3_masks(d, gt, read_grey(d / "mask0nocc.png"))
        scenes.append(Scene(name, read_image(d / "im0.png"), read_image(d / "im1.png"),
                            gt, masks, calib.ndisp - 1, calib=calib))
    return scenes


def missing_files(scene_folder: Path) -> list[str]:
    """The files of :data:`SCENE_FILES` that ``scene_folder`` lacks."""
    return [f for f in SCENE_FILES if not (scene_folder / f).is_file()]
