"""The disparity range: an offset range (min_disp) honoured by every stage, and the range
estimated from the pair (--max-disp auto)."""

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

import vsmatch
from vsmatch import datasets, io, search_range
from vsmatch.cli import main

from conftest import random_pair
from figures import hold


def textured_pair(rng, shift, height=60, width=120):
    """A smooth random texture (features find corners in it), shifted by ``shift``."""
    base = rng.integers(0, 256, size=(height // 4, (width + abs(shift)) // 4 + 1, 3),
                        dtype=np.uint8)
    wide = cv2.resize(base, ((width + abs(shift)) // 4 * 4 + 4, height),
                      interpolation=cv2.INTER_CUBIC)
    # Left pixel x shows what right pixel x - shift shows.
    if shift >= 0:
        return (np.ascontiguousarray(wide[:, :width]),
                np.ascontiguousarray(wide[:, shift:shift + width]))
    return (np.ascontiguousarray(wide[:, -shift:-shift + width]),
            np.ascontiguousarray(wide[:, :width]))


@pytest.mark.parametrize("shift,low,high", [(12, 8, 20), (12, 10, 13), (-3, -6, 2)])
def test_an_offset_range_finds_the_shift(rng, shift, low, high):
    left, right = textured_pair(rng, shift, height=30, width=70)
    disp = vsmatch.match(left, right, min_disp=low, max_disp=high, config="paper")
    if low > 0:
        assert np.isinf(disp[:, :low]).all()  # no candidate there, as with SGBM
        inner = disp[5:-5, low + 8:-5]
    else:
        # Every left column keeps the candidates that lie in the right view: only where
        # the match lies beyond its last column (x - shift >= width) is there none.
        width = disp.shape[1]
        assert np.mean(np.isinf(disp[:, width + shift:])) > 0.6
        assert np.mean(disp[5:-5, width + low:width + shift] == shift) > 0.9
        inner = disp[5:-5, 5:width + shift - 1]
    assert np.mean(inner == shift) > 0.95


def test_an_offset_range_is_the_zero_range_of_cropped_views(rng):
    left, right = textured_pair(rng, 15, height=40, width=90)
    offset = vsmatch.match(left, right, min_disp=10, max_disp=20)
    cropped = vsmatch.match(np.ascontiguousarray(left[:, 10:]),
                            np.ascontiguousarray(right[:, :-10]), max_disp=10)
    np.testing.assert_array_equal(offset[:, 10:], cropped + 10)


@pytest.mark.parametrize("low,high,message", [
    (5, 5, "must be larger than min_disp"),
    (50, 80, "too wide"),
    (1.5, 8, "min_disp must be an integer"),
])
def test_bad_offset_ranges_are_refused(rng, low, high, message):
    left, right = random_pair(rng, height=20, width=60)
    with pytest.raises(ValueError, match=message):
        vsmatch.match(left, right, min_disp=low, max_disp=high)


@pytest.mark.parametrize("shift", [7, 25])
def test_auto_range_covers_a_known_shift(rng, shift):
    left, right = textured_pair(rng, shift, height=120, width=240)
    found = search_range.estimate_disparity_range(left, right)
    assert found.min_disp == 0 and shift <= found.max_disp <= 2 * shift + 20
    assert found.matches >= search_range.MIN_MATCHES


def test_no_range_from_a_blank_pair():
    blank = np.full((60, 120, 3), 128, np.uint8)
    with pytest.raises(search_range.RangeError, match="give --max-disp"):
        search_range.estimate_disparity_range(blank, blank)


def test_run_without_max_disp_estimates_it(rng, tmp_path):
    left, right = textured_pair(rng, 9, height=120, width=240)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    result = CliRunner().invoke(main, ["-v", "run", str(tmp_path / "l.png"),
                                       str(tmp_path / "r.png"), "-o", str(tmp_path / "d.pfm")])
    assert result.exit_code == 0, result.output
    assert "feature matches" in result.output and "searching disparities 0.." in result.output
    disp = io.read_disparity(tmp_path / "d.pfm")
    assert np.mean(np.abs(disp[10:-10, 40:-10] - 9) < 0.5) > 0.9


def test_run_on_a_blank_pair_asks_for_max_disp(tmp_path):
    blank = np.full((60, 120, 3), 128, np.uint8)
    cv2.imwrite(str(tmp_path / "l.png"), blank)
    cv2.imwrite(str(tmp_path / "r.png"), blank)
    result = CliRunner().invoke(main, ["run", str(tmp_path / "l.png"),
                                       str(tmp_path / "r.png"), "-o", str(tmp_path / "d.pfm")])
    assert result.exit_code == 1 and "give --max-disp" in result.output
    assert not (tmp_path / "d.pfm").exists()


@pytest.mark.data
@pytest.mark.parametrize("dataset", ["middlebury2", "middlebury-third",
                                     "middlebury2014-quarter", "kitti2015"])
def test_auto_range_covers_the_true_range_on_every_scene(data_dir, dataset):
    for scene in datasets.load_dataset(dataset, data_dir):
        truth = scene.ground_truth[scene.masks.get("nonocc", scene.masks["all"])]
        found = search_range.estimate_disparity_range(scene.left, scene.right)
        assert found.min_disp <= truth.min() and truth.max() <= found.max_disp, scene.name


@pytest.mark.data
def test_a_negative_range_matches_every_column_with_a_partner_in_view(data_dir):
    """Teddy's views cropped so that its disparities move by -30: the pixels whose match
    lies in the right view are matched as well as the scene is (bad 2.0 in
    tests/figures.yaml; 10.27 % when the last 30 columns were cut from the match), the
    rest are invalid."""
    from vsmatch import datasets, metrics, pipeline

    scene = datasets.load_dataset("middlebury2014-quarter", data_dir, names=["Teddy"])[0]
    shift = 30
    left = np.ascontiguousarray(scene.left[:, shift:])
    right = np.ascontiguousarray(scene.right[:, :-shift])
    truth = scene.ground_truth[:, shift:] - shift
    width = left.shape[1]
    beyond = np.arange(width)[None, :] - truth > width - 0.5
    known = scene.masks["nonocc"][:, shift:] & (scene.ground_truth[:, shift:] > 0)
    result = pipeline.run(left, right, min_disp=-shift, max_disp=scene.max_disp - shift)
    hold("range/teddy-negative-bad2",
         metrics.bad_percent(result.disparity, truth, known & ~beyond, 2.0))
    assert np.isfinite(result.disparity[:, -shift:]).mean() > 0.5  # no longer cut
    finite = np.isfinite(result.disparity)
    columns = np.arange(width)[None, :]
    assert not (finite & (columns - result.disparity > width - 0.5)).any()
    assert (result.confidence[~finite] == 0).all()


def write_views(folder, left, right):
    cv2.imwrite(str(folder / "l.png"), left)
    cv2.imwrite(str(folder / "r.png"), right)
    return folder / "l.png", folder / "r.png"


def searched(result):
    """The range a -v run says it searches."""
    assert result.exit_code == 0, result.output
    line = next(text for text in result.output.splitlines()
                if "searching disparities" in text)
    low, high = line.split()[-1].split("..")
    return int(low), int(high)


def test_the_found_range_stops_where_the_calibration_puts_infinity(tmp_path, rng):
    """A point at infinity has d = -doffs: the found range does not reach below it."""
    from cli_helpers import verged_pair

    views = write_views(tmp_path, *verged_pair(rng))
    free = searched(CliRunner().invoke(main, ["-v", "run", *map(str, views), "-o",
                                              str(tmp_path / "a.pfm")]))
    assert free[0] < -14  # the pair's own -12, with the margin
    (tmp_path / "calib.txt").write_text("cam0=[300 0 120; 0 300 80; 0 0 1]\n"
                                        "cam1=[300 0 134; 0 300 80; 0 0 1]\n"
                                        "doffs=14\nbaseline=60\n")
    bounded = searched(CliRunner().invoke(main, ["-v", "run", *map(str, views), "-o",
                                                 str(tmp_path / "b.pfm"), "--calib",
                                                 str(tmp_path / "calib.txt")]))
    assert bounded[0] == -14 and bounded[1] == free[1]
    disp = io.read_disparity(tmp_path / "b.pfm")
    assert np.mean(np.abs(disp[10:70, 30:-30] + 12) < 1) > 0.9


def test_a_verged_rigs_rectified_folder_keeps_its_range(tmp_path, rng):
    """run --rectified writes the searched range's bottom (dmin) beside ndisp: run again
    on the folder, the same negative range is searched (it was cut to 0..max)."""
    from cli_helpers import shifted_pair
    from cli_helpers import write_opencv_rig

    top, bottom = (shifted_pair(rng, dx, height=48, width=160) for dx in (-12, 10))
    left, right = np.vstack([top[0], bottom[0]]), np.vstack([top[1], bottom[1]])
    views = write_views(tmp_path, left, right)
    rig_file = write_opencv_rig(tmp_path / "rig.yaml")
    first = searched(CliRunner().invoke(main, [
        "-v", "run", *map(str, views), "--calib", str(rig_file), "-o", str(tmp_path / "a.pfm"),
        "--min-disp", "-20", "--max-disp", "16", "--rectified", str(tmp_path / "rect")]))
    assert first == (-20, 16)
    calib = vsmatch.read_calibration(tmp_path / "rect" / "calib.txt")
    assert calib.search_range(left.shape[1]) == (-20, 16)
    again = searched(CliRunner().invoke(main, [
        "-v", "run", str(tmp_path / "rect/im0.png"), str(tmp_path / "rect/im1.png"),
        "--calib", str(tmp_path / "rect/calib.txt"), "-o", str(tmp_path / "b.pfm")]))
    assert again == (-20, 16)


def test_min_disp_alone_is_honoured_by_the_stream_matcher(rng):
    left, right = textured_pair(rng, 12, height=80, width=200)
    stereo = vsmatch.StereoMatcher(min_disp=4, config="fast")
    stereo.compute(left, right)
    assert stereo.range[0] == 4 and stereo.range[1] >= 12


def test_min_disp_alone_is_honoured_by_video(tmp_path, rng):
    from test_video import write_videos

    write_videos(tmp_path, rng)
    result = CliRunner().invoke(main, ["-v", "video", str(tmp_path / "left.avi"),
                                       str(tmp_path / "right.avi"), "-o",
                                       str(tmp_path / "d.avi"), "--min-disp", "3",
                                       "--config", "fast"])
    assert result.exit_code == 0, result.output
    assert "disparities 3.." in result.output, result.output


@pytest.mark.data
@pytest.mark.parametrize("name", ["Piano", "ArtL"])
def test_a_negative_found_range_stays_near_the_truth(data_dir, name):
    """Views cropped against each other so that the disparities run below 0: the found
    bottom covers the truth without reaching far past it (unsure dense matches piled up
    at the dense check's own bottom: Piano -67 for a true -15.7, ArtL -53 for -8.8)."""
    scene = datasets.load_dataset("middlebury2014-quarter", data_dir, names=[name])[0]
    mask = scene.masks["nonocc"]
    shift = round(float(scene.ground_truth[mask].max()) / 2)
    left = np.ascontiguousarray(scene.left[:, shift:])
    right = np.ascontiguousarray(scene.right[:, :-shift])
    truth = (scene.ground_truth - shift)[:, shift:][mask[:, shift:]]
    found = search_range.estimate_disparity_range(left, right)
    assert found.min_disp <= truth.min() and truth.max() <= found.max_disp
    margin = search_range.MARGIN_FACTOR * truth.min() - search_range.MARGIN_PIXELS
    assert found.min_disp >= margin - 6, (found.min_disp, truth.min())
