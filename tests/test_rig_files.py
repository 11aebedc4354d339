"""Raw-rig calibrations (OpenCV, ROS, Kalibr, calib.txt): impossible rigs refused naming
the key."""

import numpy as np
import pytest
import yaml
from cli_helpers import (
    HEIGHT,
    WIDTH,
    invoke,
    kalibr_rig,
    one_line_error,
    ros_pair,
    write_opencv_rig,
    write_pair,
)

from vsmatch import rig
from vsmatch.geometry import CalibrationError


def opencv_text(**replace):
    """An OpenCV YAML rig as text, with keys' values replaced verbatim."""
    lines = {"K1": "!!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [300., 0., 80., "
                   "0., 300., 48., 0., 0., 1.]",
             "K2": "!!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [300., 0., 80., "
                   "0., 300., 48., 0., 0., 1.]",
             "D1": "!!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n"
                   "   data: [0., 0., 0., 0., 0.]",
             "D2": "!!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n"
                   "   data: [0., 0., 0., 0., 0.]",
             "R": "!!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [1., 0., 0., "
                  "0., 1., 0., 0., 0., 1.]",
             "T": "!!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [-60., 0., 0.]",
             "image_width": str(WIDTH), "image_height": str(HEIGHT)}
    lines.update(replace)
    return "%YAML:1.0\n---\n" + "".join(f"{k}: {v}\n" for k, v in lines.items() if v is not None)


def coefficients(n):
    return (f"!!opencv-matrix\n   rows: 1\n   cols: {n}\n   dt: d\n   data: "
            f"[{', '.join(['0.'] * n)}]")


@pytest.mark.parametrize("changes,key", [
    (dict(R=np.zeros((3, 3))), "R is not a rotation"),
    (dict(R=np.diag([1.0, 1, -1])), "R is not a rotation"),
    (dict(T=np.array([[-1e300], [0], [0]])), "overflow float32"),
    (dict(T=np.array([[0.0], [-60], [0]])), "not mostly along x"),
    (dict(K2=np.zeros((3, 3))), "K2 has focal lengths"),
    (dict(K1=np.array([[300.0, 0, 900], [0, 300, 48], [0, 0, 1]])), "outside the"),
    # Lenses no camera has: the view magnified into a uniform grey, or mostly empty.
    (dict(D1=np.array([[1e4, 0, 0, 0, 0]]), D2=np.array([[1e4, 0, 0, 0, 0]])),
     "the rectification scales the views by 966"),
    (dict(D1=np.array([[-1e3, 0, 0, 0, 0]])), "% of the rectified left view shows its image"),
])
def test_impossible_opencv_rigs_are_refused_naming_the_key(tmp_path, rng, changes, key):
    views = write_pair(tmp_path, rng)
    calib = write_opencv_rig(tmp_path / "rig.yaml", **changes)
    line = one_line_error(invoke("run", *views, "--calib", calib, "-o", tmp_path / "d.pfm",
                                 "--max-disp", 16))
    assert key in line and "rig.yaml" in line
    assert not (tmp_path / "d.pfm").exists()


@pytest.mark.parametrize("side,changes,key", [
    ("right", {"rectification_matrix": {"data": [0.0] * 9}}, "rectification_matrix"),
    ("right", {"camera_matrix": {"data": [0.0] * 9}}, "camera_matrix"),
    ("right", {"projection_matrix": {"data": [0.0] * 12}}, "projection_matrix"),
    ("right", {"image_width": -5}, "image_width"),
    ("left", {"image_width": float("inf")}, "image_width"),
    ("left", {"image_width": float("nan")}, "image_width"),
    ("left", {"image_width": "abc"}, "image_width"),
])
def test_impossible_ros_pairs_are_refused_naming_the_key(tmp_path, side, changes, key):
    left, right = ros_pair(tmp_path, **{f"{side}_changes": changes})
    with pytest.raises(CalibrationError) as caught:
        rig.read_rig([left, right])
    assert key in str(caught.value) and f"{side}.yaml" in str(caught.value)


def test_hand_values_with_a_raw_rig_are_refused(tmp_path, rng):
    views = write_pair(tmp_path, rng)
    calib = write_opencv_rig(tmp_path / "rig.yaml")
    line = one_line_error(invoke("run", *views, "--calib", calib, "--focal", 500,
                                 "--baseline", 1, "-o", tmp_path / "d.pfm"), code=2)
    assert "--calib or --focal, --baseline" in line


@pytest.mark.parametrize("command", ["run", "rectify"])
def test_alpha_nan_is_refused(tmp_path, rng, command):
    views = write_pair(tmp_path, rng)
    calib = write_opencv_rig(tmp_path / "rig.yaml")
    out = ["-o", tmp_path / "d.pfm"] if command == "run" else ["--to", tmp_path / "r"]
    line = one_line_error(invoke(command, *views, "--calib", calib, "--alpha", "nan", *out),
                          code=2)
    assert "--alpha" in line and "finite" in line


