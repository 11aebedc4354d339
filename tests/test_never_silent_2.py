"""Never silent, round 2 (issue 26): the newer commands (video, rectify, raw-rig
calibrations, eval's outputs, batch at scale, signals) never overwrite an input, never
accept an impossible rig, never leave a partial output, and say what is wrong in one line.
Each test names the item of the issue it checks."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from vsmatch import batch, io, pipeline, preview, rig
from vsmatch.cli import main
from vsmatch.cli import common
from vsmatch.geometry import CalibrationError

from conftest import random_pair
from test_video import frame_count

WIDTH, HEIGHT = 160, 96
K = np.array([[300.0, 0, 80], [0, 300, 48], [0, 0, 1]])


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def one_line_error(result, code=1):
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output and "unexpected" not in result.output
    # Without the progress bar's leftovers (carriage returns and blanks).
    lines = [line for line in result.output.splitlines()
             if line.strip() and "frame/s" not in line and "frame [" not in line]
    assert len(lines) == 1, result.output
    return lines[0]


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


def snapshot(folder):
    return {p.name: p.read_bytes() for p in sorted(Path(folder).iterdir()) if p.is_file()}


def write_videos(folder, rng, frames=(4, 4), name="v"):
    left, right = smooth_pair(rng)
    fourcc = cv2.VideoWriter_fourcc(*"MJPG")
    paths = []
    for side, count, view in (("l", frames[0], left), ("r", frames[1], right)):
        path = folder / f"{name}_{side}.avi"
        writer = cv2.VideoWriter(str(path), fourcc, 10, (WIDTH, HEIGHT))
        for _ in range(count):
            writer.write(view)
        writer.release()
        paths.append(path)
    return paths


# --- 1-3. outputs over inputs -----------------------------------------------------------

def test_1_video_refuses_an_output_over_an_input_or_its_link(tmp_path, rng):
    left, right = write_videos(tmp_path, rng)
    before = left.read_bytes()
    line = one_line_error(invoke("video", left, right, "-o", left, "--max-disp", 16))
    assert "would overwrite the input" in line
    (tmp_path / "link.avi").symlink_to(right)
    line = one_line_error(invoke("video", left, right, "-o", tmp_path / "link.avi",
                                 "--max-disp", 16))
    assert "would overwrite the input" in line
    assert left.read_bytes() == before and (tmp_path / "link.avi").is_symlink()


def test_2_rectified_views_never_overwrite_the_inputs(tmp_path, rng):
    views = write_pair(tmp_path, rng, names=("im0.png", "im1.png"))
    calib = write_opencv_rig(tmp_path / "rig.yaml")
    (tmp_path / "calib.txt").write_text("cam0=[1 0 0; 0 1 0; 0 0 1]\nbaseline=1\n")
    before = snapshot(tmp_path)
    line = one_line_error(invoke("run", *views, "--calib", calib, "--rectified", tmp_path,
                                 "-o", tmp_path / "d.pfm", "--max-disp", 16))
    assert "would overwrite the input" in line and "im0.png" in line
    line = one_line_error(invoke("rectify", *views, "--calib", calib, "--to", tmp_path))
    assert "would overwrite the input" in line
    assert snapshot(tmp_path) == before


def fake_dataset(root):
    scene = root / "middlebury2" / "tsukuba"
    scene.mkdir(parents=True)
    for name in ("imL.png", "imR.png", "groundtruth.png"):
        (scene / name).write_bytes(b"data")
    return scene


def test_3_eval_and_bench_write_nothing_into_the_data_set(tmp_path):
    scene = fake_dataset(tmp_path)
    for option, target in (("--json", scene / "imL.png"),
                           ("--figure", scene / "groundtruth.png"),
                           ("--out-dir", scene)):
        line = one_line_error(invoke("eval", "--data-root", tmp_path, "--dataset",
                                     "middlebury2", "--method", "census", option, target))
        assert "into the data set" in line
    line = one_line_error(invoke("bench", "--data-root", tmp_path, "--json",
                                 scene / "imR.png"))
    assert "into the data set" in line
    assert all(p.read_bytes() == b"data" for p in scene.iterdir())


# --- 4-8. partial or corrupt outputs -------------------------------------------------------

def test_4_rectified_views_are_written_with_the_run_or_not_at_all(tmp_path, rng):
    views = write_pair(tmp_path, rng)
    calib = write_opencv_rig(tmp_path / "rig.yaml")
    result = invoke("run", *views, "--calib", calib, "--rectified", tmp_path / "out", "-o",
                    tmp_path / "d.pfm", "--max-disp", 800)
    assert result.exit_code != 0 and "Traceback" not in result.output
    assert not (tmp_path / "out").exists() or not list((tmp_path / "out").iterdir())
    assert not (tmp_path / "d.pfm").exists()
    result = invoke("run", *views, "--calib", calib, "--rectified", tmp_path / "out", "-o",
                    tmp_path / "d.pfm", "--max-disp", 16)
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["calib.txt", "im0.png",
                                                                      "im1.png"]
    assert "ndisp=17" in (tmp_path / "out" / "calib.txt").read_text()


class DroppingWriter:
    """cv2.VideoWriter that, like one on a full disk, stops writing after two frames."""

    real = cv2.VideoWriter

    def __init__(self, *args):
        self.inner, self.count = self.real(*args), 0

    def isOpened(self):
        return self.inner.isOpened()

    def write(self, frame):
        self.count += 1
        if self.count <= 2:
            self.inner.write(frame)

    def release(self):
        self.inner.release()


def test_5_a_video_the_writer_could_not_finish_is_an_error(tmp_path, rng, monkeypatch):
    from vsmatch.cli import video

    left, right = write_videos(tmp_path, rng)
    monkeypatch.setattr(video.cv2, "VideoWriter", DroppingWriter)
    line = one_line_error(invoke("video", left, right, "-o", tmp_path / "d.avi",
                                 "--max-disp", 16))
    assert "d.avi" in line and "holds 2 of 4 frames" in line
    assert not [p for p in tmp_path.iterdir() if p.name.startswith((".d", "d."))]


def test_5_a_video_onto_a_full_disk_fails_in_one_line(tmp_path, rng):
    disk = tmp_path / "disk"
    disk.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=600k", "tmpfs", str(disk)],
                      capture_output=True).returncode != 0:
        pytest.skip("cannot mount a small tmpfs here")
    try:
        left, right = write_videos(tmp_path, rng, frames=(40, 40))
        noisy = rng.integers(0, 256, (HEIGHT, WIDTH, 3), np.uint8)  # large MJPG frames
        cv2.imwrite(str(tmp_path / "noise.png"), noisy)
        result = invoke("video", left, right, "-o", disk / "v.avi", "--max-disp", 16,
                        "--config", "fast")
        if result.exit_code == 0:  # 40 disparity frames fit: fill the disk first
            size = (disk / "v.avi").stat().st_size
            (disk / "v.avi").unlink()
            (disk / "filler").write_bytes(b"\1" * (disk_free(disk) - size // 2))
            result = invoke("video", left, right, "-o", disk / "v.avi", "--max-disp", 16,
                            "--config", "fast")
        line = one_line_error(result)
        assert "v.avi" in line and "could not be written" in line
        assert not (disk / "v.avi").exists()
        assert [p.name for p in disk.iterdir()] in ([], ["filler"])
    finally:
        subprocess.run(["umount", str(disk)], capture_output=True)


def disk_free(folder):
    stats = os.statvfs(folder)
    return stats.f_bavail * stats.f_frsize


def test_6_a_video_leaves_another_runs_temporary_alone(tmp_path, rng):
    left, right = write_videos(tmp_path, rng)
    other = tmp_path / ".d.partial.avi"  # the name every run used to write to
    other.write_bytes(b"another run's frames")
    result = invoke("video", left, right, "-o", tmp_path / "d.avi", "--max-disp", 16)
    assert result.exit_code == 0, result.output
    assert other.read_bytes() == b"another run's frames"
    assert frame_count(tmp_path / "d.avi") == 4


SIGTERM_AT_FIRST_RENAME = """
import os, signal, sys
real = os.replace
def replace(src, dst):
    result = real(src, dst)
    if str(dst).endswith(".pfm") and not getattr(replace, "sent", False):
        replace.sent = True  # after the first output is in place, before the others
        os.kill(os.getpid(), signal.SIGTERM)
    return result
