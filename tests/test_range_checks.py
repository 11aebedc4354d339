"""The disparity range found or given: thin pairs, ranges below zero, swapped and
unrectified views named."""

import cv2
import numpy as np
import pytest
from cli_helpers import invoke, one_line_error, shifted_pair, verged_pair
from conftest import random_pair

import vsmatch
from vsmatch import config, exposure, io


def test_first_match_over_more_than_256_disparities(rng):
    """OpenCV 5's blur takes at most 128 channels; 4.x took 512."""
    left, right = random_pair(rng, height=40, width=420, shift=30)
    cfg = config.load_config("default")
    disp, matched = exposure.first_match(left, right, 300, cfg)
    assert disp.shape == (40, 420)
    assert np.mean(disp[matched] == 30) > 0.9 and matched[:, 340:].mean() > 0.5


@pytest.mark.parametrize("height, width", [(4, 20000), (2, 100000), (60, 1)])
def test_a_very_thin_pair_without_a_range_is_one_line(tmp_path, rng, height, width):
    """What is wrong is the views' size, whatever the range: said before any range is
    looked for (not "give --max-disp")."""
    left, right = random_pair(rng, height=height, width=width, shift=0)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    line = one_line_error(invoke("run", tmp_path / "l.png", tmp_path / "r.png", "-o",
                                 tmp_path / "d.pfm"))
    assert "smaller than the census window" in line and "--max-disp" not in line


def test_the_found_range_goes_below_zero_with_the_pair(rng):
    from vsmatch.search_range import estimate_disparity_range

    found = estimate_disparity_range(*verged_pair(rng))
    assert found.min_disp <= -12 and found.max_disp >= 10
    left, right = shifted_pair(rng, 12)
    assert estimate_disparity_range(left, right).min_disp == 0


def test_a_negative_found_range_is_searched(tmp_path, rng):
    left, right = verged_pair(rng)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    result = invoke("run", tmp_path / "l.png", tmp_path / "r.png", "-o", tmp_path / "d.pfm",
                    "-v")
    assert result.exit_code == 0, result.output
    disp = io.read_disparity(tmp_path / "d.pfm")
    assert np.mean(np.abs(disp[10:70, 30:-30] + 12) < 1) > 0.9
    assert np.mean(np.abs(disp[90:-10, 30:-30] - 10) < 1) > 0.9


def test_swapped_views_are_refused_without_a_range_and_named_with_one(tmp_path, rng):
    left, right = shifted_pair(rng, 12)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    swapped = ["run", tmp_path / "r.png", tmp_path / "l.png", "-o", tmp_path / "d.pfm"]
    assert "views look swapped" in one_line_error(invoke(*swapped))
    assert not (tmp_path / "d.pfm").exists()
    given = invoke(*swapped, "--max-disp", 20)
    assert given.exit_code == 0 and "warning: " in given.output and "swapped" in given.output


def test_unrectified_views_are_refused_without_a_range_and_named_with_one(tmp_path, rng):
    left, right = shifted_pair(rng, 8, dy=4)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    args = ["run", tmp_path / "l.png", tmp_path / "r.png", "-o", tmp_path / "d.pfm"]
    line = one_line_error(invoke(*args))
    assert "rows disagree by 4.0 px" in line and "not rectified" in line
    given = invoke(*args, "--max-disp", 20)
    assert given.exit_code == 0 and "warning: " in given.output and "rectif" in given.output


def test_match_finds_the_range_when_max_disp_is_none(rng):
    left, right = verged_pair(rng)
    result = vsmatch.run(left, right, max_disp=None, config="paper")
    low, high = result.search_range
    assert low <= -12 and high >= 10
    disp = vsmatch.match(left, right, max_disp=None, config="paper")
    np.testing.assert_array_equal(disp, result.disparity)
    np.testing.assert_array_equal(
        disp, vsmatch.match(left, right, min_disp=low, max_disp=high, config="paper"))
    left, right = shifted_pair(rng, 12)
    with pytest.raises(ValueError, match="swapped"):
        vsmatch.match(right, left, max_disp=None)


def test_a_swapped_raw_pair_is_not_told_to_rectify(data_dir, tmp_path):
    """Rows that disagree after vsmatch rectified the views itself: the views are swapped
    or the calibration is another rig's, not "rectify it first"."""
    rig_dir = data_dir / "real-cameras" / "ukulele-raw"
    line = one_line_error(invoke("run", rig_dir / "right.png", rig_dir / "left.png",
                                 "--calib", rig_dir / "rig.yml", "-o", tmp_path / "d.pfm"))
    assert "are the views swapped" in line and "rectify it first" not in line


def test_a_range_too_small_is_said_with_how_many_pixels_pile_at_its_end(tmp_path, data_dir):
    """cones (disparities up to ~55) searched to 30 exits 0 with a disparity map, and says
    how many pixels lie at the range's top; searched over its own range, nothing is said."""
    folder = data_dir / "middlebury2" / "cones"
    result = invoke("run", folder / "imL.png", folder / "imR.png", "-o", tmp_path / "d.pfm",
                    "--max-disp", 30, "--config", "fast")
    assert result.exit_code == 0, result.output
    warning = [line for line in result.output.splitlines() if "warning:" in line]
    assert len(warning) == 1, result.output
    assert "of the pixels lie at the top of the range searched (30)" in warning[0]
    assert "larger --max-disp" in warning[0]
    result = invoke("run", folder / "imL.png", folder / "imR.png", "-o", tmp_path / "e.pfm",
                    "--max-disp", 59, "--config", "fast")
    assert result.exit_code == 0 and "warning" not in result.output, result.output
    # Above a bottom of 0 the bottom end counts too (a scene farther than the range).
    from vsmatch.search_range import range_end_warning

    disparity = np.full((10, 10), 20.0, np.float32)
    assert "at the bottom of the range searched (20)" in range_end_warning(disparity, 20, 60)
    assert range_end_warning(np.zeros((10, 10), np.float32), 0, 60) is None