@pytest.mark.parametrize("changes,message", [
    ({"distortion_coeffs": [0.1, 0.01, 0.0]}, "must be 4 numbers (k1, k2, p1, p2) or 5"),
    ({"distortion_model": "equidistant"}, "cam1's distortion_model"),
    ({"resolution": [WIDTH + 2, HEIGHT]}, "cam1's resolution"),
    ({"resolution": [WIDTH, HEIGHT, 3]}, "[width, height]"),
])
def test_kalibr_cam1_fields_are_read(tmp_path, changes, message):
    (tmp_path / "camchain.yaml").write_text(yaml.safe_dump(kalibr_rig(**changes)))
    with pytest.raises(CalibrationError) as caught:
        rig.read_rig([tmp_path / "camchain.yaml"])
    assert message in str(caught.value)


def test_a_calib_txt_for_other_views_is_refused(tmp_path, rng):
    views = write_pair(tmp_path, rng)
    (tmp_path / "calib.txt").write_text(
        "cam0=[300 0 80; 0 300 48; 0 0 1]\ncam1=[300 0 80; 0 300 48; 0 0 1]\ndoffs=0\n"
        f"baseline=60\nwidth={WIDTH * 2}\nheight={HEIGHT}\nndisp=17\n")
    line = one_line_error(invoke("run", *views, "--calib", tmp_path / "calib.txt", "-o",
                                 tmp_path / "d.pfm"))
    assert "calib.txt" in line and f"{WIDTH * 2}x{HEIGHT}" in line
    assert not (tmp_path / "d.pfm").exists()


@pytest.mark.parametrize("replace,key", [
    (dict(T="!!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [0., 0., 0.]"), "T"),
    (dict(D1=coefficients(3)), "D1"),
    (dict(D1=coefficients(10)), "D1"),
    (dict(D1=coefficients(100)), "D1"),
    (dict(K1='"hello"'), "K1"),
    (dict(image_width=None, image_height=None, imageSize="hello"), "imageSize"),
    (dict(D1="[]"), "D1"),
    (dict(image_width=".inf"), "image_width"),
    (dict(image_width=".nan"), "image_width"),
    (dict(image_width="'abc'"), "image_width"),
    (dict(image_width="1e400"), "image_width"),
    (dict(K1="!!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [300., 0., 80., "
              "0., 0., 48., 0., 0., 1.]"), "K1"),
])
def test_bad_opencv_fields_are_one_line_naming_the_key(tmp_path, rng, replace, key):
    views = write_pair(tmp_path, rng)
    (tmp_path / "rig.yaml").write_text(opencv_text(**replace))
    line = one_line_error(invoke("run", *views, "--calib", tmp_path / "rig.yaml", "-o",
                                 tmp_path / "d.pfm", "--max-disp", 16))
    assert "rig.yaml" in line and key in line
    assert "function" not in line and "swapped" not in line and "convert" not in line


@pytest.mark.parametrize("text", [
    opencv_text()[:120],
    '<?xml version="1.0"?>\n<!DOCTYPE x [<!ENTITY a "b">]>\n<opencv_storage><K1>',
    "%YAML:1.0\n---\nK1: [1, 2\n",
])
def test_broken_filestorage_files_are_one_line(tmp_path, rng, text):
    views = write_pair(tmp_path, rng)
    (tmp_path / "rig.yaml").write_text(text)
    line = one_line_error(invoke("run", *views, "--calib", tmp_path / "rig.yaml", "-o",
                                 tmp_path / "d.pfm", "--max-disp", 16))
    assert "rig.yaml" in line and "SystemError" not in line


