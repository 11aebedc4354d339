"""Conversions between the image forms the stages use."""

from __future__ import annotations

import cv2
import numpy as np

from ._kernels.arms import colour_change as colour_change_kernel
from ._kernels.images import channel_planes as channel_planes_kernel
from ._kernels.images import doubled
from ._kernels.photometric import box_mean, plane_box_mean


def to_grey(image: np.ndarray) -> np.ndarray:
    """Grey level (float32, 0..255) of a BGR colour image or of a grey one."""
    return grey_levels(image).astype(np.float32)


def grey_levels(image: np.ndarray) -> np.ndarray:
    """The grey image of a BGR colour image (OpenCV's weights, its dtype), or a grey one
    as it is."""
    return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def as_channels(image: np.ndarray) -> np.ndarray:
    """(H, W, C) uint8, C-contiguous; a grey image gets one channel."""
    if image.ndim == 2:
        image = image[:, :, None]
    return np.ascontiguousarray(image, dtype=np.uint8)


def channel_planes(image: np.ndarray) -> np.ndarray:
    """The view as (C, H, W) int16 planes, each channel's pixels side by side (a grey
    view: one plane), as the arms and the colour changes read it."""
    image = as_channels(image)
    planes = np.empty((image.shape[2],) + image.shape[:2], np.int16)
    channel_planes_kernel(image, planes)
    return planes


def colour_change(image: np.ndarray, threshold: float, *, along_rows: bool,
                  planes: np.ndarray | None = None) -> np.ndarray:
    """uint8 (H, W): 1 where the largest channel difference from the previous pixel
    along the axis ((y, x - 1) on rows, (y - 1, x) on columns) is ``threshold`` or more,
    and in the first column (row), which has no previous pixel. ``planes``: the view's
    :func:`channel_planes`, where the caller has them."""
    if planes is None:
        planes = channel_planes(image)
    out = np.empty(planes.shape[1:], dtype=np.uint8)
    colour_change_kernel(planes, float(threshold), bool(along_rows), out)
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


def downsample(image: np.ndarray) -> np.ndarray:
    """One pyramid level down: Gaussian 5 x 5, every other row and column."""
    return cv2.pyrDown(image)


def upsample_nearest(array: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Each fine pixel (y, x) takes coarse pixel (y // 2, x // 2) (the last coarse row
    and column where the fine size is odd beyond them), over the last two axes of
    ``array`` (the arms' planes come along)."""
    rows = np.minimum(np.arange(shape[0]) // 2, array.shape[-2] - 1)
    cols = np.minimum(np.arange(shape[1]) // 2, array.shape[-1] - 1)
    if rows[-1] == (shape[0] - 1) // 2 and cols[-1] == (shape[1] - 1) // 2:
        # The usual case, every index y // 2: one pass (OpenCV's nearest resize by
        # exactly 2 took 8x as long, NumPy's repeats 2.4x that).
        height, width = array.shape[-2:]
        planes = np.ascontiguousarray(array).reshape((-1, height, width))
        out = np.empty(array.shape[:-2] + tuple(shape), array.dtype)
        doubled(planes, out.reshape((-1,) + tuple(shape)))
        return out
    return array[..., rows[:, None], cols[None, :]]


def box_blur(maps: np.ndarray, box: int) -> np.ndarray:
    """The mean of each (H, W, K) map over ``box`` x ``box`` windows, the borders mirrored:
    cv2.blur's values (the same bytes), on every core."""
    out = np.empty_like(maps)
    box_mean(maps, box, *(mirrored_lines(n, box) for n in maps.shape[:2]), out)
    return out


def plane_blur(planes: np.ndarray, box: int) -> np.ndarray:
    """:func:`box_blur` of each (H, W) plane of ``planes`` (K, H, W)."""
    out = np.empty_like(planes)
    plane_box_mean(planes, box, *(mirrored_lines(n, box) for n in planes.shape[1:]), out)
    return out


def mirrored_lines(length: int, box: int) -> np.ndarray:
    """The line each of a ``box`` window's positions reads, for windows starting ``box //
    2`` before each of ``length`` lines: OpenCV's mirror about the edge lines
    (BORDER_REFLECT_101), again and again where the window is wider than the image.
    Unsigned: the box kernels' reads through them then take no wrap-around test (a signed
    index is tested for a negative value at each read; half the plane blur's time)."""
    at = np.arange(length + box - 1) - box // 2
    if length == 1:
        return np.zeros(at.shape, np.uint64)
    period = 2 * (length - 1)
    at = np.abs(at) % period
    return np.where(at < length, at, period - at).astype(np.uint64)
