"""Planes across wide regions (vsmatch.surfaces): unsure pixels take their region's plane
where it explains the views as well, and only there."""

import dataclasses

import numpy as np
import pytest

from vsmatch import synthetic
from vsmatch.config import load_config
from vsmatch.disparity import VALID
from vsmatch.surfaces import spread_planes

#: A block of the synthetic pair's background plane (x beyond 0.85 of the width, clear of
#: the rectangles and the disc).
BLOCK = (slice(100, 140), slice(280, 312))


@pytest.fixture(scope="module")
def pair():
    return synthetic.make_pair(width=320, height=240, seed=3)


def _inputs(pair):
    disp = pair.disparity.copy()
    confidence = np.full(disp.shape, 0.9, np.float32)
    labels = np.full(disp.shape, VALID, np.uint8)
    return disp, confidence, labels


def _config(**changes):
    # The synthetic pair's grey levels spread 71 (view_contrast): its wide regions grown,
    # and its unsure pixels chosen, as a view's of full contrast (and not dark all over),
    # unless a test says otherwise.
    changes.setdefault("contrast", None)
    changes.setdefault("take_contrast", None)
    changes.setdefault("dark_level", None)
    cfg = load_config("accurate")
    return dataclasses.replace(cfg, surfaces=dataclasses.replace(cfg.surfaces, **changes))


def test_an_unsure_wrong_block_takes_its_planes_value(pair):
    disp, confidence, labels = _inputs(pair)
    disp[BLOCK] = 2.0  # far from the plane's 6 + 10 x / 320 (about 15)
    confidence[BLOCK] = 0.1
    out = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                        _config()).disparity
    truth = pair.disparity[BLOCK]
    assert np.mean(np.abs(out[BLOCK] - truth) <= 1.0) > 0.95
    sure = confidence >= 0.5
    assert np.array_equal(out[sure], disp[sure])  # the sure pixels keep their values


def test_a_view_of_little_contrast_leaves_more_pixels_as_they_are(pair):
    """take shrinks with the view's contrast below take_contrast: a block of confidence
    0.3 (below accurate's take of 0.35) takes its plane in a view of full contrast, and is
    left alone in the synthetic pair (contrast 71) when take_contrast is 120 (take 0.21)."""
    disp, confidence, labels = _inputs(pair)
    disp[BLOCK] = 2.0
    confidence[BLOCK] = 0.3
    changes = dict(bridge=0, refit=False, long_arms=False, segments=False)
    taken = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                          _config(**changes)).disparity
    assert np.mean(np.abs(taken[BLOCK] - pair.disparity[BLOCK]) <= 1.0) > 0.95
    kept = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                         _config(take_contrast=120, **changes)).disparity
    assert np.array_equal(kept[BLOCK], disp[BLOCK])


def test_a_plane_that_explains_the_views_worse_is_refused(pair):
    """The block holds the true disparities but is unsure; the sure pixels around it are
    3 px off, so their plane is too: its matching cost is higher, and it is not taken
    unless the tolerance lets it through."""
    disp, confidence, labels = _inputs(pair)
    around = (slice(60, 180), slice(250, 320))
    disp[around] += 3.0
    disp[BLOCK] = pair.disparity[BLOCK]
    confidence[BLOCK] = 0.1
    # Bridges and the refit (no cost check in accurate) would carry the sure pixels' error
    # across: off.
    kept = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                         _config(bridge=0, refit=False)).disparity
    assert np.mean(np.abs(kept[BLOCK] - pair.disparity[BLOCK]) <= 1.0) > 0.95
    lenient = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                            _config(tolerance=3.0, bridge=0, refit=False)).disparity
    assert np.mean(np.abs(lenient[BLOCK] - pair.disparity[BLOCK]) > 1.0) > 0.5  # taken


def test_without_unsure_pixels_nothing_changes(pair):
    disp, confidence, labels = _inputs(pair)
    out = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                        _config()).disparity
    assert np.array_equal(out, disp) and out is not disp


