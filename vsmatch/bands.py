"""Each pixel's candidate disparities: a band ``lo .. lo + count - 1`` of the range.

Every stage of the method works on bands: a volume holds ``width`` candidates a pixel,
candidate k of pixel p being disparity ``lo[p] + k`` for ``k < count[p]``. The full
search is the band ``0 .. D - 1`` at every pixel (:meth:`Bands.full`); coarse-to-fine and
video search narrow bands around an earlier estimate (:func:`around`).
"""

from __future__ import annotations

from dataclasses import dataclass

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
