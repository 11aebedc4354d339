"""Calibration files, depth and point clouds (geometry.py) and their PLY output."""

import cv2
import numpy as np
import pytest
from plyfile import PlyData

from vsmatch import geometry, io

MIDDLEBURY_CALIB = """cam0=[1038.018 0 322.037; 0 1038.018 243.393; 0 0 1]
cam1=[1038.018 0 375.308; 0 1038.018 243.393; 0 0 1]
doffs=53.271
baseline=176.252
width=718
height=496
ndisp=73
isint=0
vmin=8
vmax=65
"""

KITTI_CALIB = """calib_time: 09-Jan-2012 13:57:47
corner_dist: 9.950000e-02
P_rect_00: 7.215377e+02 0.000000e+00 6.095593e+02 0.000000e+00 0.000000e+00 7.215377e+02 1.728540e+02 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00
P_rect_02: 7.215377e+02 0.000000e+00 6.095593e+02 4.485728e+01 0.000000e+00 7.215377e+02 1.728540e+02 2.163791e-01 0.000000e+00 0.000000e+00 1.000000e+00 2.745884e-03
P_rect_03: 7.215377e+02 0.000000e+00 6.095593e+02 -3.395242e+02 0.000000e+00 7.215377e+02 1.728540e+02 2.199936e+00 0.000000e+00 0.000000e+00 1.000000e+00 2.729905e-03
"""


def test_middlebury_calibration(tmp_path):
    path = tmp_path / "calib.txt"
    path.write_text(MIDDLEBURY_CALIB)
    calib = geometry.read_calibration(path)
    assert calib.focal == pytest.approx(1038.018) and calib.baseline == pytest.approx(176.252)
    assert (calib.cx, calib.cy) == pytest.approx((322.037, 243.393))
    assert calib.doffs == pytest.approx(375.308 - 322.037, abs=1e-3) and calib.ndisp == 73


def test_kitti_calibration(tmp_path):
    path = tmp_path / "calib_cam_to_cam.txt"
    path.write_text(KITTI_CALIB)
    calib = geometry.read_calibration(path)
    assert calib.focal == pytest.approx(721.5377)
    assert calib.baseline == pytest.approx((44.85728 + 339.5242) / 721.5377)  # ~0.53 m
    assert calib.doffs == 0.0 and calib.ndisp is None
    assert (calib.cx, calib.cy, calib.focal_y) == pytest.approx((609.5593, 172.854, 721.5377))
    # Depth in metres: a disparity of 10 px lies f B / 10 = 38.4 m away.
    depth = geometry.depth_from_disparity(np.full((1, 1), 10.0, np.float32), calib)
    assert depth[0, 0] == pytest.approx(721.5377 * calib.baseline / 10, rel=1e-6)


@pytest.mark.parametrize("text,message", [
    ("hello\n", "not a Middlebury calib.txt"),
    ("cam0=[1 0 0; 0 1 0]\nbaseline=1\n", "3x3"),
    ("cam0=[1 0 0; 0 1 0; 0 0 1]\n", "missing 'baseline'"),
    ("cam0=[1 0 0; 0 1 0; 0 0 1]\nbaseline=-4\n", "baseline must be positive"),
    # Two cameras of other focal lengths or rows are no rectified pair.
    (MIDDLEBURY_CALIB.replace("cam1=[1038.018 0 375.308; 0 1038.018",
                              "cam1=[1100.0 0 375.308; 0 1100.0"),
     "cam1's focal length 1100 differs from cam0's 1038.02: the views are not rectified"),
    (MIDDLEBURY_CALIB.replace("375.308; 0 1038.018 243.393", "375.308; 0 1038.018 260"),
     "cam1's principal point's row cy 260 differs"),
    (KITTI_CALIB + "S_rect_02: 1.2e+03 3.75e+02 7\n", "S_rect_02 must be two whole"),
])
def test_bad_calibration_is_one_clear_error(tmp_path, text, message):
    path = tmp_path / "calib.txt"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        geometry.read_calibration(path)


