"""Blank segments of the view, and the plane their edges show.

A wide blank wall is one piece of colour: reduced a few times (the sensor's noise averaged
away), neighbouring pixels differ by a grey level or two across all of it, even where its
shading runs from bright to dim. :func:`blank_segments` cuts the reduced view where
neighbours differ by ``delta`` or more (or, with ``jump``, by ``jump`` or more, or where the
step between them bends by ``delta``: a shading steep near a lamp still runs evenly) and
keeps the large pieces. Inside such a piece the
match finds almost nothing sure; where it meets texture (a skirting board, an object on or
before it) its own pixels are matched, and so are the texture's. :func:`edge_plane` fits,
by RANSAC, the plane that most of the columns along that edge agree on: a column counts once
however many of its pixels are sure, so that a long skirting board outweighs an object
standing before the wall, whose pixels are many but few columns wide.
"""

from __future__ import annotations

from typing import NamedTuple

import cv2
import numpy as np

from .images import grey_levels

#: Candidate planes RANSAC draws (three sure pixels each, from a seeded generator: the same
#: planes whatever the threads), and the most sure pixels it weighs (an even subsample).
CANDIDATES, MOST_POINTS = 200, 20000
#: Least sure pixels along a segment's edge for a plane.
LEAST_POINTS = 50
#: The plane's inliers must span this share of the segment's height and of its width (5th to
#: 95th percentile): a plane seen along one edge only would tilt the wall by a guess.
SPAN = 0.5


class EdgePlane(NamedTuple):
    """A plane ``d = a x + b y + c`` and the share of the edge's columns it fits."""

    a: float
    b: float
    c: float
    support: float


def blank_segments(view: np.ndarray, levels: int, delta: float, area: float,
                   jump: float | None = None) -> tuple[np.ndarray, list[int]]:
    """The segments of ``view`` reduced ``levels`` times (pyrDown; labels, int32, 0: an
    edge) and the labels of those covering at least ``area`` of the reduced view. Cut where
    4-neighbours differ by ``delta`` grey levels or more; with ``jump``, where they differ
    by ``jump`` or more, or where the difference itself changes by ``delta`` or more from
    one pair of neighbours to the next: a wall's shading is a ramp, steep near a lamp, whose
    steps between cells change little."""
    grey = grey_levels(view).astype(np.float32)
    for _ in range(levels):
        grey = cv2.pyrDown(grey)
    edge = np.zeros(grey.shape, bool)
    for axis in (0, 1):
        step = np.diff(grey, axis=axis)
        cut = np.abs(step) >= (delta if jump is None else jump)
        _mark_both_sides(edge, cut, axis)
        if jump is not None:
            bend = np.abs(np.diff(step, axis=axis)) >= delta
            inner = [slice(None), slice(None)]
            inner[axis] = slice(1, -1)
            edge[tuple(inner)] |= bend
    _, labels = cv2.connectedComponents((~edge).astype(np.uint8), connectivity=4)
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    return labels, [int(k) for k in np.flatnonzero(sizes >= area * labels.size)]


def _mark_both_sides(edge: np.ndarray, cut: np.ndarray, axis: int) -> None:
    """In place: both cells of each pair of neighbours along ``axis`` that ``cut`` marks."""
    before, after = [slice(None), slice(None)], [slice(None), slice(None)]
    before[axis], after[axis] = slice(None, -1), slice(1, None)
    edge[tuple(after)] |= cut
    edge[tuple(before)] |= cut


def segment_mask(labels: np.ndarray, label: int, shape: tuple[int, int]) -> np.ndarray:
    """One segment's pixels at full size (``shape``), its single-cell holes (noise that cut
    a cell off the wall) closed."""
    cells = cv2.morphologyEx((labels == label).astype(np.uint8), cv2.MORPH_CLOSE,
                             np.ones((3, 3), np.uint8))
    return cv2.resize(cells, shape[::-1], interpolation=cv2.INTER_NEAREST).astype(bool)


def bounding_box(mask: np.ndarray) -> tuple[slice, slice]:
    """The rows and columns ``mask`` (not empty) spans."""
    rows, columns = (np.flatnonzero(mask.any(axis=axis)) for axis in (1, 0))
    return slice(rows[0], rows[-1] + 1), slice(columns[0], columns[-1] + 1)


def edge_plane(disparity: np.ndarray, sure: np.ndarray, mask: np.ndarray, ring: int,
               inlier: float) -> EdgePlane | None:
    """The plane most columns of the ``sure`` pixels within ``ring`` pixels of ``mask``
    agree on within ``inlier`` (RANSAC, refined by least squares on its inliers), or None
    where there are too few, or its inliers lie along one side only (:data:`SPAN`)."""
    grown = cv2.dilate(mask.astype(np.uint8), np.ones((2 * ring + 1, 2 * ring + 1), np.uint8))
    ys, xs = np.nonzero(grown.astype(bool) & sure)
    if xs.size < LEAST_POINTS:
        return None
    step = -(-xs.size // MOST_POINTS)
    ys, xs = ys[::step], xs[::step]
    values = disparity[ys, xs].astype(np.float64)
    weight = 1.0 / np.bincount(xs)[xs]  # each column weighs the same in all
    xs, ys = xs.astype(np.float64), ys.astype(np.float64)

    def off(plane: np.ndarray) -> np.ndarray:
        # Element by element, no BLAS: the same bytes whatever its threads.
        return np.abs(plane[0] * xs + plane[1] * ys + plane[2] - values)

    draws = np.random.default_rng(0).integers(0, xs.size, (CANDIDATES, 3))
    best, best_weight = None, -1.0
    for picked in draws:
        corners = np.column_stack([xs[picked], ys[picked], np.ones(3)])
        try:
            plane = np.linalg.solve(corners, values[picked])
        except np.linalg.LinAlgError:
            continue
        fitting = weight[off(plane) <= inlier].sum()
        if fitting > best_weight:
            best, best_weight = plane, fitting
    if best is None:
        return None
    try:
        for _ in range(2):
            best = _least_squares(xs, ys, values, off(best) <= inlier)
    except np.linalg.LinAlgError:
        return None  # the inliers on one line
    near = off(best) <= inlier
    rows, columns = bounding_box(mask)
    for inside, extent in ((ys[near], rows.stop - 1 - rows.start),
                           (xs[near], columns.stop - 1 - columns.start)):
        low, high = np.percentile(inside, [5, 95]) if inside.size else (0, 0)
        if high - low < SPAN * extent:
            return None
    return EdgePlane(*best, support=float(weight[near].sum() / weight.sum()))


def _least_squares(xs: np.ndarray, ys: np.ndarray, values: np.ndarray, use: np.ndarray
                   ) -> np.ndarray:
    """The least-squares plane through the ``use`` points, by its normal equations about
    their centre (NumPy's sums: the same bytes whatever the threads)."""
    x, y, d = xs[use], ys[use], values[use]
    cx, cy, cd = x.mean(), y.mean(), d.mean()
    x, y, d = x - cx, y - cy, d - cd
    a, b = np.linalg.solve(np.array([[(x * x).sum(), (x * y).sum()],
                                     [(x * y).sum(), (y * y).sum()]]),
                           np.array([(x * d).sum(), (y * d).sum()]))
    return np.array([a, b, cd - a * cx - b * cy])
