"""Coarse-to-fine search and stripes: the parts that keep large images in bounds."""

import contextlib
import os

import numba
import numpy as np
import pytest
from click.testing import CliRunner

from vsmatch import (aggregation, datasets, disparity, images, level, metrics, optimization,
                     pipeline, pyramid, scale, tiles, volumes)
from vsmatch.bands import Bands
from vsmatch.bench import upscaled_scene
from vsmatch.cli import main
from vsmatch.config import config_from_dict, load_config

from conftest import random_pair
from figures import hold


def test_levels_halve_until_a_row_fits():
    assert pyramid.coarse_levels(718, 73, 262144) == 0  # Middlebury 2014 quarter
    assert pyramid.coarse_levels(1242, 192, 262144) == 0  # KITTI
    assert pyramid.coarse_levels(2872, 292, 262144) == 1  # the 4x pair
    assert pyramid.coarse_levels(5744, 584, 262144) == 2
    assert pyramid.coarse_levels(100, 5000, 1024) == 1  # stops at 64 columns


def test_levels_also_halve_a_pair_of_too_many_cells():
    cells = load_config(None).pyramid.max_cells
    assert cells == 120_000_000
    assert pyramid.coarse_levels(1242, 192, 262144, 0, 375, cells) == 0  # KITTI: 89 million
    assert pyramid.coarse_levels(1472, 150, 262144, 0, 1017, cells) == 1  # 1.5 megapixels
    assert pyramid.coarse_levels(1224, 128, 262144, 0, 816, cells) == 1  # 1 MP, 128 disparities
    assert pyramid.coarse_levels(1472, 150, 262144, 0, 1017, 0) == 0  # no limit


def _narrow(bands_full):
    """The whole range, given as bands one wider than the range: the band code paths."""
    return Bands(bands_full.lo, bands_full.count, bands_full.width + 1, bands_full.n_disp)


def test_band_stages_over_whole_ranges_are_the_full_search(rng):
    """Bands holding every disparity, through the band code paths: every stage gives the
    full volume's result."""
    height, width, n_disp = 9, 13, 7
    volume = rng.random((height, width, n_disp), dtype=np.float32) * 2
    wide = np.concatenate([volume, np.full((height, width, 1), 9, np.float32)], axis=2)
    left = rng.integers(0, 40, size=(height, width, 3), dtype=np.uint8)
    right = rng.integers(0, 40, size=(height, width, 3), dtype=np.uint8)
    cfg = config_from_dict({"scanline": {"p1": 0.5, "p2": 1.7, "tau": 20}},
                           base=load_config(None)).scanline
    bands = _narrow(Bands.full((height, width), n_disp))
    want = optimization.scanline_optimise(volume, left, right, cfg)
    got = optimization.scanline_optimise(wide, left, right, cfg, bands=bands)
    np.testing.assert_allclose(got[:, :, :n_disp], want, rtol=1e-6, atol=1e-6)
    arms = rng.integers(0, 4, size=(4, height, width)).astype(np.uint8)
    arms = aggregation.keep_arms_inside(arms)
    arms_r = aggregation.keep_arms_inside(rng.integers(0, 4, size=(4, height, width)
                                                       ).astype(np.uint8))
    want = aggregation.aggregate_cross(volume.copy(), arms, arms_r, iterations=2)
    got = aggregation.aggregate_cross(wide.copy(), arms, arms_r, iterations=2, bands=bands)
    np.testing.assert_allclose(got[:, :, :n_disp], want, rtol=1e-5)
    for a, b in zip(disparity.winner_takes_all_both(volume),
                    disparity.winner_takes_all_both(wide, bands)):
        np.testing.assert_array_equal(a, b)


