"""The bundled ``fast`` config (issue 21): coarse-to-fine at every size, and at most 0.6x
SGBM's errors on every dataset, run through the real pipeline on the real data, and
within today's figures plus a small margin (tests/figures.yaml)."""

import dataclasses

import numpy as np
import pytest

from vsmatch import datasets, evaluation, level, pipeline, pyramid, scale
from vsmatch.config import ConfigError, config_from_dict, load_config

from conftest import standard_scenes
from figures import hold

#: The datasets and their keys in tests/figures.yaml (headline: nonocc, KITTI all).
FIGURES = {"middlebury2": "middlebury2/fast", "middlebury-third": "middlebury-third/fast",
           "middlebury2014-quarter": "middlebury2014/fast", "kitti2015": "kitti2015/fast"}


def test_min_levels_halves_at_least_that_often():
    assert pyramid.coarse_levels(718, 73, 262144) == 0
    assert pyramid.coarse_levels(718, 73, 262144, min_levels=1) == 1
    assert pyramid.coarse_levels(2872, 292, 262144, min_levels=1) == 1  # already one
    assert pyramid.coarse_levels(2872, 292, 262144, min_levels=2) == 2
    # Never below 16 disparities or 64 columns, whatever is asked; and min_levels keeps
    # at least 10 at the level below (tsukuba's 16 stay a full search, venus's 20 go down).
    assert pyramid.coarse_levels(384, 16, 262144, min_levels=3) == 0
    assert pyramid.coarse_levels(434, 20, 262144, min_levels=3) == 1
    assert pyramid.coarse_levels(100, 60, 262144, min_levels=3) == 1


def test_fast_is_bundled_and_searches_one_level_down(rng):
    cfg = load_config("fast")
    assert cfg.pyramid.min_levels == 1 and not cfg.photometric.enabled
    left = rng.integers(0, 256, (96, 160, 3), dtype=np.uint8)
    right = np.ascontiguousarray(np.roll(left, -6, axis=1))
    result = pipeline.run(left, right, max_disp=24, config=cfg)
    assert result.levels == 1
    inside = np.s_[8:-8, 30:-8]  # away from the borders and the wrapped columns
    assert np.mean(np.abs(result.disparity[inside] - 6) < 0.5) > 0.95
    assert result.confidence.shape == left.shape[:2]
    assert 0 <= result.confidence.min() and result.confidence.max() <= 1


def test_a_level_down_takes_the_scanlines_p2_times_level_p2():
    cfg = load_config("fast")
    down = cfg.a_level_down()
    assert cfg.scanline.level_p2 == 0.5 and down.scanline.p2 == cfg.scanline.p2 * 0.5
    assert down.a_level_down().scanline.p2 == cfg.scanline.p2 * 0.25  # per level
    assert dataclasses.replace(down, scanline=cfg.scanline) == cfg  # P2 alone changes
    default = load_config("default")
    assert default.scanline.level_p2 == 1.0 and default.a_level_down() is default
    for value in (0.0, 1.5):
        with pytest.raises(ConfigError, match="scanline.level_p2"):
            config_from_dict({"scanline": {"level_p2": value}})


def test_each_level_down_is_solved_with_its_own_p2(rng):
    """coarse_to_fine hands each level down ``cfg.a_level_down()``: the full search two
    levels down P2 x 0.25, the bands one level down x 0.5, the views' own size as given."""
    cfg = load_config("fast")
    left = rng.integers(0, 256, (96, 320, 3), dtype=np.uint8)
    right = np.ascontiguousarray(np.roll(left, -8, axis=1))
    seen = []

    def solve(left, right, max_disp, cfg, bands=None):
        seen.append((left.shape[1], cfg.scanline.p2))
        return level.solve(left, right, max_disp, cfg, bands)

    scale.coarse_to_fine(solve, left, right, 40, cfg, levels=2)
    p2 = cfg.scanline.p2
    assert seen == [(80, p2 * 0.25), (160, p2 * 0.5), (320, p2)]


@pytest.mark.data
@pytest.mark.parametrize("dataset", list(FIGURES))
def test_fast_has_at_most_six_tenths_of_sgbms_errors(data_dir, dataset):
    scenes = standard_scenes(datasets.load_dataset(dataset, data_dir))
    report = evaluation.evaluate(scenes, {"fast": "fast", "sgbm": "opencv-sgbm"},
                                 dataset=dataset)
    mask = "all" if dataset.startswith("kitti") else "nonocc"
    fast = report["methods"]["fast"]["avg"][mask]
    sgbm = report["methods"]["sgbm"]["avg"][mask]
    hold(FIGURES[dataset], fast)
    assert fast <= 0.6 * sgbm, (fast, sgbm)
