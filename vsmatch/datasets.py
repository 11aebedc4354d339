"""The Middlebury evaluation data: scenes with ground truth and evaluation masks.

The data are read at run time from a *data root*, the folder that holds ``middlebury2/``
and ``middlebury-2005-2006-third/``: the ``--data-root`` option, else the ``VSMATCH_DATA``
environment variable, else the first of :data:`DEFAULT_DATA_ROOTS` that exists.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .io import read_image

#: Where the data are looked for when neither --data-root nor VSMATCH_DATA is given,
#: relative to the current folder (the second fits a checkout beside ``shared/``).
DEFAULT_DATA_ROOTS = ("data", "../shared/data")


class DatasetError(ValueError):
    """A dataset that cannot be found or read; the message is one line."""


@dataclass(frozen=True)
class Scene:
    """One stereo pair with its ground truth (left view) and evaluation masks."""

    name: str
    left: np.ndarray
    right: np.ndarray
    ground_truth: np.ndarray  # float32 disparity in pixels; 0 where unknown
    masks: dict[str, np.ndarray]  # "nonocc", "all", "disc": bool (H, W)
    max_disp: int  # the largest disparity searched


# name: (scale of groundtruth.png, largest disparity of the official range)
MIDDLEBURY2_SCENES = {"tsukuba": (16, 15), "venus": (8, 19), "teddy": (4, 59), "cones": (4, 59)}
THIRD_SCENES = ("Aloe", "Art", "Baby1", "Books", "Cloth1", "Dolls", "Laundry", "Moebius",
                "Reindeer")
THIRD_SCALE = 3

DATASET_FOLDERS = {"middlebury2": "middlebury2",
                   "middlebury-third": "middlebury-2005-2006-third"}


def resolve_data_root(data_root: str | Path | None = None) -> list[Path]:
    """The candidate data roots, in the order they are tried."""
    if data_root is not None:
        return [Path(data_root)]
    if os.environ.get("VSMATCH_DATA"):
        return [Path(os.environ["VSMATCH_DATA"])]
    return [Path(p) for p in DEFAULT_DATA_ROOTS]


def dataset_folder(dataset: str, data_root: str | Path | None = None) -> Path:
    """The folder of ``dataset``; a one-line :class:`DatasetError` says where it looked."""
    if dataset not in DATASET_FOLDERS:
        raise DatasetError(f"unknown dataset '{dataset}' (known: {', '.join(DATASET_FOLDERS)})")
    tried = []
    for root in resolve_data_root(data_root):
        folder = root / DATASET_FOLDERS[dataset]
        if folder.is_dir():
            return folder
        tried.append(str(folder.resolve()))
    raise DatasetError(f"dataset '{dataset}' not found; looked in {', '.join(tried)} "
                       "(set --data-root or VSMATCH_DATA)")


def _read_grey(path: Path) -> np.ndarray:
    if not path.is_file():
        raise DatasetError(f"{path}: file not found")
    image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise DatasetError(f"{path}: not a readable image")
    return image


def load_middlebury2(folder: Path, names=None) -> list[Scene]:
    """The four Middlebury v2 scenes (tsukuba, venus, teddy, cones) with official masks."""
    scenes = []
    for name in names or MIDDLEBURY2_SCENES:
        scale, max_disp = MIDDLEBURY2_SCENES[name]
        d = folder / name
        gt = _read_grey(d / "groundtruth.png").astype(np.float32) / scale
        masks = {m: _read_grey(d / f"{m}.png") == 255 for m in ("nonocc", "all", "disc")}
        scenes.append(Scene(name, read_image(d / "imL.png"), read_image(d / "imR.png"),
                            gt, masks, max_disp))
    return scenes


def consistency_masks(gt_left: np.ndarray, gt_right: np.ndarray) -> dict[str, np.ndarray]:
    """Masks of a scene that has left and right ground truth but no official masks.

    ``nonocc``: known, and the right ground truth at x - d agrees within 1 pixel;
    ``all``: known; ``disc``: non-occluded pixels within 4 pixels of a ground-truth jump
    larger than 2 pixels (Middlebury's rule, approximated).
    """
    height, width = gt_left.shape
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


def load_middlebury_third(folder: Path, names=None) -> list[Scene]:
    """The nine 2005/2006 scenes at third size, masks from left-right consistency."""
    scenes = []
    for name in names or THIRD_SCENES:
        d = folder / name
        gt_l = _read_grey(d / "disp1.png").astype(np.float32) / THIRD_SCALE
        gt_r = _read_grey(d / "disp5.png").astype(np.float32) / THIRD_SCALE
        max_disp = int(math.ceil(gt_l.max()))
        scenes.append(Scene(name, read_image(d / "view1.png"), read_image(d / "view5.png"),
                            gt_l, consistency_masks(gt_l, gt_r), max_disp))
    return scenes


LOADERS = {"middlebury2": load_middlebury2, "middlebury-third": load_middlebury_third}


def load_dataset(dataset: str, data_root: str | Path | None = None, names=None) -> list[Scene]:
    """All scenes of ``dataset`` (``middlebury2`` or ``middlebury-third``)."""
    return LOADERS[dataset](dataset_folder(dataset, data_root), names)