def _regions_by_hand(volume, arms_l, arms_r, lo, count):
    """One aggregation iteration over banded regions, slow and plain: rows, then columns;
    at d an arm is the shorter of the left pixel's and of right pixel x - d's, and a
    pixel belongs to the region at d when its band holds d."""
    height, width, n_disp = volume.shape
    holds = lambda y, x, d: lo[y, x] <= d < lo[y, x] + count[y, x]  # noqa: E731

    def reach(y, x, d, arm):
        return min(int(arms_l[arm, y, x]), int(arms_r[arm, y, x - d]) if x >= d else 255)

    rows = {}
    for y in range(height):
        for x in range(width):
            for d in range(lo[y, x], lo[y, x] + count[y, x]):
                members = [x + k for k in range(-reach(y, x, d, 0), reach(y, x, d, 1) + 1)
                           if holds(y, x + k, d)]
                rows[y, x, d] = (sum(volume[y, q, d] for q in members), len(members))
    out = np.full(volume.shape, np.nan)
    for y in range(height):
        for x in range(width):
            for d in range(lo[y, x], lo[y, x] + count[y, x]):
                parts = [rows[y + k, x, d] for k in range(-reach(y, x, d, 2),
                                                          reach(y, x, d, 3) + 1)
                         if holds(y + k, x, d)]
                out[y, x, d] = sum(p[0] for p in parts) / sum(p[1] for p in parts)
    return out


@pytest.mark.parametrize("depth", [aggregation.LANES, aggregation.LANES + 1])
def test_aggregation_over_bands_sums_the_regions_pixels_that_hold_d(rng, depth):
    """Bands of up to ``depth`` candidates in a volume that deep, where most neighbours'
    bands start together (the common case) and some do not: one vector deep (the
    coarse-to-fine search's volumes, their own kernel) and deeper (the general one)."""
    height, width, n_disp = 10, 14, 16
    full = rng.random((height, width, n_disp)).astype(np.float32)
    lo = np.where(rng.random((height, width)) < 0.7, 3,
                  rng.integers(0, 8, size=(height, width))).astype(np.int32)
    count = np.minimum(rng.integers(1, depth + 1, size=(height, width)),
                       n_disp - lo).astype(np.int32)
    count[0, :3] = 0  # pixels without candidates
    bands = Bands(lo, count, depth, n_disp)
    banded = np.full((height, width, depth), np.nan, np.float32)  # past a band: unused
    for y in range(height):
        for x in range(width):
            banded[y, x, :count[y, x]] = full[y, x, lo[y, x]:lo[y, x] + count[y, x]]
    arms_l, arms_r = (aggregation.keep_arms_inside(
        rng.integers(0, 4, size=(4, height, width)).astype(np.uint8)) for _ in range(2))
    got = aggregation.aggregate_cross(banded, arms_l, arms_r, iterations=1, bands=bands)
    want = _regions_by_hand(full.astype(np.float64), arms_l, arms_r, lo, count)
    for y in range(height):
        for x in range(width):
            np.testing.assert_allclose(got[y, x, :count[y, x]],
                                       want[y, x, lo[y, x]:lo[y, x] + count[y, x]], rtol=1e-5)