os.replace = replace
from vsmatch.cli import main
main(sys.argv[1:])
"""


def test_7_sigterm_during_the_renames_leaves_every_output_or_none(tmp_path, rng):
    views = write_pair(tmp_path, rng)
    outputs = {"-o": "d.pfm", "--depth": "z.pfm", "--confidence": "c.pfm",
               "--preview": "p.png", "--cloud": "x.ply"}
    args = [str(v) for v in views] + ["--max-disp", "16", "--focal", "300", "--baseline", "60"]
    for option, name in outputs.items():
        args += [option, str(tmp_path / name)]
    proc = subprocess.run([sys.executable, "-c", SIGTERM_AT_FIRST_RENAME, "run", *args],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 143, proc.stderr
    written = [name for name in outputs.values() if (tmp_path / name).exists()]
    assert written in ([], list(outputs.values())), written
    assert not [p for p in tmp_path.iterdir() if ".tmp" in p.name]


def test_8_frames_folder_is_refused_when_full_and_replaced_whole(tmp_path, rng):
    left, right = write_videos(tmp_path, rng)
    frames = tmp_path / "frames"
    frames.mkdir()
    for k in range(40):
        (frames / f"{k:06d}.pfm").write_bytes(b"old")
    line = one_line_error(invoke("video", left, right, "-o", tmp_path / "d.avi", "--frames",
                                 frames, "--max-disp", 16))
    assert "frames" in line and "--overwrite" in line
    assert not (tmp_path / "d.avi").exists() and len(list(frames.iterdir())) == 40
    result = invoke("video", left, right, "-o", tmp_path / "d.avi", "--frames", frames,
                    "--max-disp", 16, "--overwrite")
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in frames.iterdir()) == [
        f"{k:06d}{suffix}.pfm" for k in range(4) for suffix in ("", "_confidence")]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".frames")]


def test_8_frames_folder_may_not_hold_the_inputs(tmp_path, rng):
    left, right = write_videos(tmp_path, rng)
    line = one_line_error(invoke("video", left, right, "-o", tmp_path / "out" / "d.avi",
                                 "--frames", tmp_path, "--overwrite", "--max-disp", 16),
                          code=1)
    assert "--frames folder" in line or "does not exist" in line
    assert left.exists() and right.exists()


# --- 9-10. bombs and scale -------------------------------------------------------------------

ALIAS_BOMB = """cam0:
  camera_model: pinhole
  intrinsics: [300, 300, 80, 48]
  distortion_model: radtan
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [160, 96]
cam1:
  camera_model: pinhole
  intrinsics: [300, 300, 80, 48]
  distortion_model: radtan
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [160, 96]
  a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1]
  b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a]
  c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b]
  d: &d [*c, *c, *c, *c, *c, *c, *c, *c, *c]
  e: &e [*d, *d, *d, *d, *d, *d, *d, *d, *d]
  f: &f [*e, *e, *e, *e, *e, *e, *e, *e, *e]
  g: &g [*f, *f, *f, *f, *f, *f, *f, *f, *f]
  h: &h [*g, *g, *g, *g, *g, *g, *g, *g, *g]
  T_cn_cnm1: [*h, *h, *h, *h]
