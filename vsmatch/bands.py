"""Each pixel's candidate disparities: a band ``lo .. lo + count - 1`` of the range.

Every stage of the method works on bands: a volume holds ``width`` candidates a pixel,
candidate k of pixel p being disparity ``lo[p] + k`` for ``k < count[p]``. The full
search is the band ``0 .. D - 1`` at every pixel (:meth:`Bands.full`); coarse-to-fine and
video search narrow bands around an earlier estimate (:func:`around`).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class Bands:
    """Candidates ``lo .. lo + count - 1`` (int32 (H, W) each) of a range ``0 .. n_disp - 1``;
    at most ``width`` a pixel (the depth of the volumes). ``count`` 0: no candidate."""

    lo: np.ndarray
    count: np.ndarray
    width: int
    n_disp: int
    # Pixels searched no more, their disparity known (float32, inf elsewhere): a pixel
    # with no candidates and a held value keeps it (video's still pixels).
    held: np.ndarray | None = None

    @classmethod
    def full(cls, shape: tuple[int, int], n_disp: int) -> "Bands":
        """The whole range at every pixel."""
        return cls(np.zeros(shape, np.int32), np.full(shape, n_disp, np.int32), n_disp, n_disp)

    @property
    def is_full(self) -> bool:
        return self.width == self.n_disp and not self.lo.any()

    def placed(self, first: int, height: int) -> "Bands":
        """These bands of rows ``first ..`` placed in views ``height`` rows high: no
        candidates in the other rows."""
        lo = np.zeros((height, self.lo.shape[1]), np.int32)
        count = np.zeros_like(lo)
        stop = first + self.lo.shape[0]
        lo[first:stop], count[first:stop] = self.lo, self.count
        return Bands(lo, count, self.width, self.n_disp)

    def rows(self, first: int, stop: int) -> "Bands":
        """The bands of rows ``first .. stop - 1``."""
        return Bands(np.ascontiguousarray(self.lo[first:stop]),
                     np.ascontiguousarray(self.count[first:stop]), self.width, self.n_disp,
                     None if self.held is None else self.held[first:stop])


def of(volume: np.ndarray, bands: Bands | None) -> Bands:
    """``bands``, or the whole range of ``volume`` (H, W, D) when None."""
    return Bands.full(volume.shape[:2], volume.shape[2]) if bands is None else bands


def extremes(disparity: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest finite disparity over each pixel's ``size`` x ``size``
    neighbourhood (float32; inf and -inf where there is none): the span a band around an
    earlier estimate starts from."""
    finite = np.isfinite(disparity)
    kernel = np.ones((size, size), np.uint8)
    low = cv2.erode(np.where(finite, disparity, np.inf).astype(np.float32), kernel,
                    borderType=cv2.BORDER_REPLICATE)
    high = cv2.dilate(np.where(finite, disparity, -np.inf).astype(np.float32), kernel,
                      borderType=cv2.BORDER_REPLICATE)
    return low, high


def held(low: np.ndarray, high: np.ndarray, n_disp: int) -> tuple[np.ndarray, np.ndarray]:
    """The first candidate and the count of ``low .. high`` (float arrays, per pixel;
    rounded outwards) within the range ``0 .. n_disp - 1`` (float arrays)."""
    lo = np.clip(np.floor(low), 0, n_disp - 1)
    return lo, np.clip(np.ceil(high), 0, n_disp - 1) - lo + 1


def around(low: np.ndarray, high: np.ndarray, centre: np.ndarray, n_disp: int,
           width: int) -> Bands:
    """Bands holding ``low .. high`` (float arrays, per pixel; rounded outwards) within the
    range ``0 .. n_disp - 1``; where that is more than ``width`` candidates, the ``width``
    centred on ``centre``; none where ``low``, ``high`` or ``centre`` is not finite."""
    known = np.isfinite(low) & np.isfinite(high) & np.isfinite(centre)
    lo, count = held(np.where(known, low, 0), np.where(known, high, 0), n_disp)
    wide = count > width
    middle = np.round(np.where(known, centre, 0)) - width // 2
    lo = np.where(wide, np.clip(middle, 0, max(n_disp - width, 0)), lo)
    count = np.where(wide, min(width, n_disp), count)
    count[~known] = 0
    return Bands(lo.astype(np.int32), count.astype(np.int32), int(min(width, n_disp)), n_disp)
