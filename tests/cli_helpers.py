"""Helpers of the tests that check vsmatch refuses bad input and never loses an output:
a CLI runner, the one-line error, small pairs, rigs and videos written for a test."""

import cv2
import numpy as np
import yaml
from click.testing import CliRunner

from vsmatch.cli import main


def invoke(*args, env=None):
    return CliRunner().invoke(main, [str(a) for a in args], env=env)


def one_line_error(result, code=1, unexpected=False):
    """The one line a refused run prints (besides a progress bar's leftovers); with
    ``unexpected`` False, not vsmatch's report of an error it did not foresee."""
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output
    if not unexpected:
        assert "unexpected" not in result.output, result.output
    lines = [line for line in result.output.splitlines()
             if line.strip() and "frame/s" not in line and "frame [" not in line]
    assert len(lines) == 1, result.output
    return lines[0]


def files_in(folder):
    return sorted(p.name for p in folder.iterdir())


def smooth_texture(rng, height, width):
    """A smooth random texture (SIFT finds corners in it)."""
    base = rng.integers(0, 256, size=(height // 4 + 1, width // 4 + 1, 3), dtype=np.uint8)
    return cv2.resize(base, (width // 4 * 4 + 4, height // 4 * 4 + 4),
                      interpolation=cv2.INTER_CUBIC)[:height, :width]


def shifted_pair(rng, dx, dy=0, height=120, width=240):
    """Left pixel (x, y) shows what right pixel (x - dx, y - dy) shows."""
    wide = smooth_texture(rng, height + 2 * abs(dy), width + 2 * abs(dx))
    x0, y0 = abs(dx), abs(dy)
    left = wide[y0:y0 + height, x0:x0 + width]
    right = wide[y0 + dy:y0 + dy + height, x0 + dx:x0 + dx + width]
    return np.ascontiguousarray(left), np.ascontiguousarray(right)


WIDTH, HEIGHT = 160, 96


K = np.array([[300.0, 0, 80], [0, 300, 48], [0, 0, 1]])


def smooth_pair(rng, shift=6, height=HEIGHT, width=WIDTH):
    """Texture smooth enough to match, left x showing right x - shift."""
    base = rng.integers(0, 256, (height // 4 + 1, (width + shift) // 4 + 2, 3), np.uint8)
    wide = cv2.resize(base, (base.shape[1] * 4, base.shape[0] * 4),
                      interpolation=cv2.INTER_CUBIC)[:height]
    return (np.ascontiguousarray(wide[:, :width]),
            np.ascontiguousarray(wide[:, shift:shift + width]))


def write_pair(folder, rng, names=("l.png", "r.png")):
    left, right = smooth_pair(rng)
    for name, view in zip(names, (left, right)):
        cv2.imwrite(str(folder / name), view)
    return [folder / n for n in names]


def write_opencv_rig(path, **changes):
    """An OpenCV stereoCalibrate file of a side-by-side rig (60 mm, no distortion)."""
    m = dict(K1=K, K2=K, D1=np.zeros((1, 5)), D2=np.zeros((1, 5)), R=np.eye(3),
             T=np.array([[-60.0], [0], [0]]))
    m.update(changes)
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    for key, value in m.items():
        fs.write(key, np.asarray(value, dtype=np.float64))
    fs.write("image_width", WIDTH)
    fs.write("image_height", HEIGHT)
    fs.release()
    return path


def kalibr_rig(**cam1_changes):
    cam = {"camera_model": "pinhole", "intrinsics": [300.0, 300.0, 80.0, 48.0],
           "distortion_model": "radtan", "distortion_coeffs": [0.0, 0.0, 0.0, 0.0],
           "resolution": [WIDTH, HEIGHT]}
    pose = np.eye(4)
    pose[0, 3] = -0.06
    cam1 = {**cam, "T_cn_cnm1": pose.tolist(), **cam1_changes}
    return {"cam0": dict(cam), "cam1": cam1}


def ros_pair(folder, right_changes=None, left_changes=None):
    paths = []
    for name, tx, changes in (("left", 0.0, left_changes), ("right", -300 * 0.06,
                                                              right_changes)):
        data = {"image_width": WIDTH, "image_height": HEIGHT, "distortion_model": "plumb_bob",
                "camera_matrix": {"rows": 3, "cols": 3, "data": K.ravel().tolist()},
                "distortion_coefficients": {"rows": 1, "cols": 5, "data": [0.0] * 5},
                "rectification_matrix": {"rows": 3, "cols": 3,
                                         "data": np.eye(3).ravel().tolist()},
                "projection_matrix": {"rows": 3, "cols": 4,
                                      "data": [300.0, 0, 80, tx, 0, 300, 48, 0, 0, 0, 1, 0]}}
        data.update(changes or {})
        path = folder / f"{name}.yaml"
        path.write_text(yaml.safe_dump(data))
        paths.append(path)
    return paths


def verged_pair(rng):
    """Disparities -12 in the top half, +10 in the bottom half (a verged rig's mix)."""
    top, bottom = shifted_pair(rng, -12, height=80), shifted_pair(rng, 10, height=80)
    return np.vstack([top[0], bottom[0]]), np.vstack([top[1], bottom[1]])