def test_an_unsure_board_between_agreeing_rows_takes_the_line_between_them(pair):
    """No region's plane reaches the board (min_share 1: no plane at all; no refit); the
    sure rows above and below it bridge it, and only where they are close enough and agree."""
    disp, confidence, labels = _inputs(pair)
    board = (slice(100, 130), BLOCK[1])  # on the background plane, 31 rows between sure rows
    disp[board] = 2.0
    confidence[board] = 0.1
    bridged = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                            _config(min_share=1.0, refit=False, bridge=64)).disparity
    truth = pair.disparity[board]
    assert np.mean(np.abs(bridged[board] - truth) <= 1.0) > 0.95
    sure = confidence >= 0.5
    assert np.array_equal(bridged[sure], disp[sure])
    raised = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                           _config(min_share=1.0, refit=False, bridge=64,
                                   bridge_confidence=0.6)).confidence
    crossed = bridged != disp
    assert np.all(raised[crossed] == np.float32(0.6))  # bridged: the bridges' confidence
    assert np.array_equal(raised[~crossed], confidence[~crossed])  # elsewhere as it was
    apart = disp.copy()
    apart[130:, BLOCK[1]] += 3.0  # below the board 3 px farther than above it,
    apart[100:130, BLOCK[1].stop:] += 3.0  # and to its right than to its left
    for ends, changes in ((disp, {"bridge": 0}), (disp, {"bridge": 20}),
                          (apart, {"bridge": 64})):
        out = spread_planes(ends, confidence, labels, pair.left, pair.right, pair.max_disp,
                            _config(min_share=1.0, refit=False, **changes)).disparity
        # Off, a gap (31 rows) longer than the bridge, ends that disagree: nothing crosses.
        assert np.mean(out[board] == 2.0) > 0.95, changes


def test_a_thin_object_in_front_is_not_bridged_over(pair):
    """An unsure strip matched 15 px in front of the surface above and below it (an
    armrest before a chair's back) keeps its match; a bridge may put a pixel at most
    ``bridge_behind`` behind its own."""
    disp, confidence, labels = _inputs(pair)
    strip = (slice(100, 110), BLOCK[1])
    disp[strip] += 15.0
    confidence[strip] = 0.1
    kept = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                         _config(min_share=1.0, refit=False, bridge=64)).disparity
    assert np.array_equal(kept[strip], disp[strip])
    crossed = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                            _config(min_share=1.0, refit=False, bridge=64,
                                    bridge_behind=100.0)).disparity
    assert np.mean(np.abs(crossed[strip] - pair.disparity[strip]) <= 1.0) > 0.95


def test_the_refit_averages_a_boards_skewed_bridges_into_its_plane(pair):
    """The sure rows just above the board are 1.8 px off (another surface's edge), so the
    bridges lean towards them; the planes refitted through the sure and bridged pixels
    together put the board back on the background's plane. A pixel no bridge reaches (its
    ends disagree) takes the refitted plane too, and only with the refit on."""
    disp, confidence, labels = _inputs(pair)
    board = (slice(100, 130), BLOCK[1])
    disp[board] = 2.0
    confidence[board] = 0.1
    disp[96:100, BLOCK[1]] += 1.8
    lone = (slice(20, 24), slice(300, 304))  # in the background; no bridge: the nearest
    disp[lone] = 2.0  # sure pixels above it and to its left are 5 px off
    confidence[lone] = 0.1
    disp[:20, 300:304] += 5.0
    disp[20:24, 290:300] += 5.0
    truth = pair.disparity
    results = {}
    for refit in (False, True):
        results[refit] = spread_planes(disp, confidence, labels, pair.left, pair.right,
                                       pair.max_disp, _config(min_share=1.0, bridge=64,
                                                              refit=refit)).disparity
    bridged, refitted = results[False][board], results[True][board]
    assert np.mean(np.abs(bridged - truth[board]) <= 1.0) < 0.8  # the bridges lean
    assert np.mean(np.abs(refitted - truth[board]) <= 1.0) > 0.95
    assert np.all(results[False][lone] == 2.0)
    assert np.all(np.abs(results[True][lone] - truth[lone]) <= 1.0)
    sure = confidence >= 0.3
    assert np.array_equal(results[True][sure], disp[sure])  # the sure pixels keep theirs


def test_bridges_follow_columns_first_then_rows():
    from vsmatch.surfaces import _bridges

    sure = np.full((9, 9), np.nan, np.float32)
    sure[0, :], sure[8, :] = 10.0, 12.0  # columns: 10 above, 12 below
    sure[:, 0], sure[:, 8] = 20.0, 20.0  # rows: 20 at both ends (the columns win)
    unsure = np.zeros((9, 9), bool)
    unsure[1:8, 1:8] = True
    out = _bridges(sure, unsure, span=8, agree=2.0)
    assert np.allclose(out[4, 1:8], 11.0) and np.allclose(out[1, 4], 10.25)
    assert np.isnan(out[0, 0]) and np.isnan(out[8, 4])  # sure or not unsure: no bridge
    rows_only = _bridges(np.where(np.arange(9)[:, None] % 8 == 0, np.nan, sure), unsure,
                         span=8, agree=2.0)
    assert np.allclose(rows_only[1:8, 1:8], 20.0)
    assert np.isnan(_bridges(sure, unsure, span=7, agree=2.0)[4, 4])  # too far apart