def test_depth_formula_and_invalid_pixels():
    calib = geometry.Calibration(focal=1000.0, baseline=0.5, doffs=2.0)
    disp = np.array([[8.0, np.inf, -2.0, 48.0]], np.float32)
    depth = geometry.depth_from_disparity(disp, calib)
    assert depth[0, 0] == pytest.approx(1000 * 0.5 / 10)
    assert depth[0, 3] == pytest.approx(1000 * 0.5 / 50)
    assert np.isinf(depth[0, 1]) and np.isinf(depth[0, 2])  # invalid; d + doffs = 0


def test_point_cloud_matches_opencv_reprojection(rng):
    calib = geometry.Calibration(focal=700.0, baseline=120.0, cx=30.5, cy=18.0, doffs=3.0)
    disp = rng.uniform(5, 40, size=(36, 60)).astype(np.float32)
    disp[4, 7] = np.inf
    image = rng.integers(0, 256, size=(36, 60, 3), dtype=np.uint8)
    points, colours = geometry.point_cloud(disp, image, calib)
    assert len(points) == disp.size - 1
    # OpenCV's Q for a rectified pair (Tx = -B, principal points differing by doffs).
    q = np.array([[1, 0, 0, -calib.cx], [0, 1, 0, -calib.cy], [0, 0, 0, calib.focal],
                  [0, 0, 1 / calib.baseline, calib.doffs / calib.baseline]])
    expected = cv2.reprojectImageTo3D(np.where(np.isfinite(disp), disp, 0).astype(np.float32),
                                      q)
    valid = np.isfinite(disp)
    np.testing.assert_allclose(points, expected[valid], rtol=1e-4)
    np.testing.assert_array_equal(colours, image[valid][:, ::-1])


def test_max_depth_drops_far_points():
    calib = geometry.Calibration(focal=100.0, baseline=1.0)
    disp = np.array([[1.0, 10.0, 100.0]], np.float32)  # depths 100, 10, 1
    image = np.zeros((1, 3), np.uint8)
    points, colours = geometry.point_cloud(disp, image, calib, max_depth=10.0)
    assert points[:, 2].tolist() == pytest.approx([10.0, 1.0]) and colours.shape == (2, 3)


def test_ply_is_binary_little_endian_and_reads_back(tmp_path):
    points = np.array([[1.5, -2.0, 30.0], [0.0, 0.25, 4.0]], np.float32)
    colours = np.array([[255, 0, 10], [1, 2, 3]], np.uint8)
    path = tmp_path / "c.ply"
    io.write_point_cloud(path, geometry.ply_vertices(points, colours))
    assert path.read_bytes().startswith(b"ply\nformat binary_little_endian 1.0\n")
    vertex = PlyData.read(str(path))["vertex"]
    assert [p.name for p in vertex.properties] == ["x", "y", "z", "red", "green", "blue"]
    np.testing.assert_array_equal(np.stack([vertex[a] for a in "xyz"], axis=1), points)
    np.testing.assert_array_equal(
        np.stack([vertex[c] for c in ("red", "green", "blue")], axis=1), colours)


MIDDLEBURY = ("cam0=[{f} 0 {cx}; 0 {fy} 15; {last}]\ncam1=[{f} 0 22.5; 0 {fy} 15; 0 0 1]\n"
              "doffs={doffs}\nbaseline=100\nwidth=40\nheight=30\n")


@pytest.mark.parametrize("changes, message", [
    (dict(fy=-510), "vertical focal length must be positive"),
    (dict(fy=0), "vertical focal length must be positive"),
    (dict(last="5 5 5"), "not a camera matrix"),
])
def test_a_calib_txt_no_camera_has_is_refused(tmp_path, changes, message):
    values = dict(f=500, cx=20.5, fy=510, last="0 0 1", doffs=2)
    values.update(changes)
    path = tmp_path / "calib.txt"
    path.write_text(MIDDLEBURY.format(**values))
    with pytest.raises(geometry.CalibrationError, match=message):
        geometry.read_calibration(path)


@pytest.mark.parametrize("changes, message", [
    (dict(cx=-5000), "principal point"),
    (dict(doffs=-1000), "doffs = -1000"),
])
def test_a_principal_point_outside_the_views_is_refused(tmp_path, changes, message):
    values = dict(f=500, cx=20.5, fy=510, last="0 0 1", doffs=2)
    values.update(changes)
    path = tmp_path / "calib.txt"
    path.write_text(MIDDLEBURY.format(**values))
    calib = geometry.read_calibration(path)
    assert message in calib.size_problem((30, 40, 3))


