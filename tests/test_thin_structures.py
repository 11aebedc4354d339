"""Thin structures keep their width: the bands of coarse-to-fine centred, at a depth edge,
on the coarse neighbour most like the pixel (``bands.guide``)."""

from __future__ import annotations

import numpy as np

from vsmatch import pipeline
from vsmatch._kernels.bands import centre_on_likest
from vsmatch.config import with_changes
from vsmatch.synthetic import wires_pair


def test_a_wide_cell_is_centred_on_the_neighbour_of_the_nearest_grey():
    # Coarse cells: a wall (disparity 10, grey 120) left of a wire (20, grey 220).
    coarse = np.array([[10.0, 10.0, 20.0, 20.0]] * 3, np.float32)
    coarse_grey = np.array([[120.0, 120.0, 220.0, 220.0]] * 3, np.float32)
    usable = np.ones(coarse.shape, bool)
    wide = np.zeros(coarse.shape, bool)
    wide[:, 1:3] = True  # the cells beside the edge
    fine_grey = np.repeat(np.repeat(coarse_grey, 2, 0), 2, 1)
    fine_grey[:, 3] = 210.0  # a wire pixel in the wall's cell: coarse 1 mixes both
    lo = np.full(fine_grey.shape, -1, np.int32)
    count = np.zeros(fine_grey.shape, np.int32)
    for penalty, wire_from_wall_cell in ((15.0, True), (200.0, False)):
        lo[:], count[:] = -1, 0
        centre_on_likest(coarse, usable, coarse_grey, fine_grey, wide, np.float32(penalty),
                         8, 64, lo, count)
        assert np.all(lo[:, :2] == -1)  # not wide: left as it was
        assert np.all(lo[:, 2] == 16) and np.all(count[:, 2] == 8)  # own cell: 2 x 10 - 4
        assert np.all(lo[:, 3] == (36 if wire_from_wall_cell else 16))
        assert np.all(lo[:, 4:6] == 36)  # the wire's own cell, its grey nearest too
    usable[:, 2:] = False  # no usable neighbour of the wire: its own cell's estimate only
    lo[:] = -1
    centre_on_likest(coarse, usable, coarse_grey, fine_grey, wide, np.float32(15.0), 8, 64,
                     lo, count)
    assert np.all(lo[:, 4:6] == 16)


def test_fast_keeps_a_thin_wires_width_and_trusts_no_fattened_pixel():
    pair = wires_pair(3)
    wire = pair.disparity == pair.disparity.max()
    drawn = {}
    for guide in ("15", "null"):
        cfg = with_changes("fast", [f"bands.guide={guide}"])
        result = pipeline.run(pair.left, pair.right, max_disp=pair.max_disp, config=cfg)
        as_wire = np.abs(result.disparity - pair.disparity.max()) <= 1
        fat = as_wire & ~wire
        kept = result.confidence >= cfg.cloud.min_confidence
        drawn[guide] = (as_wire.sum() / wire.sum(), (fat & kept).sum(), as_wire[wire].mean())
    # Measured: 1.15x and 79 fattened pixels kept with the guide, 1.47x and 3059 without.
    assert drawn["15"][0] < 1.2 and drawn["15"][1] < 150 and drawn["15"][2] > 0.98
    assert drawn["null"][0] > 1.35 and drawn["null"][1] > 2000