def test_a_dark_views_wide_regions_grow_with_a_smaller_colour_threshold():
    from vsmatch.surfaces import _wide_arms, view_contrast

    ramp = np.tile(np.arange(256, dtype=np.uint8), (8, 1))
    assert view_contrast(ramp) == pytest.approx(204, abs=1)  # 90th less 10th percentile
    assert view_contrast((ramp * 0.3).astype(np.uint8)) == pytest.approx(61, abs=1)
    cfg = _config(contrast=150.0).surfaces
    arms = load_config("accurate").arms
    assert _wide_arms(arms, cfg, 204.0).tau1 == cfg.tau  # enough contrast: tau as it is
    assert _wide_arms(arms, cfg, 75.0).tau1 == pytest.approx(cfg.tau / 2)
    off = dataclasses.replace(cfg, contrast=None)
    assert _wide_arms(arms, off, 75.0).tau1 == cfg.tau


def test_long_arms_carry_a_walls_plane_across_its_shading():
    """A wall whose grey level falls slowly to the left (a lamp's light on it), sure only
    on its right part (x >= 200). The wide regions' stricter threshold beyond arms.l1 stops
    their arms on the shading: no plane reaches left of x = 115, and no bridge (nothing sure
    on the left); with long_arms the regions reach the sure part and the wall's plane."""
    height, width = 96, 320
    x = np.arange(width, dtype=np.float32)
    truth = np.tile(6.0 + 10.0 * x / width, (height, 1)).astype(np.float32)
    left = np.tile(40.0 + 0.2 * x, (height, 1))
    right = np.tile(40.0 + 0.2 * np.minimum(x + truth[0], width - 1), (height, 1))
    left, right = (np.rint(v).astype(np.uint8) for v in (left, right))
    disp = truth.copy()
    confidence = np.full(disp.shape, 0.9, np.float32)
    disp[:, :200], confidence[:, :200] = 2.0, 0.1
    labels = np.full(disp.shape, VALID, np.uint8)
    results = {long: spread_planes(disp, confidence, labels, left, right, 31,
                                   _config(long_arms=long)).disparity
               for long in (False, True)}
    wall = (slice(None), slice(20, 100))
    assert np.mean(np.abs(results[False][wall] - truth[wall]) <= 1.0) < 0.05
    assert np.mean(np.abs(results[True][wall] - truth[wall]) <= 1.0) > 0.95
    sure = confidence >= 0.3
    assert np.array_equal(results[True][sure], disp[sure])


def test_the_refit_raises_the_confidence_only_where_the_pixels_own_match_agrees(pair):
    """Two unsure blocks of the background; the one whose match was wrong takes the plane
    (first pass) and the refit then agrees with that plane, not with its match: its
    confidence stays; the one whose match was right is raised to refit_confidence."""
    disp, confidence, labels = _inputs(pair)
    wrong, right = BLOCK, (slice(160, 200), BLOCK[1])
    disp[wrong] = 2.0
    confidence[wrong] = confidence[right] = 0.1
    cfg = _config()
    out = spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp, cfg)
    truth = pair.disparity
    assert np.mean(np.abs(out.disparity[wrong] - truth[wrong]) <= 1.0) > 0.95  # taken
    assert np.all(out.confidence[wrong] == np.float32(0.1))
    assert np.mean(out.confidence[right] == np.float32(cfg.surfaces.refit_confidence)) > 0.95


def test_a_sure_match_where_the_view_is_flat_counts_as_unsure(pair):
    """A block of the left view without any texture, its inside matched surely but wrong
    (its rim, next to the texture around it, is matched right): with surfaces.flat the
    inside counts as unsure and takes the background's plane; without, a sure pixel keeps
    its value."""
    disp, confidence, labels = _inputs(pair)
    left = pair.left.copy()
    left[BLOCK] = 128
    inside = (slice(BLOCK[0].start + 3, BLOCK[0].stop - 3),  # the 3 x 3 Sobel's 5 x 5
              slice(BLOCK[1].start + 3, BLOCK[1].stop - 3))  # mean reaches 3 px in
    disp[inside] = 2.0
    results = {flat: spread_planes(disp, confidence, labels, left, pair.right, pair.max_disp,
                                   _config(flat=flat)).disparity[inside]
               for flat in (None, 1.0)}
    assert np.all(results[None] == 2.0)
    assert np.mean(np.abs(results[1.0] - pair.disparity[inside]) <= 1.0) > 0.95


