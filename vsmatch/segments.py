"""Blank segments of the view, and the plane their edges show.

A wide blank wall is one piece of colour: reduced a few times (the sensor's noise averaged
away), neighbouring pixels differ by a grey level or two across all of it, even where its
shading runs from bright to dim. :func:`blank_segments` cuts the reduced view where
neighbours differ by ``delta`` or more and keeps the large pieces. Inside such a piece the
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


def blank_segments(view: np.ndarray, levels: int, delta: float, area: float
                   ) -> tuple[np.ndarray, list[int]]:
    """The segments of ``view`` reduced ``levels`` times (pyrDown; labels, int32, 0: an
    edge), cut where 4-neighbours differ by ``delta`` grey levels or more, and the labels of
    those covering at least ``area`` of the reduced view."""
    grey = grey_levels(view).astype(np.float32)
    for _ in range(levels):
        grey = cv2.pyrDown(grey)
    edge = np.zeros(grey.shape, bool)
    across = np.abs(np.diff(grey, axis=1)) >= delta
    down = np.abs(np.diff(grey, axis=0)) >= delta
    edge[:, 1:] |= across
    edge[:, :-1] |= across
    edge[1:, :] |= down
    edge[:-1, :] |= down
    _, labels = cv2.connectedComponents((~edge).astype(np.uint8), connectivity=4)
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    return labels, [int(k) for k in np.flatnonzero(sizes >= area * labels.size)]


def segment_mask(labels: np.ndarray, label: int, shape: tuple[int, int]) -> np.ndarray:
    """One segment's pixels at full size (``shape``), its single-cell holes (noise that cut
    a cell off the wall) closed."""
    cells = cv2.morphologyEx((labels == label).astype(np.uint8), cv2.MORPH_CLOSE,
                             np.ones((3, 3), np.uint8))
    return cv2.resize(cells, shape[::-1], interpolation=cv2.INTER_NEAREST).astype(bool)


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
    # Each column weighs the same in all.
    weight = 1.0 / np.bincount(xs)[xs]
    points = np.column_stack([xs, ys, np.ones(xs.size)]).astype(np.float64)
    draws = np.random.default_rng(0).integers(0, xs.size, (CANDIDATES, 3))
    best, best_weight = None, -1.0
    for picked in draws:
        try:
            plane = np.linalg.solve(points[picked], values[picked])
        except np.linalg.LinAlgError:
            continue
        fitting = weight[np.abs(points @ plane - values) <= inlier].sum()
        if fitting > best_weight:
            best, best_weight = plane, fitting
    if best is None:
        return None
    for _ in range(2):
        near = np.abs(points @ best - values) <= inlier
        best = np.linalg.lstsq(points[near], values[near], rcond=None)[0]
    near = np.abs(points @ best - values) <= inlier
    rows, columns = (np.flatnonzero(mask.any(axis=axis)) for axis in (1, 0))
    for inside, extent in ((ys[near], np.ptp(rows)), (xs[near], np.ptp(columns))):
        low, high = np.percentile(inside, [5, 95]) if inside.size else (0, 0)
        if high - low < SPAN * extent:
            return None
    return EdgePlane(*best, support=float(weight[near].sum() / weight.sum()))
