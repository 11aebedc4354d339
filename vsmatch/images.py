"""Conversions between the image forms the stages use."""

from __future__ import annotations

import cv2
import numpy as np


def to_grey(image: np.ndarray) -> np.ndarray:
    """Grey level (float32, 0..255) of a BGR colour image or of a grey one."""
    if image.ndim == 2:
        return image.astype(np.float32)
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY).astype(np.float32)


def as_channels(image: np.ndarray) -> np.ndarray:
    """(H, W, C) uint8, C-contiguous; a grey image gets one channel."""
    if image.ndim == 2:
        image = image[:, :, None]
    return np.ascontiguousarray(image, dtype=np.uint8)