@pytest.mark.parametrize("depth", [optimization.LANES, optimization.LANES + 1])
def test_scanline_over_bands_is_the_scanline_with_the_rest_infinite(rng, depth):
    """A band's path is the whole range's with every cost outside the bands infinite:
    narrow bands (a vector at a time), wider ones, starts that move from pixel to pixel; in
    a volume one vector deep (coarse-to-fine's, its own kernels) and deeper (the general
    ones)."""
    height, width, n_disp = 11, 17, 16
    full = rng.random((height, width, n_disp)).astype(np.float32) * 3
    lo = np.where(rng.random((height, width)) < 0.6, 4,
                  rng.integers(0, 8, size=(height, width))).astype(np.int32)
    count = np.minimum(rng.integers(1, depth + 1, size=(height, width)),
                       n_disp - lo).astype(np.int32)
    inside = np.zeros(full.shape, bool)
    banded = np.full((height, width, depth), np.nan, np.float32)  # past a band: unused
    for y in range(height):
        for x in range(width):
            inside[y, x, lo[y, x]:lo[y, x] + count[y, x]] = True
            banded[y, x, :count[y, x]] = full[y, x, lo[y, x]:lo[y, x] + count[y, x]]
    left = rng.integers(0, 60, size=(height, width, 3), dtype=np.uint8)
    right = rng.integers(0, 60, size=(height, width, 3), dtype=np.uint8)
    for directions in (4, 8):
        cfg = config_from_dict({"scanline": {"p1": 0.5, "p2": 1.7, "tau": 20,
                                             "directions": directions}},
                               base=load_config(None)).scanline
        want = optimization.scanline_optimise(np.where(inside, full, np.inf).astype(np.float32),
                                              left, right, cfg)
        got = optimization.scanline_optimise(banded, left, right, cfg,
                                             bands=Bands(lo, count, depth, n_disp))
        for y in range(height):
            for x in range(width):
                np.testing.assert_allclose(got[y, x, :count[y, x]],
                                           want[y, x, lo[y, x]:lo[y, x] + count[y, x]],
                                           rtol=1e-5)


def test_winners_over_bands_by_hand(rng):
    height, width, n_disp = 6, 20, 8
    full = np.round(rng.random((height, width, n_disp)) * 5).astype(np.float32)
    lo = rng.integers(0, 5, size=(height, width)).astype(np.int32)
    count = np.minimum(rng.integers(0, 4, size=(height, width)), n_disp - lo).astype(np.int32)
    banded = np.zeros((height, width, 3), np.float32)
    for y in range(height):
        for x in range(width):
            banded[y, x, :count[y, x]] = full[y, x, lo[y, x]:lo[y, x] + count[y, x]]
    got_l, got_r = disparity.winner_takes_all_both(banded, Bands(lo, count, 3, n_disp))
    for y in range(height):
        for x in range(width):
            ds = range(lo[y, x], lo[y, x] + count[y, x])
            want = min(ds, key=lambda d: (full[y, x, d], d)) if count[y, x] else None
            assert got_l[y, x] == (want if want is not None else disparity.NO_DISPARITY)
            offers = [(full[y, x + d, d], d) for d in range(n_disp) if x + d < width
                      and lo[y, x + d] <= d < lo[y, x + d] + count[y, x + d]]
            assert got_r[y, x] == (min(offers)[1] if offers else disparity.NO_DISPARITY)


@pytest.mark.parametrize("height, rows, overlap", [(100, 1000, 8), (100, 40, 8), (997, 200, 48),
                                                   (1984, 575, 48)])
def test_stripe_cores_tile_the_image(height, rows, overlap):
    layout = tiles.stripe_layout(height, rows, overlap)
    covered = np.zeros(height, int)
    for first, stop, core_first, core_stop in layout:
        assert stop - first <= rows
        assert first == max(0, core_first - overlap) and stop == min(height, core_stop + overlap)
        covered[core_first:core_stop] += 1
    assert np.all(covered == 1)


def test_too_small_a_budget_is_refused_in_one_line(rng, tmp_path):
    left, right = random_pair(rng, height=120, width=400, shift=3)
    cfg = config_from_dict({"memory": {"max_mb": 16}}, base=load_config(None))
    with pytest.raises(ValueError, match="memory budget of 16 MB is too small .* at least"):
        pipeline.check_pair(left, right, 49, cfg)
    import cv2
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    out = tmp_path / "d.pfm"
    res = CliRunner().invoke(main, ["run", str(tmp_path / "l.png"), str(tmp_path / "r.png"),
                                    "-o", str(out), "--max-disp", "49", "--max-memory", "16"])
    assert res.exit_code == 1
    assert "too small" in res.output and len(res.output.strip().splitlines()) == 1
    assert not out.exists()


