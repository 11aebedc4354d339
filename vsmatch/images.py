"""Conversions between the image forms the stages use."""

from __future__ import annotations

import cv2
import numpy as np

from ._kernels.arms import colour_change as colour_change_kernel


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


def colour_change(image: np.ndarray, threshold: float, *, along_rows: bool) -> np.ndarray:
    """uint8 (H, W): 1 where the largest channel difference from the previous pixel
    along the axis ((y, x - 1) on rows, (y - 1, x) on columns) is ``threshold`` or more,
    and in the first column (row), which has no previous pixel."""
    image = as_channels(image)
    out = np.empty(image.shape[:2], dtype=np.uint8)
    colour_change_kernel(image, float(threshold), int(along_rows), out)
    return out


def mirrored(array: np.ndarray, *, axis: int = -1, pad: int = 0, fill: int = 0) -> np.ndarray:
    """``array`` reversed along ``axis`` (its x axis), then ``pad`` entries of ``fill``;
    C-contiguous.

    The kernels read the right view this way: the right pixel x - d of x, at
    ``width - 1 - x + d``, lies forward in memory, and the padding stands for x - d < 0.
    """
    axis = axis % array.ndim
    shape = list(array.shape)
    shape[axis] += pad
    out = np.empty(shape, dtype=array.dtype)  # each entry written once
    inside = [slice(None)] * array.ndim
    inside[axis] = slice(0, array.shape[axis])
    out[tuple(inside)] = np.flip(array, axis)
    if pad:
        inside[axis] = slice(array.shape[axis], None)
        out[tuple(inside)] = fill
    return out


def row_blocks(height: int, rows: int, margin: int, start: int = 0, stop: int | None = None):
    """``(top, bottom, y0, y1)`` of blocks of at most ``rows`` rows tiling ``start ..
    stop`` (default: the whole height), each with the ``margin`` rows on either side that
    the image has: ``y0 .. y1`` is read, ``top .. bottom`` kept."""
    stop = height if stop is None else stop
    for top in range(start, stop, rows):
        bottom = min(stop, top + rows)
        yield top, bottom, max(0, top - margin), min(height, bottom + margin)
