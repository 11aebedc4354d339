"""ETH3D low-res two-view (training), in the MiddEval3 layout: grey indoor and outdoor scenes.

One folder per scene: ``im0.png``, ``im1.png`` (grey), ``calib.txt``, ``disp0GT.pfm``
(``inf`` unknown), ``mask0nocc.png`` (255 non-occluded). The files' ``ndisp`` is a
placeholder (the image width), so the range searched is ``0 .. ceil(1.1 x`` the largest
ground-truth disparity ``)``, as EVALUATION.md's protocol says.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..geometry import read_calibration
from ..io import read_image
from .base import Scene, check_names, midd_eval3_masks, read_grey, read_pfm_disparity
from .middlebury2014 import scene_names

#: The range searched, as a multiple of the largest ground-truth disparity.
RANGE_MARGIN = 1.1


def load(folder: Path, names=None) -> list[Scene]:
    scenes = []
    for name in check_names(scene_names(folder), names, folder):
        d = folder / name
        gt = read_pfm_disparity(d / "disp0GT.pfm")
        masks = midd_eval3_masks(d, gt, read_grey(d / "mask0nocc.png"))
        left = read_image(d / "im0.png")
        max_disp = min(math.ceil(RANGE_MARGIN * float(gt.max())), left.shape[1] - 1)
        scenes.append(Scene(name, left, read_image(d / "im1.png"), gt, masks,
                            max(max_disp, 1), calib=read_calibration(d / "calib.txt")))
    return scenes