def test_a_board_running_out_of_the_views_bottom_takes_the_level_disparity_above_it():
    from vsmatch.surfaces import EDGE_LEVEL_ROWS, _bottom_edge_extension

    height, width = 60, 4
    sure = np.full((height, width), np.nan, np.float32)
    sure[:40, 0] = 20.0  # a vertical face above the board: level
    sure[:40, 1] = 20.0 + 0.2 * np.arange(40)  # a floor: rises 0.2 px a row
    sure[:40, 2] = 20.0
    sure[55, 2] = 25.0  # something sure below the gap: a bridge's business, not this
    sure[:40, 3] = 20.0
    unsure = np.zeros((height, width), bool)
    unsure[40:, :] = True
    out = _bottom_edge_extension(sure, unsure, reach=24)
    assert np.all(out[40:, 0] == 20.0) and np.all(np.isnan(out[:40, 0]))
    assert np.all(np.isnan(out[:, 1]))  # not level
    assert np.all(np.isnan(out[40:55, 2]))  # a sure pixel below
    assert np.all(np.isnan(_bottom_edge_extension(sure, unsure, reach=19)[:, 3]))  # too far
    sure[39 - EDGE_LEVEL_ROWS, 3] = np.nan  # no sure pixel to tell the column is level
    assert np.all(np.isnan(_bottom_edge_extension(sure, unsure, reach=24)[:, 3]))


def _bridges_by_numpy(sure, unsure, span, agree):
    """The bridges along columns as whole-array NumPy steps (the kernel's reference)."""
    height, width = sure.shape
    rows = np.arange(height)[:, None]
    known = np.isfinite(sure)
    above = np.maximum.accumulate(np.where(known, rows, -1), axis=0)
    below = np.minimum.accumulate(np.where(known, rows, height)[::-1], axis=0)[::-1]
    ends = unsure & (above >= 0) & (below < height) & (below - above <= span)
    columns = np.arange(width)[None, :]
    top = sure[np.clip(above, 0, height - 1), columns]
    bottom = sure[np.clip(below, 0, height - 1), columns]
    with np.errstate(invalid="ignore"):
        ends &= np.abs(top - bottom) <= np.float32(agree)
        share = (rows - above) / np.maximum(below - above, 1)
        return np.where(ends, top + share * (bottom - top), np.nan).astype(np.float32)


def test_bridges_kernel_equals_the_numpy_steps_along_columns_and_rows():
    from vsmatch.surfaces import _line_bridges

    rng = np.random.default_rng(3)
    drawn = 0
    for _ in range(12):
        height, width = rng.integers(1, 120, 2)
        sure = (rng.random((height, width)) * 60).astype(np.float32)
        sure[rng.random((height, width)) < rng.random()] = np.nan
        unsure = rng.random((height, width)) < 0.5
        for span, agree in ((16, 1.0), (48, 0.3), (3, 2.5)):
            expected = _bridges_by_numpy(sure, unsure, span, agree)
            assert np.array_equal(_line_bridges(sure, unsure, span, agree, False), expected,
                                  equal_nan=True)
            across = _bridges_by_numpy(sure.T, unsure.T, span, agree).T
            assert np.array_equal(_line_bridges(sure, unsure, span, agree, True),
                                  across, equal_nan=True)
            drawn += np.isfinite(expected).sum()
    assert drawn > 1000  # the cases hold bridges, not only NaN