"""


def test_9_yaml_alias_bombs_in_calibrations_are_refused_at_once(tmp_path):
    (tmp_path / "camchain.yaml").write_text(ALIAS_BOMB)
    start = time.perf_counter()
    with pytest.raises(CalibrationError, match="more YAML nodes than a calibration holds"):
        rig.read_rig([tmp_path / "camchain.yaml"])
    assert time.perf_counter() - start < 5  # was 42 s and 7.7 GB
    left, right = ros_pair(tmp_path)
    bomb = ALIAS_BOMB[ALIAS_BOMB.index("  a: &a"):].replace("  T_cn_cnm1", "  z")
    right.write_text(right.read_text() + "bomb:\n" + bomb)
    with pytest.raises(CalibrationError, match="more YAML nodes"):
        rig.read_rig([left, right])


def test_9_a_few_plain_aliases_are_still_read(tmp_path):
    """PyYAML writes a list shared by both cameras once, with an alias."""
    text = yaml.safe_dump(kalibr_rig())
    assert "*id001" in text
    (tmp_path / "camchain.yaml").write_text(text)
    assert rig.read_rig([tmp_path / "camchain.yaml"]).size == (WIDTH, HEIGHT)


def test_10_batch_plan_check_is_linear(tmp_path, monkeypatch):
    rows = 300
    jobs = [batch.PairJob(tmp_path / f"l{k}.png", tmp_path / f"r{k}.png",
                          tmp_path / f"d{k}.pfm", 8, f"line {k}") for k in range(rows)]
    calls = []
    monkeypatch.setattr(batch.io, "same_file", lambda a, b: calls.append(1) or False)
    original = batch._file_key
    monkeypatch.setattr(batch, "_file_key", lambda p: calls.append(1) or original(p))
    batch.check_plan(jobs)
    assert len(calls) <= 3 * rows  # quadratic: 90 000


def test_10_ten_thousand_missing_rows_are_checked_in_seconds(tmp_path):
    lines = [f"l{k}.png,r{k}.png,d{k}.pfm,8" for k in range(10_000)]
    (tmp_path / "p.csv").write_text("\n".join(lines) + "\n")
    lines[9_999] = "l9999.png,r9999.png,l0.png,8"
    (tmp_path / "bad.csv").write_text("\n".join(lines) + "\n")
    line = one_line_error(invoke("batch", tmp_path / "bad.csv"))
    assert "line 10000" in line and "would overwrite the input" in line


# --- 11-16. accepted but wrong -----------------------------------------------------------------

@pytest.mark.parametrize("changes,key", [
    (dict(R=np.zeros((3, 3))), "R is not a rotation"),
    (dict(R=np.diag([1.0, 1, -1])), "R is not a rotation"),
    (dict(T=np.array([[-1e300], [0], [0]])), "overflow float32"),
    (dict(T=np.array([[0.0], [-60], [0]])), "not mostly along x"),
    (dict(K2=np.zeros((3, 3))), "K2 has focal lengths"),
    (dict(K1=np.array([[300.0, 0, 900], [0, 300, 48], [0, 0, 1]])), "outside the"),
])
def test_11_impossible_opencv_rigs_are_refused_naming_the_key(tmp_path, rng, changes, key):
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
def test_11_impossible_ros_pairs_are_refused_naming_the_key(tmp_path, side, changes, key):
    left, right = ros_pair(tmp_path, **{f"{side}_changes": changes})
    with pytest.raises(CalibrationError) as caught:
        rig.read_rig([left, right])
    assert key in str(caught.value) and f"{side}.yaml" in str(caught.value)


def test_12_hand_values_with_a_raw_rig_are_refused(tmp_path, rng):
    views = write_pair(tmp_path, rng)
    calib = write_opencv_rig(tmp_path / "rig.yaml")
    line = one_line_error(invoke("run", *views, "--calib", calib, "--focal", 500,
                                 "--baseline", 1, "-o", tmp_path / "d.pfm"), code=2)
    assert "--calib or --focal, --baseline" in line


def test_13_depths_float32_cannot_hold_are_refused_before_matching(tmp_path, rng,
                                                                   monkeypatch):
    views = write_pair(tmp_path, rng)
    monkeypatch.setattr(pipeline, "run", lambda *a, **k: pytest.fail("matched anyway"))
    line = one_line_error(invoke("run", *views, "--focal", 1e20, "--baseline", 1e20,
                                 "--depth", tmp_path / "z.pfm", "-o", tmp_path / "d.pfm",
                                 "--max-disp", 16))
    assert "float32" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["l.png", "r.png"]


@pytest.mark.parametrize("command", ["run", "rectify"])
def test_14_alpha_nan_is_refused(tmp_path, rng, command):
    views = write_pair(tmp_path, rng)
    calib = write_opencv_rig(tmp_path / "rig.yaml")
    out = ["-o", tmp_path / "d.pfm"] if command == "run" else ["--to", tmp_path / "r"]
    line = one_line_error(invoke(command, *views, "--calib", calib, "--alpha", "nan", *out),
                          code=2)
    assert "--alpha" in line and "finite" in line


def test_15_unpaired_video_frames_fail_with_both_counts(tmp_path, rng):
    left, right = write_videos(tmp_path, rng, frames=(6, 3))
    result = invoke("video", left, right, "-o", tmp_path / "d.avi", "--max-disp", 16)
    assert result.exit_code == 1
    assert "has 6 frames" in result.output and "3:" in result.output
    assert "3 frames without a partner" in result.output
    assert frame_count(tmp_path / "d.avi") == 3
    left, right = write_videos(tmp_path, rng, frames=(2, 5), name="w")
    result = invoke("video", left, right, "-o", tmp_path / "e.avi", "--max-disp", 16)
    assert result.exit_code == 1 and "3 frames without a partner" in result.output
    result = invoke("video", left, right, "-o", tmp_path / "f.avi", "--max-disp", 16,
                    "--max-frames", 2)
    assert result.exit_code == 0, result.output


@pytest.mark.parametrize("changes,message", [
    ({"distortion_model": "equidistant"}, "cam1's distortion_model"),
    ({"resolution": [WIDTH + 2, HEIGHT]}, "cam1's resolution"),
    ({"resolution": [WIDTH, HEIGHT, 3]}, "[width, height]"),
])
def test_16_kalibr_cam1_fields_are_read(tmp_path, changes, message):
    (tmp_path / "camchain.yaml").write_text(yaml.safe_dump(kalibr_rig(**changes)))
    with pytest.raises(CalibrationError) as caught:
        rig.read_rig([tmp_path / "camchain.yaml"])
    assert message in str(caught.value)


def test_16_a_calib_txt_for_other_views_is_refused(tmp_path, rng):
    views = write_pair(tmp_path, rng)
    (tmp_path / "calib.txt").write_text(
        "cam0=[300 0 80; 0 300 48; 0 0 1]\ncam1=[300 0 80; 0 300 48; 0 0 1]\ndoffs=0\n"
        f"baseline=60\nwidth={WIDTH * 2}\nheight={HEIGHT}\nndisp=17\n")
    line = one_line_error(invoke("run", *views, "--calib", tmp_path / "calib.txt", "-o",
                                 tmp_path / "d.pfm"))
    assert "calib.txt" in line and f"{WIDTH * 2}x{HEIGHT}" in line
    assert not (tmp_path / "d.pfm").exists()


# --- 17-20. messages that are one clear line ---------------------------------------------------

def opencv_text(**replace):
    """An OpenCV YAML rig as text, with keys' values replaced verbatim."""
    lines = {"K1": "!!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [300., 0., 80., "
                   "0., 300., 48., 0., 0., 1.]",
             "K2": "!!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [300., 0., 80., "
                   "0., 300., 48., 0., 0., 1.]",
             "D1": "!!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [0., 0., 0., 0., 0.]",
             "D2": "!!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [0., 0., 0., 0., 0.]",
             "R": "!!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [1., 0., 0., 0., 1., "
                  "0., 0., 0., 1.]",
             "T": "!!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [-60., 0., 0.]",
             "image_width": str(WIDTH), "image_height": str(HEIGHT)}
    lines.update(replace)
    return "%YAML:1.0\n---\n" + "".join(f"{k}: {v}\n" for k, v in lines.items() if v is not None)


