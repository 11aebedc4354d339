"""KITTI 2015 and 2012 training frames (the official layout under ``training/``).

Ground truth is a 16-bit PNG, disparity = value / 256, 0 = unknown, sparse (laser).
KITTI gives no search range; vsmatch evaluates with ``0 .. 191`` (192 levels, the usual
choice), which covers the true disparities of the training frames.
"""

from __future__ import annotations

from pathlib import Path

from ..io import read_image
from .base import DatasetError, Scene, check_names, read_png16_disparity

MAX_DISP = 191

#: Per version: left images, right images, ground truth with occluded pixels, without.
LAYOUTS = {"kitti2015": ("image_2", "image_3", "disp_occ_0", "disp_noc_0"),
           "kitti2012": ("colored_0", "colored_1", "disp_occ", "disp_noc")}


def _loader(version: str):
    left_dir, right_dir, occ_dir, noc_dir = LAYOUTS[version]

    def load(folder: Path, names=None) -> list[Scene]:
        training = folder / "training"
        gt_folder = training / occ_dir
        if not gt_folder.is_dir():
            raise DatasetError(f"{gt_folder}: folder not found (KITTI layout: "
                               f"training/{left_dir}, {right_dir}, {occ_dir})")
        # Frames with ground truth are the *_10.png ones.
        available = sorted(p.stem.removesuffix("_10") for p in gt_folder.glob("*_10.png"))
        scenes = []
        for name in check_names(available, names, gt_folder):
            file = f"{name}_10.png"
            occ = read_png16_disparity(gt_folder / file)
            masks = {"all": occ > 0}
            noc_file = training / noc_dir / file
            if noc_file.is_file():
                masks = {"nonocc": read_png16_disparity(noc_file) > 0, **masks}
            scenes.append(Scene(name, read_image(training / left_dir / file),
                                read_image(training / right_dir / file), occ, masks,
                                MAX_DISP))
        return scenes

    return load


load_kitti2015 = _loader("kitti2015")
load_kitti2012 = _loader("kitti2012")