@pytest.mark.parametrize("coeffs", [[], [0.1, 0.2]])
def test_a_fisheye_without_four_coefficients_is_named(tmp_path, coeffs):
    data = kalibr_rig()
    for cam in ("cam0", "cam1"):
        data[cam].update(distortion_model="equidistant", distortion_coeffs=coeffs)
    (tmp_path / "camchain.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(CalibrationError, match="cam0.distortion_coeffs has"):
        rig.read_rig([tmp_path / "camchain.yaml"])


def test_a_key_given_twice_in_an_opencv_rig_is_refused(tmp_path):
    """OpenCV keeps one of two K1 without a word (the YAML configs already refuse it)."""
    text = opencv_text()
    (tmp_path / "rig.yaml").write_text(text + "K1: " + text.split("K1: ")[1].split("\nK2")[0]
                                       + "\n")
    with pytest.raises(CalibrationError, match="rig.yaml: K1 is given twice"):
        rig.read_rig([tmp_path / "rig.yaml"])
    (tmp_path / "once.yaml").write_text(text)
    assert rig.read_rig([tmp_path / "once.yaml"]).K1[0, 0] == 300.0


def test_json_rigs_are_read_and_unknown_files_name_the_formats(tmp_path, data_dir):
    """A rig as JSON (cv2.stereoCalibrate's names, or the published rig.json's intrinsic1,
    distCoeffs1, res1) is read as its YAML is; one EuRoC sensor.yaml says the other camera's
    is needed; a file of no known kind names the kinds read."""
    import json

    raw = data_dir / "real-cameras" / "ukulele-raw"
    published, as_yaml = rig.read_rig([raw / "rig.json"]), rig.read_rig([raw / "rig.yml"])
    for key in ("K1", "D1", "K2", "D2", "R", "T"):
        np.testing.assert_allclose(getattr(published, key), getattr(as_yaml, key), rtol=1e-9)
    assert published.size == as_yaml.size == (1280, 720)
    values = {"K1": [[300, 0, 80], [0, 300, 48], [0, 0, 1]], "K2": [[300, 0, 80], [0, 300, 48],
              [0, 0, 1]], "D1": [0, 0, 0, 0, 0], "D2": [0, 0, 0, 0, 0],
              "R": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "T": [-60, 0, 0],
              "image_width": WIDTH, "image_height": HEIGHT}
    (tmp_path / "mine.json").write_text(json.dumps(values))
    assert rig.is_raw_rig([tmp_path / "mine.json"])
    assert rig.read_rig([tmp_path / "mine.json"]).T[0] == -60
    sensor = data_dir / "real-cameras" / "euroc-clip" / "cam0" / "sensor.yaml"
    with pytest.raises(CalibrationError, match="describes one camera; give both cameras'"):
        rig.read_rig([sensor])
    from vsmatch.geometry import read_calibration

    (tmp_path / "other.json").write_text('{"a": 1}')
    with pytest.raises(CalibrationError, match="nor a raw rig \\(OpenCV stereoCalibrate"):
        read_calibration(tmp_path / "other.json")


@pytest.mark.parametrize("kind", ["opencv", "kalibr", "ros"])
def test_each_rig_reader_gives_the_rectified_camera_in_its_own_unit(tmp_path, kind):
    """Each reader's rectified camera, value by value (not the baseline alone): f 300 px and
    the principal point (80, 48) of these rigs, doffs 0 (same cameras, no rotation), the
    baseline in the file's unit (OpenCV's T in mm, Kalibr's and ROS's in m), so a disparity
    of 6 px lies 3000 mm or 3 m away."""
    from vsmatch import geometry

    if kind == "opencv":
        paths, unit_baseline = [write_opencv_rig(tmp_path / "rig.yaml")], 60.0
    elif kind == "kalibr":
        (tmp_path / "camchain.yaml").write_text(yaml.safe_dump(kalibr_rig()))
        paths, unit_baseline = [tmp_path / "camchain.yaml"], 0.06
    else:
        paths, unit_baseline = ros_pair(tmp_path), 0.06
    camera = rig.Rectifier(rig.read_rig(paths), (WIDTH, HEIGHT)).calibration()
    assert camera.focal == pytest.approx(300, abs=1e-3)
    assert camera.focal_y == pytest.approx(300, abs=1e-3)
    assert (camera.cx, camera.cy) == pytest.approx((80, 48), abs=1e-3)
    assert camera.doffs == pytest.approx(0, abs=1e-6)
    assert camera.baseline == pytest.approx(unit_baseline, rel=1e-9)
    depth = geometry.depth_from_disparity(np.full((2, 2), 6.0, np.float32), camera)
    assert depth == pytest.approx(np.full((2, 2), 300 * unit_baseline / 6), rel=1e-6)


def test_alpha_keeps_more_of_a_distorted_view_at_a_smaller_focal_length(tmp_path):
    """--alpha 1 keeps every source pixel of a barrel-distorted view: a smaller focal
    length than alpha 0 (which crops to valid pixels), the same baseline."""
    barrel = np.array([[-0.3, 0.1, 0, 0, 0]])
    raw = rig.read_rig([write_opencv_rig(tmp_path / "rig.yaml", D1=barrel, D2=barrel)])
    cropped = rig.Rectifier(raw, (WIDTH, HEIGHT), 0.0).calibration()
    whole = rig.Rectifier(raw, (WIDTH, HEIGHT), 1.0).calibration()
    assert whole.focal < cropped.focal < 300.5
    assert whole.baseline == pytest.approx(cropped.baseline)


def test_a_rig_whose_cameras_are_swapped_is_named(tmp_path):
    """T pointing the other way (the left camera's file given as the right's): after
    rectifying, the right camera lies left of the left one; said, not matched."""
    raw = rig.read_rig([write_opencv_rig(tmp_path / "rig.yaml", T=np.array([[60.0], [0], [0]]))])
    with pytest.raises(CalibrationError, match="are the cameras swapped"):
        rig.Rectifier(raw, (WIDTH, HEIGHT)).calibration()
