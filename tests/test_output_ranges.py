"""Outputs that cannot hold a value are refused before the work, never clipped."""

import cv2
import numpy as np
import pytest
from cli_helpers import HEIGHT, WIDTH, files_in, invoke, one_line_error, write_pair
from conftest import random_pair

from vsmatch import geometry, io, pipeline, preview


def test_png_output_refuses_a_range_it_cannot_hold_before_matching(tmp_path, rng,
                                                                   monkeypatch):
    left, right = random_pair(rng, height=24, width=300, shift=3)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    monkeypatch.setattr(pipeline, "run", lambda *a, **k: pytest.fail("matched anyway"))
    for extra in (["--max-disp", 280], ["--min-disp", -16, "--max-disp", 8]):
        line = one_line_error(invoke("run", tmp_path / "l.png", tmp_path / "r.png",
                                     "-o", tmp_path / "d.png", *extra))
        assert "16-bit PNG" in line and ".pfm" in line
    assert files_in(tmp_path) == ["l.png", "r.png"]


def test_png_encoder_refuses_instead_of_clipping():
    with pytest.raises(ValueError, match="16-bit PNG"):
        io.disparity_to_png16(np.array([[300.0, 2.0]], np.float32))
    with pytest.raises(ValueError, match="16-bit PNG"):
        io.disparity_to_png16(np.array([[-3.0, 2.0]], np.float32))
    png = io.disparity_to_png16(np.array([[np.inf, 255.5]], np.float32))
    assert png.tolist() == [[0, 65408]]


def test_batch_png_refuses_a_pair_whose_range_it_cannot_hold(tmp_path, rng):
    for name, width in (("wide", 300), ("narrow", 48)):
        left, right = random_pair(rng, height=24, width=width, shift=3)
        cv2.imwrite(str(tmp_path / f"{name}_left.png"), left)
        cv2.imwrite(str(tmp_path / f"{name}_right.png"), right)
    (tmp_path / "p.csv").write_text("wide_left.png,wide_right.png,wide.png,280\n"
                                    "narrow_left.png,narrow_right.png,narrow.png,8\n")
    result = invoke("batch", tmp_path / "p.csv")
    assert result.exit_code == 1
    assert "16-bit PNG" in result.output and "failed: " in result.output
    assert (tmp_path / "narrow.png").exists() and not (tmp_path / "wide.png").exists()


def test_ndisp_of_half_the_width_or_more_is_unknown(tmp_path, pair_files):
    calib = tmp_path / "calib.txt"
    calib.write_text("cam0=[100 0 24; 0 100 16; 0 0 1]\ndoffs=0\nbaseline=50\nndisp=48\n")
    assert geometry.read_calibration(calib).search_range_for(48) is None
    assert geometry.read_calibration(calib).search_range_for(200) == 48
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--calib", calib, "-v")
    # The range is then found from the pair (this tiny random pair has too few features).
    assert "taken as 'unknown'" in result.output
    assert "--max-disp" not in result.output.split("taken as")[0]


def test_preview_is_written_with_the_disparity(pair_files, tmp_path):
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8,
                    "--preview", tmp_path / "d_colour.png")
    assert result.exit_code == 0, result.output
    preview = cv2.imread(str(tmp_path / "d_colour.png"))
    assert preview.shape[0] == 32 and preview.shape[1] > 48 and preview[:, :48].std() > 0


def test_a_placeholder_ndisp_of_100000_does_not_blame_max_disp(tmp_path, pair_files):
    calib = tmp_path / "calib.txt"
    calib.write_text("cam0=[100 0 24; 0 100 16; 0 0 1]\ndoffs=0\nbaseline=50\nndisp=100000\n")
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--calib", calib, "-v")
    assert "ndisp=100000 is half the image width or more" in result.output
    assert "must be less than the image width" not in result.output


def test_depths_float32_cannot_hold_are_refused_before_matching(tmp_path, rng,
                                                                   monkeypatch):
    views = write_pair(tmp_path, rng)
    monkeypatch.setattr(pipeline, "run", lambda *a, **k: pytest.fail("matched anyway"))
    line = one_line_error(invoke("run", *views, "--focal", 1e20, "--baseline", 1e20,
                                 "--depth", tmp_path / "z.pfm", "-o", tmp_path / "d.pfm",
                                 "--max-disp", 16))
    assert "float32" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["l.png", "r.png"]


def test_preview_spans_the_disparities_present_with_a_bar_and_dims_the_unsure():
    disp = np.tile(np.linspace(10, 20, 120, dtype=np.float32), (80, 1))
    disp[:, :5] = np.inf
    conf = np.ones_like(disp)
    conf[40:, :] = 0.1  # the lower half is unsure
    picture = preview.disparity_preview(disp, conf, 0.5)
    assert picture.shape[0] == 80 and picture.shape[1] > 120  # the colour bar
    image = picture[:, :120].astype(int)
    turbo = cv2.applyColorMap(np.arange(256, dtype=np.uint8)[None], cv2.COLORMAP_TURBO)[0]
    # The trusted rows' ends take the scale's two ends (a 0..173 range would not).
    assert np.abs(image[10, 6] - turbo[0]).max() <= 20
    assert np.abs(image[10, 119] - turbo[255]).max() <= 20
    assert (image[:, :5] == 0).all()  # invalid: black
    assert image[50:, 5:].mean() < 0.6 * image[:40, 5:].mean()  # unsure: dimmed
    bar = picture[:, 120:]
    assert (bar == 0).all(axis=2).any()  # labels drawn on the bar's panel


def test_run_writes_the_preview_with_its_colour_bar(tmp_path, rng):
    views = write_pair(tmp_path, rng)
    result = invoke("run", *views, "-o", tmp_path / "d.pfm", "--max-disp", 40, "--preview",
                    tmp_path / "p.png")
    assert result.exit_code == 0, result.output
    picture = cv2.imread(str(tmp_path / "p.png"))
    assert picture.shape[0] == HEIGHT and picture.shape[1] > WIDTH + 40
    # Disparities of about 6 in a 0..40 search: the colours still span the scale.
    turbo = cv2.applyColorMap(np.arange(256, dtype=np.uint8)[None], cv2.COLORMAP_TURBO)[0]
    used = picture[8:-8, 24:WIDTH - 8].reshape(-1, 3).astype(int)
    nearest = np.abs(used[:, None, :] - turbo[None].astype(int)).sum(2).argmin(1)
    assert nearest.max() - nearest.min() > 128
