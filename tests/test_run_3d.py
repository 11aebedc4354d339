"""vsmatch run with a calibration: depth, point cloud, the range from ndisp; and the
output-path safety checks (no output over an input, outputs readable by others)."""

import os

import cv2
import numpy as np
import pytest
from click.testing import CliRunner
from plyfile import PlyData

from vsmatch import confidence, geometry, io
from vsmatch.cli import main

from conftest import random_pair

CALIB = """cam0=[500.0 0 20.5; 0 510.0 15.0; 0 0 1]
cam1=[500.0 0 22.5; 0 510.0 15.0; 0 0 1]
doffs=2.0
baseline=100.0
width=48
height=32
ndisp=9
"""


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture
def pair(tmp_path, rng):
    left, right = random_pair(rng, height=32, width=48, shift=3)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    (tmp_path / "calib.txt").write_text(CALIB)
    return tmp_path


def test_cloud_points_reproject_to_their_pixels(pair):
    result = invoke("-v", "run", pair / "l.png", pair / "r.png", "-o", pair / "d.pfm",
                    "--calib", pair / "calib.txt", "--depth", pair / "z.pfm",
                    "--cloud", pair / "c.ply", "--config", "paper", "--min-confidence", 0)
    assert result.exit_code == 0, result.output
    assert "searching disparities 0..8" in result.output  # ndisp 9 sets the range
    disp = io.read_disparity(pair / "d.pfm")
    depth = io.read_disparity(pair / "z.pfm")
    # Every pixel with a match inside the right view (out of view: never in a cloud).
    valid = np.isfinite(disp) & ~confidence.out_of_view(disp)
    np.testing.assert_allclose(depth[valid], 500.0 * 100.0 / (disp[valid] + 2.0), rtol=1e-5)
    vertex = PlyData.read(str(pair / "c.ply"))["vertex"]
    x, y, z = (np.asarray(vertex[a], np.float64) for a in "xyz")
    assert len(x) == valid.sum()
    cols = 500.0 * x / z + 20.5
    rows = 510.0 * y / z + 15.0
    np.testing.assert_allclose(cols, np.round(cols), atol=1e-3)
    np.testing.assert_allclose(rows, np.round(rows), atol=1e-3)
    r, c = np.round(rows).astype(int), np.round(cols).astype(int)
    np.testing.assert_allclose(z, 500.0 * 100.0 / (disp[r, c] + 2.0), rtol=1e-5)
    left = cv2.imread(str(pair / "l.png"))
    np.testing.assert_array_equal(vertex["red"], left[r, c, 2])


def test_calibration_by_hand_matches_the_file(pair):
    args = [pair / "l.png", pair / "r.png", "--max-disp", 8, "--config", "paper"]
    assert invoke("run", *args, "-o", pair / "a.pfm", "--calib", pair / "calib.txt",
                  "--depth", pair / "za.pfm").exit_code == 0
    assert invoke("run", *args, "-o", pair / "b.pfm", "--focal", 500, "--baseline", 100,
                  "--doffs", 2, "--depth", pair / "zb.pfm").exit_code == 0
    assert (pair / "za.pfm").read_bytes() == (pair / "zb.pfm").read_bytes()


@pytest.mark.parametrize("extra,code,message", [
    (["-o", "l.png"], 1, "would overwrite the input l.png"),
    (["-o", "./sub/../r.png"], 1, "would overwrite the input"),
    (["-o", "d.pfm", "--depth", "d.pfm"], 1, "would overwrite the output d.pfm"),
    (["-o", "d.pfm", "--depth", "z.pfm"], 2, "need --calib"),
    (["-o", "d.pfm", "--depth", "z.png", "--calib", "calib.txt"], 2, "must end in .pfm"),
    (["-o", "d.pfm", "--cloud", "c.txt", "--calib", "calib.txt"], 2, "must end in .ply"),
    (["-o", "d.pfm", "--focal", "500"], 2, "neither is asked for"),
    (["-o", "d.pfm", "--focal", "500", "--depth", "z.pfm"], 2,
     "--focal and --baseline go together"),
    (["-o", "d.pfm", "--calib", "calib.txt", "--focal", "5"], 2, "not both"),
    (["-o", "d.pfm", "--calib", "nothere.txt"], 1, "nothere.txt: file not found"),
    (["-o", "d.pfm", "--calib", "l.png"], 1, "cannot read the calibration"),
])
def test_output_and_calibration_errors(pair, monkeypatch, extra, code, message):
    (pair / "sub").mkdir()
    monkeypatch.chdir(pair)
    before = sorted(pair.rglob("*"))
    original = (pair / "l.png").read_bytes()
    result = invoke("run", "l.png", "r.png", "--max-disp", 8, *extra)
    assert result.exit_code == code, result.output
    assert message in result.output and len(result.output.strip().splitlines()) == 1
    assert sorted(pair.rglob("*")) == before
    assert (pair / "l.png").read_bytes() == original


