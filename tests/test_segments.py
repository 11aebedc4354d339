"""Blank segments and the plane their edges show (vsmatch.segments), and accurate's last
step that gives it to a blank wall (vsmatch.surfaces)."""

import numpy as np

from vsmatch import segments


def _wall_view(height=240, width=320):
    """A wall shaded from grey 200 to 140 across its width (under 3 grey levels a cell of
    the view reduced 8 times), a textured skirting board along its bottom, and a textured
    object standing before it in a few columns."""
    rng = np.random.default_rng(1)
    xs = np.arange(width, dtype=np.float32)
    view = np.tile(200 - 60 * xs / width, (height, 1))
    view[200:] = rng.integers(0, 255, (height - 200, width))  # the skirting board
    view[60:200, 140:170] = rng.integers(0, 255, (140, 30))  # the object
    return np.clip(view, 0, 255).astype(np.uint8)


def test_a_shaded_wall_is_one_blank_segment():
    view = _wall_view()
    labels, large = segments.blank_segments(view, 3, 3.0, 0.02)
    # The wall either side of the object is one segment (joined above it).
    wall = {int(labels[3, 2]), int(labels[3, 35])}
    assert len(wall) == 1 and wall.pop() in large
    # A cut where the shading steps by more than delta.
    steep = view.copy()
    steep[:, 160:] = np.clip(steep[:, 160:].astype(int) - 40, 0, 255).astype(np.uint8)
    labels, _ = segments.blank_segments(steep, 3, 3.0, 0.02)
    assert labels[3, 2] != labels[3, 35]


def test_a_steep_even_shading_is_one_segment_with_a_jump():
    """A wall shaded from 230 to 50 across its width (4.5 grey levels a cell of the view
    reduced 8 times, more than delta): cut everywhere by its steps alone, one segment where
    only a step of 8 or a bend of 3 cuts; a step of 40 still cuts."""
    view = _wall_view()
    xs = np.arange(view.shape[1], dtype=np.float32)
    view[:200, :140] = np.clip(230 - 180 * xs[:140] / view.shape[1], 0, 255)
    view[:200, 170:] = np.clip(230 - 180 * xs[170:] / view.shape[1], 0, 255)
    view[:60, 140:170] = np.clip(230 - 180 * xs[140:170] / view.shape[1], 0, 255)
    assert not _one_wall(*segments.blank_segments(view, 3, 3.0, 0.02))
    assert _one_wall(*segments.blank_segments(view, 3, 3.0, 0.02, jump=8.0))
    steep = view.copy()
    steep[:, 160:] = np.clip(steep[:, 160:].astype(int) - 40, 0, 255).astype(np.uint8)
    assert not _one_wall(*segments.blank_segments(steep, 3, 3.0, 0.02, jump=8.0))


def _one_wall(labels, large):
    """The wall either side of the object (cells (3, 2) and (3, 35)) one large segment."""
    return labels[3, 2] == labels[3, 35] and int(labels[3, 2]) in large


def test_the_edge_plane_is_the_one_most_columns_show():
    height, width = 240, 320
    mask = np.zeros((height, width), bool)
    mask[10:190, 10:310] = True
    sure = np.zeros_like(mask)
    disparity = np.zeros((height, width), np.float32)
    ys, xs = np.mgrid[0:height, 0:width]
    wall = 40 + 0.01 * xs - 0.02 * ys
    # The ceiling and the skirting board along the wall's top and bottom: every column.
    for rows in (slice(0, 2), slice(192, 196)):
        sure[rows, :] = True
        disparity[rows] = wall[rows]
    # An object before the wall: many sure pixels, few columns, 15 px nearer.
    sure[60:190, 140:170] = True
    disparity[60:190, 140:170] = 60
    plane = segments.edge_plane(disparity, sure, mask, 16, 1.0)
    assert plane is not None and plane.support > 0.85
    np.testing.assert_allclose([plane.a, plane.b, plane.c], [0.01, -0.02, 40], atol=1e-3)
    # Counted by pixels, the object would win: the weighting is what picks the wall.
    assert (sure & (disparity == 60)).sum() > (sure & (disparity != 60)).sum()
    assert segments.edge_plane(disparity, np.zeros_like(sure), mask, 16, 1.0) is None