def coefficients(n):
    return (f"!!opencv-matrix\n   rows: 1\n   cols: {n}\n   dt: d\n   data: "
            f"[{', '.join(['0.'] * n)}]")


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
def test_17_bad_opencv_fields_are_one_line_naming_the_key(tmp_path, rng, replace, key):
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
def test_17_broken_filestorage_files_are_one_line(tmp_path, rng, text):
    views = write_pair(tmp_path, rng)
    (tmp_path / "rig.yaml").write_text(text)
    line = one_line_error(invoke("run", *views, "--calib", tmp_path / "rig.yaml", "-o",
                                 tmp_path / "d.pfm", "--max-disp", 16))
    assert "rig.yaml" in line and "SystemError" not in line


@pytest.mark.parametrize("coeffs", [[], [0.1, 0.2]])
def test_17_a_fisheye_without_four_coefficients_is_named(tmp_path, coeffs):
    data = kalibr_rig()
    for cam in ("cam0", "cam1"):
        data[cam].update(distortion_model="equidistant", distortion_coeffs=coeffs)
    (tmp_path / "camchain.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(CalibrationError, match="cam0.distortion_coeffs has"):
        rig.read_rig([tmp_path / "camchain.yaml"])


def test_18_grey_with_colour_is_named_as_such(rng):
    left, right = random_pair(rng, height=40, width=64)
    with pytest.raises(ValueError, match="grey .* colour"):
        pipeline.match(cv2.cvtColor(left, cv2.COLOR_BGR2GRAY), right, max_disp=8)


def test_19_a_nul_in_a_csv_cell_names_the_line(tmp_path):
    (tmp_path / "p.csv").write_text("a.png,b.png,c.pfm\na\0.png,b.png,d.pfm\n")
    line = one_line_error(invoke("batch", tmp_path / "p.csv"))
    assert "line 2" in line and "NUL" in line


def test_19_an_output_that_is_a_folder_is_refused_before_matching(tmp_path, rng,
                                                                  monkeypatch):
    views = write_pair(tmp_path, rng)
    (tmp_path / "d.pfm").mkdir()
    monkeypatch.setattr(pipeline, "run", lambda *a, **k: pytest.fail("matched anyway"))
    line = one_line_error(invoke("run", *views, "-o", tmp_path / "d.pfm", "--max-disp", 16))
    assert "d.pfm: is a folder" in line and ".tmp" not in line


def test_19_an_unwritable_folder_is_named_not_a_temporary(tmp_path, rng, monkeypatch):
    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied", str(tmp_path / ".im0.xyz.tmp.png"))
    monkeypatch.setattr(io.tempfile, "mkstemp", refuse)
    with pytest.raises(OSError) as caught:
        io.imwrite_atomic(tmp_path / "im0.png", np.zeros((4, 4), np.uint8))
    assert str(caught.value).startswith(f"{tmp_path / 'im0.png'}: could not be written")
    assert ".tmp" not in str(caught.value)


def test_19_a_text_file_named_mp4_is_one_line_on_the_real_stderr(tmp_path):
    (tmp_path / "l.mp4").write_text("not a video\n")
    (tmp_path / "r.mp4").write_text("not a video\n")
    proc = subprocess.run([sys.executable, "-m", "vsmatch", "video", tmp_path / "l.mp4",
                           tmp_path / "r.mp4", "-o", tmp_path / "d.avi"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1
    assert proc.stderr.strip().splitlines() == [f"Error: {tmp_path / 'l.mp4'}: cannot open "
                                                "this video"]


def test_20_a_second_sigterm_is_ignored_while_the_first_unwinds(monkeypatch):
    monkeypatch.setattr(signal, "signal", lambda *a: calls.append(a))
    calls = []
    with pytest.raises(common.Terminated):
        common.on_sigterm(signal.SIGTERM, None)
    assert calls == [(signal.SIGTERM, common.ignore_signal), (signal.SIGTERM, signal.SIG_IGN)]
    assert common.ignore_signal(signal.SIGTERM, None) is None  # a callable: no race OSError


def test_20_two_sigterms_in_a_row_give_one_line(tmp_path, rng):
    left, right = smooth_pair(rng, height=900, width=1400)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    proc = subprocess.Popen([sys.executable, "-m", "vsmatch", "-v", "run", tmp_path / "l.png",
                             tmp_path / "r.png", "-o", tmp_path / "d.pfm", "--max-disp", "96"],
                            stderr=subprocess.PIPE, text=True)
    lines = []
    for line in proc.stderr:  # until the matching starts
        lines.append(line)
        if line.startswith("searching disparities"):
            break
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    time.sleep(0.001)
    proc.send_signal(signal.SIGTERM)
    err = "".join(lines) + proc.communicate(timeout=120)[1]
    assert proc.returncode == 143, err
    assert "Traceback" not in err and "Exception ignored" not in err
    assert err.strip().splitlines()[-1] == "vsmatch: terminated"
    assert not (tmp_path / "d.pfm").exists()


def test_20_a_late_second_sigterm_neither_kills_nor_prints(tmp_path, rng):
    """The second SIGTERM 0-1.5 ms after the first, at several points of the match: exit
    143 with one line each time (a do-nothing Python handler alone let Python's shutdown
    restore the default action, and a late signal killed the process: 1 run in 3)."""
    left, right = smooth_pair(rng, height=400, width=600)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    for attempt in range(8):
        proc = subprocess.Popen([sys.executable, "-m", "vsmatch", "-v", "run",
                                 tmp_path / "l.png", tmp_path / "r.png", "-o",
                                 tmp_path / "d.pfm", "--max-disp", "48"],
                                stderr=subprocess.PIPE, text=True)
        for line in proc.stderr:
            if line.startswith("searching disparities"):
                break
        time.sleep(0.05 * (attempt % 4))
        proc.send_signal(signal.SIGTERM)
        time.sleep(0.0005 * (attempt % 4))
        proc.send_signal(signal.SIGTERM)
        err = proc.communicate(timeout=120)[1]
        assert proc.returncode == 143, (attempt, proc.returncode, err)
        assert "Traceback" not in err, err


# --- 21-22. a newcomer's trial ---------------------------------------------------------------

def test_21_demo_announces_the_first_compilation(tmp_path, monkeypatch):
    from vsmatch import _kernels

    monkeypatch.setattr(_kernels, "cache_is_cold", lambda: True)
    result = invoke("demo", "-o", tmp_path / "demo")
    assert result.exit_code == 0 and "compiling the kernels once" in result.output


def test_22_preview_spans_the_disparities_present_with_a_bar_and_dims_the_unsure():
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


def test_18_a_swapped_raw_pair_is_not_told_to_rectify(data_dir, tmp_path):
    """Rows that disagree after vsmatch rectified the views itself: the views are swapped
    or the calibration is another rig's, not "rectify it first"."""
    rig_dir = data_dir / "real-cameras" / "ukulele-raw"
    line = one_line_error(invoke("run", rig_dir / "right.png", rig_dir / "left.png",
                                 "--calib", rig_dir / "rig.yml", "-o", tmp_path / "d.pfm"))
    assert "are the views swapped" in line and "rectify it first" not in line


def test_22_run_writes_the_preview_with_its_colour_bar(tmp_path, rng):
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
