"""What every dataset reader shares: the scene record, its error, and file reading."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from ..io import ImageError, read_pfm


class DatasetError(ValueError):
    """A dataset that cannot be found or read; the message is one line."""


@dataclass(frozen=True)
class Scene:
    """One stereo pair with its ground truth (left view) and evaluation masks."""

    name: str
    left: np.ndarray
    right: np.ndarray
    ground_truth: np.ndarray  # float32 disparity in pixels; 0 where unknown
    masks: dict[str, np.ndarray]  # "nonocc", "all" (and "disc"): bool (H, W)
    max_disp: int  # the largest disparity of the official range
    min_disp: int = 0  # the smallest one
    calib: Any = None  # a geometry.Calibration where the dataset gives one


def scene_problem(scene: Scene) -> str | None:
    """Why a scene as read cannot be scored (views, ground truth and masks of different
    sizes, no pixel with ground truth), or None."""
    height, width = scene.left.shape[:2]
    if scene.right.shape != scene.left.shape:
        return (f"the views differ in size: {width}x{height} and "
                f"{scene.right.shape[1]}x{scene.right.shape[0]}")
    arrays = {"the ground truth": scene.ground_truth, **{
        f"the {name} mask": mask for name, mask in scene.masks.items()}}
    for what, array in arrays.items():
        if array.shape[:2] != (height, width):
            return (f"{what} is {array.shape[1]}x{array.shape[0]}, the views "
                    f"{width}x{height}")
    for name, mask in scene.masks.items():
        if not mask.any():
            return f"no pixel of the {name} mask has ground truth"
    return None


def midd_eval3_masks(folder: Path, gt: np.ndarray, nocc: np.ndarray
                     ) -> dict[str, np.ndarray]:
    """MiddEval3's masks of a scene: "nonocc" (known and ``mask0nocc == 255``) and "all"
    (known); a mask of another size than the ground truth is an error naming both."""
    if nocc.shape != gt.shape:
        raise DatasetError(f"{folder}: mask0nocc.png is {nocc.shape[1]}x{nocc.shape[0]}, "
                           f"disp0GT.pfm {gt.shape[1]}x{gt.shape[0]}")
    known = gt > 0
    return {"nonocc": known & (nocc == 255), "all": known}


def read_grey(path: Path) -> np.ndarray:
    """An 8-bit single-channel image (masks, 8-bit ground truth)."""
    return _read(path, cv2.IMREAD_GRAYSCALE)


def read_png16_disparity(path: Path) -> np.ndarray:
    """KITTI ground truth: 16-bit PNG, disparity = value / 256, 0 = unknown."""
    raw = _read(path, cv2.IMREAD_UNCHANGED)
    if raw.dtype != np.uint16 or raw.ndim != 2:
        raise DatasetError(f"{path}: expected a 16-bit single-channel PNG")
    return raw.astype(np.float32) / 256.0


def read_pfm_disparity(path: Path) -> np.ndarray:
    """Middlebury 2014 ground truth: float32 PFM, ``inf`` = unknown, returned as 0."""
    try:
        gt = read_pfm(path)
    except ImageError as exc:
        raise DatasetError(str(exc)) from None
    gt[~np.isfinite(gt)] = 0.0
    return gt


def _read(path: Path, flags: int) -> np.ndarray:
    if not path.is_file():
        raise DatasetError(f"{path}: file not found")
    image = cv2.imread(str(path), flags)
    if image is None:
        raise DatasetError(f"{path}: not a readable image")
    return image


def check_names(available: list[str], names, folder: Path) -> list[str]:
    """``names`` (all of ``available`` when None), refusing one that is not there."""
    if names is None:
        return available
    missing = [n for n in names if n not in available]
    if missing:
        raise DatasetError(f"{folder}: no scene {', '.join(missing)} "
                           f"(found: {', '.join(available) or 'none'})")
    return list(names)