def test_outputs_get_the_umask_permissions(pair):
    old = os.umask(0o022)
    try:
        result = invoke("run", pair / "l.png", pair / "r.png", "-o", pair / "d.pfm",
                        "--max-disp", 8, "--calib", pair / "calib.txt",
                        "--cloud", pair / "c.ply")
        assert result.exit_code == 0, result.output
        assert (pair / "d.pfm").stat().st_mode & 0o777 == 0o644
        assert (pair / "c.ply").stat().st_mode & 0o777 == 0o644
        os.umask(0o007)
        io.write_text_atomic(pair / "t.json", "{}")
        assert (pair / "t.json").stat().st_mode & 0o777 == 0o660
    finally:
        os.umask(old)


def test_hard_link_to_an_input_is_refused(pair):
    os.link(pair / "l.png", pair / "alias.png")
    with pytest.raises(ValueError, match="would overwrite the input"):
        io.check_distinct_paths([pair / "l.png"], [pair / "alias.png"])
    io.check_distinct_paths([pair / "l.png"], [pair / "new.pfm", None])  # no error


def test_python_api_is_exported():
    import vsmatch

    assert vsmatch.depth_from_disparity is geometry.depth_from_disparity
    assert vsmatch.point_cloud is geometry.point_cloud


@pytest.mark.data
@pytest.mark.parametrize("left, right", [
    ("kitti2015/training/image_2/000000_10.png", "kitti2015/training/image_3/000000_10.png"),
    ("middlebury2/teddy/imL.png", "middlebury2/teddy/imR.png"),
    ("middlebury2/venus/imL.png", "middlebury2/venus/imR.png")])
def test_a_16_bit_png_holds_every_real_pairs_disparities(data_dir, tmp_path, left, right):
    """KITTI's own output format: the disparities stay within the searched range (a
    sub-pixel fit or a plane never reaches past it), so the PNG the docs name is written
    for real pairs (it failed after the whole match on -0.52 px)."""
    out = tmp_path / "d.png"
    result = CliRunner().invoke(main, ["run", str(data_dir / left), str(data_dir / right),
                                       "-o", str(out), "--config", "fast"])
    assert result.exit_code == 0, result.output
    disp = io.read_disparity(out)
    assert np.isfinite(disp).mean() > 0.9 and np.nanmin(disp[np.isfinite(disp)]) >= 0


def test_an_empty_cloud_is_said_not_written_silently(pair):
    """A threshold no pixel reaches writes a valid cloud of 0 points, and says so: a user
    would otherwise find an empty file under a plain 'wrote'."""
    (pair / "strict.yaml").write_text("cloud:\n  min_confidence: 1.0\n")
    result = invoke("run", pair / "l.png", pair / "r.png", "--calib", pair / "calib.txt",
                    "-o", pair / "d.pfm", "--cloud", pair / "c.ply", "--config",
                    pair / "strict.yaml")
    assert result.exit_code == 0, result.output
    assert f"warning: {pair / 'c.ply'} holds no points" in result.output
    assert "cloud.min_confidence" in result.output
    assert len(PlyData.read(str(pair / "c.ply"))["vertex"]) == 0
    # A cloud with points says nothing of the kind.
    result = invoke("run", pair / "l.png", pair / "r.png", "--calib", pair / "calib.txt",
                    "-o", pair / "d2.pfm", "--cloud", pair / "c2.ply", "--min-confidence", 0)
    assert result.exit_code == 0 and "holds no points" not in result.output
