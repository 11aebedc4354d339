"""Peer methods run beside vsmatch in ``eval`` and ``bench``: OpenCV's StereoSGBM."""

from __future__ import annotations

import cv2
import numpy as np

from .disparity import INVALID_DISPARITY

#: ``eval --method`` names of the peers.
PEER_METHODS = ("opencv-sgbm",)


def sgbm_matcher(max_disp: int, channels: int = 3, *, min_disp: int = 0,
                 mode: int = cv2.STEREO_SGBM_MODE_HH) -> cv2.StereoSGBM:
    """OpenCV StereoSGBM, block size 3 (mode HH unless told), covering
    ``min_disp .. max_disp`` (rounded up to the multiple of 16 it needs)."""
    levels = (max_disp - min_disp + 1 + 15) // 16 * 16
    block = 3
    return cv2.StereoSGBM_create(minDisparity=min_disp, numDisparities=levels,
                                 blockSize=block, P1=8 * channels * block ** 2,
                                 P2=32 * channels * block ** 2, mode=mode)


def sgbm_disparity(left: np.ndarray, right: np.ndarray, *, max_disp: int,
                   min_disp: int = 0) -> np.ndarray:
    """SGBM's left disparity (float32) with its holes filled from the left, as in
    EVALUATION.md (see :func:`sgbm_fill_from_left`)."""
    channels = 1 if left.ndim == 2 else left.shape[2]
    raw = sgbm_matcher(max_disp, channels, min_disp=min_disp).compute(left, right)
    return sgbm_fill_from_left(raw, min_disp)


def sgbm_fill_from_left(raw: np.ndarray, min_disp: int = 0) -> np.ndarray:
    """SGBM's fixed-point output (16 x d) as float32 disparities, each invalid pixel
    taking the nearest valid disparity to its left; what has no valid pixel to its left
    (SGBM's empty left margin) stays invalid."""
    disp = raw.astype(np.float32) / 16.0
    valid = raw >= (min_disp * 16)
    last_valid = np.maximum.accumulate(np.where(valid, np.arange(disp.shape[1]), -1), axis=1)
    rows = np.arange(disp.shape[0])[:, None]
    filled = disp[rows, np.maximum(last_valid, 0)]
    filled[last_valid < 0] = INVALID_DISPARITY
    return filled.astype(np.float32)