@pytest.fixture(scope="module")
def teddy(data_dir):
    [scene] = datasets.load_dataset("middlebury2014-quarter", data_dir, names=["Teddy"])
    return scene


def test_stripes_agree_with_one_piece_but_near_seams(teddy):
    """Three stripes (a 60 MB budget) against one piece on a real scene."""
    s = teddy
    one = pipeline.run(s.left, s.right, max_disp=s.max_disp, config="default")
    cfg = config_from_dict({"memory": {"max_mb": 60}}, base=load_config(None))
    cut = pipeline.run(s.left, s.right, max_disp=s.max_disp, config=cfg)
    assert one.stripes == 1 and cut.stripes == 3
    with np.errstate(invalid="ignore"):  # inf - inf where both are invalid
        differ = ~((cut.disparity == one.disparity)
                   | (np.abs(cut.disparity - one.disparity) <= 0.5))
    assert differ.mean() < 0.02
    bad_one, bad_cut = (metrics.bad_percent(d, s.ground_truth, s.masks["nonocc"], 2.0)
                        for d in (one.disparity, cut.disparity))
    assert abs(bad_cut - bad_one) < 0.3


def test_stripes_share_their_volumes_memory_and_hold_none_after(teddy, monkeypatch):
    """Each stripe of a level takes the last one's volume memory (one buffer a slot for
    the three stripes), the bytes as with fresh memory a stripe, and nothing is held
    once the match is done."""
    s = teddy
    cfg = config_from_dict({"memory": {"max_mb": 60}, "photometric": {"enabled": False}},
                           base=load_config(None))
    mapped = []
    take = volumes.VolumePool.take

    def counted(pool, slot, shape):
        held = pool._held.get(slot)
        if held is None or held.size < int(np.prod(shape)):
            mapped.append(slot)
        return take(pool, slot, shape)

    monkeypatch.setattr(volumes.VolumePool, "take", counted)
    shared = pipeline.run(s.left, s.right, max_disp=s.max_disp, config=cfg)
    assert shared.stripes == 3
    assert sorted(set(mapped)) == ["cost", "work"] and len(mapped) <= 4  # the last may grow
    assert getattr(volumes._active, "pool", None) is None
    monkeypatch.setattr(volumes, "shared_by_stripes", contextlib.nullcontext)
    fresh = pipeline.run(s.left, s.right, max_disp=s.max_disp, config=cfg)
    assert shared.disparity.tobytes() == fresh.disparity.tobytes()
    assert shared.confidence.tobytes() == fresh.confidence.tobytes()


@pytest.mark.parametrize("base", ["default", "fast", "accurate"])
def test_striped_and_pyramid_results_do_not_depend_on_threads(teddy, base):
    s = teddy
    cfg = config_from_dict({"memory": {"max_mb": 60}, "pyramid": {"max_row_cells": 20000}},
                           base=load_config(base))
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = pipeline.run(s.left, s.right, max_disp=s.max_disp, config=cfg)
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        many = pipeline.run(s.left, s.right, max_disp=s.max_disp, config=cfg)
    finally:
        numba.set_num_threads(before)
    assert one.levels == 1
    assert one.disparity.tobytes() == many.disparity.tobytes()
    assert one.confidence.tobytes() == many.confidence.tobytes()


def test_band_levels_in_stripes_stay_near_one_piece(teddy):
    """A finer level's band search in stripes within a small budget: the cores kept, the
    result near the level in one piece."""
    s = teddy
    cfg = load_config(None)
    _, coarse_max = pyramid.level_down(s.left.shape[1], s.max_disp)
    coarse = pipeline.run(images.downsample(s.left), images.downsample(s.right),
                          max_disp=coarse_max, config=cfg)
    bands = pyramid.bands_from_coarse(coarse.disparity, coarse.labels, s.left.shape[:2],
                                      s.max_disp, cfg.bands)
    assert 0 < bands.count.mean() < 8 and bands.width <= cfg.bands.max_band
    whole = scale.in_stripes(level.solve, s.left, s.right, s.max_disp, cfg, bands)
    small = config_from_dict({"memory": {"max_mb": 16, "overlap": 24}}, base=cfg)
    cut = scale.in_stripes(level.solve, s.left, s.right, s.max_disp, small, bands)
    assert whole.stripes == 1 and cut.stripes > 1
    with np.errstate(invalid="ignore"):
        differ = ~((cut.disparity == whole.disparity)
                   | (np.abs(cut.disparity - whole.disparity) <= 0.5))
    assert differ.mean() < 0.02