@pytest.mark.parametrize("args, message", [
    (["--cx", "1e9"], "principal point"),
    (["--doffs", "-1000"], "doffs = -1000"),
])
def test_hand_typed_values_no_camera_has_are_refused(pair_files, tmp_path, args, message):
    from click.testing import CliRunner
    from vsmatch.cli import main

    result = CliRunner().invoke(main, ["run", *map(str, pair_files), "-o",
                                       str(tmp_path / "d.pfm"), "--max-disp", "8", "--focal",
                                       "500", "--baseline", "100", "--depth",
                                       str(tmp_path / "z.pfm"), *args])
    assert result.exit_code == 1 and message in result.output, result.output
    assert not (tmp_path / "d.pfm").exists()


@pytest.mark.parametrize("args, message", [
    (["--alpha", "0.5"], "--alpha is for a raw rig"),
    (["--focal", "500", "--baseline", "100"], "neither is asked for"),
    (["--max-depth", "10", "--focal", "500", "--baseline", "100", "--depth", "z.pfm"],
     "--max-depth limits the --cloud"),
])
def test_options_that_would_do_nothing_are_refused(pair_files, tmp_path, monkeypatch, args,
                                                   message):
    from click.testing import CliRunner
    from vsmatch.cli import main

    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(main, ["run", *map(str, pair_files), "-o", "d.pfm",
                                       "--max-disp", "8", *args])
    assert result.exit_code == 2 and message in result.output, result.output


def test_the_api_names_the_argument_it_cannot_use(rng):
    disp = np.full((30, 40), 5.0, np.float32)
    image = rng.integers(0, 256, (30, 40, 3), dtype=np.uint8)
    calib = geometry.Calibration(focal=500.0, baseline=100.0)
    cases = [
        (lambda: geometry.point_cloud(disp, image[:20], calib), "image is 40x20"),
        (lambda: geometry.point_cloud(disp, image.astype(np.uint16), calib), "image must be"),
        (lambda: geometry.point_cloud(disp, np.dstack([image, image[..., :1]]), calib),
         "image must be"),
        (lambda: geometry.point_cloud(disp, image, calib, max_depth=float("nan")),
         "max_depth"),
        (lambda: geometry.point_cloud(disp[None], image, calib), "disparity must be"),
        (lambda: geometry.depth_from_disparity(disp, "calib.txt"), "calib must be"),
        (lambda: geometry.Calibration(focal="600", baseline=1.0), "focal must be a number"),
    ]
    for call, message in cases:
        with pytest.raises(ValueError, match=message):
            call()


@pytest.mark.parametrize("kwargs, message", [
    (dict(alpha=float("nan")), "alpha"), (dict(alpha=5), "alpha"),
    (dict(calib=123), "calib must be"), (dict(max_disp="16"), "max_disp"),
])
def test_the_stream_matcher_refuses_what_the_cli_refuses(kwargs, message):
    import vsmatch

    with pytest.raises(ValueError, match=message):
        vsmatch.StereoMatcher(**kwargs)


def test_kitti_s_rect_gives_the_views_size_and_tiny_depths_are_refused(tmp_path):
    """KITTI's S_rect_02 is the rectified views' size: views of another are refused as a
    Middlebury calib.txt of another width/height is. A focal length x baseline whose
    depths float32 reads as 0 is refused as one whose depths overflow."""
    path = tmp_path / "calib_cam_to_cam.txt"
    path.write_text(KITTI_CALIB + "S_rect_02: 1.242000e+03 3.750000e+02\n")
    calib = geometry.read_calibration(path)
    assert calib.size == (1242, 375) and calib.size_problem((375, 1242, 3)) is None
    assert "for 1242x375 views" in calib.size_problem((370, 1226, 3))
    tiny = geometry.Calibration(focal=1e-300, baseline=0.16)
    assert "too small for float32 (they would read 0)" in tiny.depth_problem()
    assert geometry.Calibration(focal=700.0, baseline=0.16).depth_problem() is None