def _dark_corner(height, width):
    """A bright noisy view (mean 150) whose lower half's left quarter is at 0.12 of it."""
    view = np.clip(np.random.default_rng(0).normal(150, 20, (height, width)), 0, 255)
    view[height // 2:, :width // 4] *= 0.12
    return view


def test_a_shadow_is_dark_against_the_views_own_median():
    """in_shadow: a quarter of a bright view at 0.12 of its light is a shadow (but for a
    box's reach into it from its edge), the rest is not; the same view dark all over keeps
    its shadow (0.12 of a darker median) and gains none; a view dark all over, no shadow."""
    from vsmatch.surfaces import in_shadow

    view = _dark_corner(240, 320)
    bright = in_shadow(view.astype(np.uint8), 3, 0.35, 16)
    assert bright[140:, :60].all()
    assert not bright[:100].any() and not bright[:, 100:].any()
    dim = in_shadow((view * 0.2).astype(np.uint8), 3, 0.35, 16)
    assert np.array_equal(dim[140:, :60], bright[140:, :60])
    assert not dim[:100].any() and not dim[:, 100:].any()
    uniform = in_shadow(np.full((240, 320), 12, np.uint8), 3, 0.35, 16)
    assert not uniform.any()


def test_a_shadow_reaches_its_own_edge():
    """Where the box is several cells wide, its mean reaches that far into a shadow from the
    light around it: a cell dark with its neighbours within that reach is in the shadow too,
    so the shadow's edge lies within a cell (8 px) of the dark region's, and no further out."""
    from vsmatch.surfaces import in_shadow

    shadow = in_shadow(_dark_corner(480, 640).astype(np.uint8), 3, 0.35, 16)
    assert shadow[244:, :156].all()
    assert not shadow[:232].any() and not shadow[:, 168:].any()


def test_an_unsure_block_in_a_shadow_keeps_its_own_match(pair):
    """The unsure wrong block of the first test, its surroundings in the left view in deep
    shadow: with surfaces.shadow it keeps its match (the shadow's pixels are not unsure),
    without it takes the plane as in a bright view; a flat pixel in the shadow still counts
    as unsure."""
    disp, confidence, labels = _inputs(pair)
    disp[BLOCK] = 2.0
    confidence[BLOCK] = 0.1
    left = pair.left.astype(np.float32)
    left[60:180, 240:] *= 0.12
    left = np.rint(left).astype(np.uint8)
    changes = dict(tolerance=3.0)  # the shadowed view's costs are not the test's business
    kept = spread_planes(disp, confidence, labels, left, pair.right, pair.max_disp,
                         _config(shadow=0.35, **changes)).disparity
    assert np.array_equal(kept[BLOCK], disp[BLOCK])
    taken = spread_planes(disp, confidence, labels, left, pair.right, pair.max_disp,
                          _config(shadow=None, **changes)).disparity
    assert np.mean(np.abs(taken[BLOCK] - pair.disparity[BLOCK]) <= 1.0) > 0.95
    flat = left.copy()
    flat[BLOCK] = 9  # one grey level over the whole block: nothing to see
    filled = spread_planes(disp, confidence, labels, flat, pair.right, pair.max_disp,
                           _config(shadow=0.35, **changes)).disparity
    inner = (slice(BLOCK[0].start + 4, BLOCK[0].stop - 4),
             slice(BLOCK[1].start + 4, BLOCK[1].stop - 4))
    assert np.mean(np.abs(filled[inner] - pair.disparity[inner]) <= 1.0) > 0.95


def test_the_shadows_median_level_is_numpys_median(rng):
    """The view's median grey level read from its histogram is ``np.median``'s, the mean of
    the two middle levels of an even count included."""
    from vsmatch.surfaces import _median_level

    for size in (1, 2, 7, 10, 4001):
        for step in (1, 64):
            grey = (rng.integers(0, 256, (1, size)) // step * step).astype(np.uint8)
            assert _median_level(grey) == float(np.median(grey))
    assert _median_level(np.array([[10, 13]], np.uint8)) == 11.5


def test_a_dark_scene_keeps_the_pixels_its_cost_curves_matched(pair):
    """The gate puts a dark scene's matched texture near confidence 0; where more than
    dark_share of the view lies in the dark (light below dark_level: every box of the
    synthetic pair's is below 256, none below 1), a pixel in the dark whose neighbourhood's
    mean cost-curve margin is at least dark_margin keeps its match. No dark (the level 1),
    too small a dark share (1.0), a flat margin or no margins at all: the block takes its
    plane as any unsure block."""
    disp, confidence, labels = _inputs(pair)
    disp[BLOCK] = 2.0
    confidence[BLOCK] = 0.0
    margin = np.zeros(disp.shape, np.float32)
    margin[BLOCK] = 1.0  # the mean over the gate's 15 x 15 window: >= 0.5 inside the block
    changes = dict(dark_margin=0.06, bridge=0, refit=False, long_arms=False, segments=False)

    def spread(level, share, margins):
        return spread_planes(disp, confidence, labels, pair.left, pair.right, pair.max_disp,
                             _config(dark_level=level, dark_share=share, **changes),
                             margin=margins).disparity

    assert np.array_equal(spread(255.0, 0.5, margin)[BLOCK], disp[BLOCK])
    for level, share, margins in ((None, 0.5, margin), (1.0, 0.5, margin),
                                  (255.0, 1.0, margin), (255.0, 0.5, margin * 0.0),
                                  (255.0, 0.5, None)):
        taken = spread(level, share, margins)
        assert np.mean(np.abs(taken[BLOCK] - pair.disparity[BLOCK]) <= 1.0) > 0.95