def test_coarse_to_fine_on_an_upscaled_pair_is_accurate(data_dir):
    """Adirondack at twice the quarter size: the full search a level down, a band above."""
    [scene] = datasets.load_dataset("middlebury2014-quarter", data_dir, names=["Adirondack"])
    left, right, gt, mask, max_disp = upscaled_scene(scene, 2)
    cfg = config_from_dict({"pyramid": {"max_row_cells": 100000}}, base=load_config(None))
    result = pipeline.run(left, right, max_disp=max_disp, config=cfg)
    assert result.levels == 1 and result.labels.shape == left.shape[:2]
    hold("large/adirondack-2x-bad4", metrics.bad_percent(result.disparity, gt, mask, 4.0))


@pytest.mark.data
def test_camera_size_pairs_keep_the_full_search_accuracy(data_dir):
    """Three Middlebury 2014 scenes at 1.5 megapixels: `default` goes a level down (the
    pairs hold more than max_cells) and the scanline over the bands keeps the accuracy."""
    scenes = datasets.load_dataset("middlebury2014-quarter", data_dir,
                                   names=["Adirondack", "Motorcycle", "Piano"])
    errors = []
    for scene in scenes:
        left, right, gt, mask, max_disp = upscaled_scene(scene, 2.05)
        result = pipeline.run(left, right, max_disp=max_disp, config="default")
        assert result.levels == 1
        errors.append(metrics.bad_percent(result.disparity, gt, mask, 4.1))
    # the full search: 1.85 / 4.18 / 11.99, mean 6.01; the band search without the
    # scanline 2.55 / 4.12 / 10.81, 5.83
    hold("large/camera-size-mean-bad4", np.mean(errors))


def test_fine_levels_keep_whole_disparities_without_subpixel(teddy):
    s = teddy
    cfg = config_from_dict({"pyramid": {"max_row_cells": 20000}}, base=load_config("paper"))
    result = pipeline.run(s.left, s.right, max_disp=s.max_disp, config=cfg)
    assert result.levels == 1 and not cfg.subpixel.enabled
    assert np.array_equal(result.disparity, np.round(result.disparity))
    # (the full search at this size: 3.83)
    hold("large/teddy-paper-one-level-down-bad2",
         metrics.bad_percent(result.disparity, s.ground_truth, s.masks["nonocc"], 2.0))