def _spread(view, disp, confidence, **changes):
    import dataclasses

    from vsmatch.config import load_config
    from vsmatch.disparity import VALID
    from vsmatch.surfaces import spread_planes

    cfg = load_config("accurate")
    cfg = dataclasses.replace(cfg, surfaces=dataclasses.replace(cfg.surfaces, **changes))
    labels = np.full(disp.shape, VALID, np.uint8)
    return spread_planes(disp, confidence, labels, view, view, 64, cfg)


def test_a_blank_wall_with_nothing_sure_inside_takes_its_edges_plane():
    view = _wall_view()
    height, width = view.shape
    ys, xs = np.mgrid[0:height, 0:width]
    truth = (40 + 0.01 * xs - 0.02 * ys).astype(np.float32)
    rng = np.random.default_rng(2)
    disp = truth + rng.uniform(-12, 12, truth.shape).astype(np.float32)  # blotches
    confidence = np.full(truth.shape, 0.05, np.float32)
    sure = np.zeros(truth.shape, bool)
    sure[200:] = True  # the skirting board, matched and sure
    sure[:3] = True  # and the ceiling's edge
    disp[sure] = truth[sure]
    confidence[sure] = 0.95
    confidence[20:180:8, 20:130:8] = 0.97  # a few blotches sure (under 5 % of the wall)
    wall = (slice(20, 170), slice(20, 110))  # clear of the edges' cells
    out = _spread(view, disp, confidence, long_arms=False, refit=False, bridge=0)
    # Within segment_move (2 px) of the plane every pixel keeps its own disparity.
    assert np.mean(np.abs(out.disparity[wall] - truth[wall]) <= 2.0) > 0.95
    # A moved pixel stays out of the cloud.
    moved = out.disparity[wall] != disp[wall]
    assert moved.any() and out.confidence[wall][moved].max() <= 0.75
    # Without the step, or where the match was sure of much of the wall, the blotches stay.
    off = _spread(view, disp, confidence, long_arms=False, refit=False, bridge=0,
                  segments=False)
    assert np.mean(np.abs(off.disparity[wall] - truth[wall]) <= 2.0) < 0.3
    seen = confidence.copy()
    seen[20:180:4, 20:300:4] = 0.95  # 6 % of the wall sure
    kept = _spread(view, disp, seen, long_arms=False, refit=False, bridge=0)
    assert np.mean(np.abs(kept.disparity[wall] - truth[wall]) <= 2.0) < 0.3
    # Seen along one edge only, the wall's tilt would be a guess: left as it is.
    one_edge = confidence.copy()
    one_edge[:3] = 0.05
    alone = _spread(view, disp, one_edge, long_arms=False, refit=False, bridge=0)
    assert np.mean(np.abs(alone.disparity[wall] - truth[wall]) <= 2.0) < 0.3


def test_an_edge_plane_that_leaves_the_range_inside_the_wall_is_refused():
    """The edge's sure pixels can lie on surfaces before the wall (delivery_area_1s: the
    crates along the wall's foot). A plane through them that falls below disparity 0 (behind
    infinity) inside the segment is no surface seen there: the wall keeps its own match."""
    view = _wall_view()
    height, width = view.shape
    ys, xs = np.mgrid[0:height, 0:width]
    for slope, refused in ((0.1, True), (0.02, False)):
        tilted = (1 + slope * (ys - 60) + 0.001 * xs).astype(np.float32)  # 1 at row 60
        disp = np.full(tilted.shape, 30.0, np.float32)  # the wall's own match
        confidence = np.full(tilted.shape, 0.05, np.float32)
        sure = np.zeros(tilted.shape, bool)
        sure[200:] = True  # the skirting board ...
        sure[60:200, 140:170] = True  # ... and the object: no sure pixel above row 60
        disp[sure] = tilted[sure]
        confidence[sure] = 0.95
        out = _spread(view, disp, confidence, long_arms=False, refit=False, bridge=0)
        top = (slice(0, 20), slice(20, 110))
        # At slope 0.1 the plane reads -5 at the top row; at 0.02, -0.2: within inlier.
        assert np.all(out.disparity[top] == 30.0) == refused