@pytest.mark.parametrize("height,width", [(31, 47), (32, 48), (5, 9)])
def test_arms_from_below_stay_inside_the_image_and_the_length(rng, height, width):
    import dataclasses

    image = rng.integers(0, 256, (height, width, 3), dtype=np.uint8)
    image[:, : width // 2] = 128  # a flat half: arms run to the border there
    cfg = dataclasses.replace(load_config("fast").arms, l1=4, l2=4)
    arms = aggregation.arms_from_below(image, cfg).astype(int)
    xs, ys = np.arange(width), np.arange(height)[:, None]
    assert (arms[0] <= xs).all() and (arms[1] <= width - 1 - xs).all()
    assert (arms[2] <= ys).all() and (arms[3] <= height - 1 - ys).all()
    assert arms.max() == 4 and arms.min() >= 0
    if width > 16:  # long in the flat half, away from its edge
        assert (arms[:, :, : width // 2 - 4] == 4).mean() > 0.5


def test_confidence_in_row_blocks_is_the_same_bytes(teddy, monkeypatch):
    """The confidence is computed in blocks of rows (its features' memory bounded at camera
    size, issue 26 item 23); each block reads enough rows around it to change nothing."""
    from vsmatch import confidence

    s = teddy
    result = pipeline.run(s.left, s.right, max_disp=s.max_disp, config="default")
    args = (result.disparity, result.labels, s.left, result.curve, s.max_disp + 1)
    monkeypatch.setattr(confidence, "CONFIDENCE_ROWS", 10**6)
    whole = confidence.confidence_map(*args)
    monkeypatch.setattr(confidence, "CONFIDENCE_ROWS", 37)
    assert confidence.confidence_map(*args).tobytes() == whole.tobytes()
    assert whole.tobytes() == result.confidence.tobytes()


def test_the_scanline_kernels_load_from_the_cache_in_a_new_process(tmp_path):
    """Each scanline kernel and loop body is a closure compiled per flag (whole range or
    bands); its on-disk cache must key the same way in every process, or every run would
    compile the kernels again (seconds each), and those compiled by different processes (as
    the compilation ahead does) must work together in one: Numba names compiled code by its
    function's name and a counter of the compiling process, so two closures of one name
    could clash (the band kernel once ran the whole range's walks so; each now has a name
    of its own). One process compiles the whole range's kernels, another the bands'; a
    third runs both from the cache, compiling nothing, and the bands' sums are the whole
    range's with the costs outside the bands infinite."""
    import subprocess
    import sys

    script = (
        "import sys\n"
        "import numpy as np\n"
        "from numba.core import event\n"
        "from vsmatch import optimization\n"
        "from vsmatch.bands import Bands\n"
        "from vsmatch.config import load_config\n"
        "rng = np.random.default_rng(0)\n"
        "full = rng.random((6, 9, 12), dtype=np.float32)\n"
        "lo = rng.integers(0, 4, size=(6, 9)).astype(np.int32)\n"
        "count = np.full((6, 9), 9, np.int32)\n"
        "inside = np.arange(12) - lo[..., None]\n"
        "inside = (inside >= 0) & (inside < 9)\n"
        "banded = np.stack([full[y, x, lo[y, x]:lo[y, x] + 9] for y in range(6)\n"
        "                   for x in range(9)]).reshape(6, 9, 9)\n"
        "view = rng.integers(0, 40, size=(6, 9, 3), dtype=np.uint8)\n"
        "cfg = load_config(None).scanline\n"
        "what = sys.argv[1]\n"
        "with event.install_recorder('numba:compile') as rec:\n"
        "    if what in ('whole', 'both'):\n"
        "        want = optimization.scanline_optimise(np.where(inside, full, np.inf)\n"
        "                                              .astype(np.float32), view, view, cfg)\n"
        "    if what in ('bands', 'both'):\n"
        "        got = optimization.scanline_optimise(banded, view, view, cfg,\n"
        "                                             bands=Bands(lo, count, 9, 12))\n"
        "if what == 'both':\n"
        "    for y in range(6):\n"
        "        for x in range(9):\n"
        "            assert np.allclose(got[y, x], want[y, x, lo[y, x]:lo[y, x] + 9]), (y, x)\n"
        "names = {e.data['dispatcher'].py_func.__qualname__ for _, e in rec.buffer}\n"
        "print(sorted(n for n in names if 'rows' in n or 'columns' in n or 'walks' in n))\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}

    def compiled(what):
        return subprocess.run([sys.executable, "-c", script, what], env=env,
                              capture_output=True, text=True, check=True).stdout.strip()

    whole = compiled("whole")
    assert "whole_rows" in whole and "whole_columns" in whole
    bands = compiled("bands")
    assert "band_rows" in bands and "band_columns" in bands
    assert compiled("both") == "[]"
