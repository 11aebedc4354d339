"""Frames as cameras write them (issue 44): folders in time order, one image per moment,
EuRoC as it ships, files that are not frames and frames cut short skipped with a word, a
dark first frame, and what a camera user sees (the bar, the dimmed pixels, the scale)."""

import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from conftest import random_pair
from vsmatch import frames, io, preview
from vsmatch.cli import main


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def write_folders(tmp_path, rng, names, shift=4, size=(96, 48)):
    """left/ and right/ holding one textured pair under each name; the pairs differ (the
    scene drifts a pixel a frame), so that their order can be read back."""
    width, height = size
    wide, _ = random_pair(rng, height=height, width=width + shift + len(names) + 8, shift=0)
    wide = cv2.GaussianBlur(wide, (3, 3), 0)
    for side in ("left", "right"):
        (tmp_path / side).mkdir(exist_ok=True)
    for k, name in enumerate(names):
        left = wide[:, k:k + width]
        right = wide[:, k + shift:k + shift + width]
        cv2.imwrite(str(tmp_path / "left" / name), left)
        cv2.imwrite(str(tmp_path / "right" / name), right)
    return tmp_path / "left", tmp_path / "right"


def test_frames_are_ordered_by_the_number_in_their_name(tmp_path, rng):
    """1.png ... 12.png were taken as 1, 10, 11, 12, 2, ...; time stamps of different
    digit counts out of time order."""
    names = [f"{k}.png" for k in range(1, 13)]
    left, _ = write_folders(tmp_path, rng, names)
    pairs = frames.FolderPairs(str(left), str(tmp_path / "right"))
    assert [p.name for p, _ in pairs.paths] == names
    assert frames.frame_key("999999999.png") < frames.frame_key("1000000000.png")
    assert frames.frame_key("frame_2.png") < frames.frame_key("frame_10.png")


def test_two_images_of_one_moment_are_refused_naming_both(tmp_path, rng):
    left, right = write_folders(tmp_path, rng, ["0001.png", "0002.png"])
    shutil.copy(left / "0002.png", left / "0002.jpg")
    result = invoke("video", left, right, "-o", tmp_path / "d.avi", "--max-disp", 8)
    assert result.exit_code == 1
    assert "0002.png" in result.output and "0002.jpg" in result.output
    assert "one moment" in result.output and not (tmp_path / "d.avi").exists()


def test_files_that_are_not_frames_and_frames_cut_short_are_skipped_with_a_word(
        tmp_path, rng):
    names = [f"{k:04d}.png" for k in range(4)]
    left, right = write_folders(tmp_path, rng, names)
    (left / "._0001.png").write_bytes(b"\x00\x05\x16\x07AppleDouble")
    (left / ".DS_Store").write_bytes(b"\x00\x00\x00\x01Bud1")
    (left / "sensor.yaml").write_text("%YAML:1.0\n")  # a companion: not worth a word
    data = (right / "0002.png").read_bytes()
    (right / "0002.png").write_bytes(data[:len(data) // 2])  # the camera stopped mid-write
    result = invoke("video", left, right, "-o", tmp_path / "d.avi", "--max-disp", 8,
                    "--frames", tmp_path / "fr")
    assert result.exit_code == 0, result.output
    assert "wrote" in result.output and "3 frames" in result.output
    warnings = [line for line in result.output.splitlines() if line.startswith("warning")]
    assert len(warnings) == 2, result.output
    assert "2 files that are not images" in warnings[0] and "._0001.png" in warnings[0]
    assert "sensor.yaml" not in result.output
    assert "0002.png" in warnings[1] and "skipped a frame" in warnings[1]
    assert sorted(p.name for p in (tmp_path / "fr").glob("*_confidence.pfm")) == [
        f"{k:06d}_confidence.pfm" for k in range(3)]


def test_left_and_right_paired_by_the_nearest_time_stamp(tmp_path, rng):
    """Two cameras' clocks seldom stamp one moment alike: nanosecond stamps a few
    microseconds apart pair; one a whole frame apart does not."""
    start, step = 1403715273262142976, 50_000_000
    names = [f"{start + k * step}.png" for k in range(4)]
    left, right = write_folders(tmp_path, rng, names)
    for k, name in enumerate(names):
        (right / name).rename(right / f"{start + k * step + 3_000 * (k + 1)}.png")
    pairs = frames.FolderPairs(str(left), str(right))
    assert len(pairs.paths) == 4 and pairs.unpaired() is None
    assert pairs.fps() == pytest.approx(20)
    (right / f"{start + 3 * step + 12_000}.png").rename(right / f"{start + 5 * step}.png")
    pairs = frames.FolderPairs(str(left), str(right))
    assert len(pairs.paths) == 3 and "2 frames without a partner" in pairs.unpaired()


def euroc_as_it_ships(clip: Path, to: Path, count: int) -> Path:
    """``mav0/cam0`` and ``mav0/cam1`` as EuRoC ships them: data/ (frames named by time
    stamp), data.csv (the index) and sensor.yaml, from the clip's flattened copy."""
    for camera in ("cam0", "cam1"):
        folder = to / "mav0" / camera
        (folder / "data").mkdir(parents=True)
        shutil.copy(clip / camera / "sensor.yaml", folder / "sensor.yaml")
        lines = ["#timestamp [ns],filename"]
        for frame in sorted((clip / camera).glob("*.png"))[:count]:
            shutil.copy(frame, folder / "data" / frame.name)
            lines.append(f"{frame.stem},{frame.name}")
        (folder / "data.csv").write_text("\n".join(lines) + "\n")
    return to / "mav0"


@pytest.mark.data
def test_euroc_as_it_ships_runs_with_one_command(data_dir, tmp_path):
    """``vsmatch video mav0/cam0 mav0/cam1``: the frames by data.csv, the two sensor.yaml
    found beside them, the rate from the stamps; the same as naming the calibration."""
    mav0 = euroc_as_it_ships(data_dir / "real-cameras" / "euroc-clip", tmp_path, 3)
    result = invoke("video", mav0 / "cam0", mav0 / "cam1", "-o", tmp_path / "a.avi",
                    "--frames", tmp_path / "a")
    assert result.exit_code == 0, result.output
    assert "sensor.yaml" in result.output and "3 frames" in result.output
    assert cv2.VideoCapture(str(tmp_path / "a.avi")).get(cv2.CAP_PROP_FPS) == 20
    named = invoke("video", mav0 / "cam0", mav0 / "cam1", "-o", tmp_path / "b.avi",
                   "--frames", tmp_path / "b", "--calib", mav0 / "cam0" / "sensor.yaml",
                   "--calib", mav0 / "cam1" / "sensor.yaml")
    assert named.exit_code == 0, named.output
    for k in range(3):
        a, b = (io.read_pfm(tmp_path / f / f"{k:06d}.pfm") for f in ("a", "b"))
        assert a.tobytes() == b.tobytes()
    assert np.isfinite(a).mean() > 0.5


def test_a_dark_first_frame_does_not_stop_the_video(tmp_path, rng):
    """The range is found from the first frame that gives one; the dark frames before it
    are written empty, with a word."""
    names = [f"{k:04d}.png" for k in range(4)]
    left, right = write_folders(tmp_path, rng, names, size=(160, 96))
    for side in (left, right):
        cv2.imwrite(str(side / "0000.png"), np.zeros((96, 160, 3), np.uint8))
    result = invoke("video", left, right, "-o", tmp_path / "d.avi", "--frames",
                    tmp_path / "fr")
    assert result.exit_code == 0, result.output
    assert "4 frames" in result.output
    assert "the first 1 frame gave no disparity range" in result.output
    assert not np.isfinite(io.read_pfm(tmp_path / "fr" / "000000.pfm")).any()
    last = io.read_pfm(tmp_path / "fr" / "000003.pfm")
    assert np.mean(np.abs(last[16:-16, 24:-16] - 4) < 1) > 0.8


def test_no_frame_with_a_range_is_one_line(tmp_path):
    for side in ("left", "right"):
        (tmp_path / side).mkdir()
        for k in range(2):
            cv2.imwrite(str(tmp_path / side / f"{k}.png"), np.zeros((64, 96, 3), np.uint8))
    result = invoke("video", tmp_path / "left", tmp_path / "right", "-o", tmp_path / "d.avi")
    assert result.exit_code == 1 and "no frame of" in result.output, result.output
    assert "--max-disp" in result.output and not (tmp_path / "d.avi").exists()


def test_a_log_file_gets_no_progress_bar(tmp_path, rng):
    left, right = write_folders(tmp_path, rng, ["0.png", "1.png"])
    result = invoke("video", left, right, "-o", tmp_path / "d.avi", "--max-disp", 8)
    assert result.exit_code == 0 and "\r" not in result.output, repr(result.output)


def test_a_terminal_gets_the_progress_bar_with_frames_per_second(tmp_path, rng):
    """The frame loop ran with stderr sent to /dev/null (the atomic writer's guard
    against libpng's own lines): no bar ever showed."""
    import fcntl
    import os
    import pty
    import struct
    import subprocess
    import sys
    import termios

    left, right = write_folders(tmp_path, rng, ["0.png", "1.png", "2.png"])
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 120, 0, 0))
    command = [sys.executable, "-c", "from vsmatch.cli.console import main; main()",
               "video", str(left), str(right), "-o", str(tmp_path / "d.avi"), "--max-disp", "8"]
    process = subprocess.Popen(command, stdin=slave, stdout=slave, stderr=slave)
    os.close(slave)
    shown = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:  # the terminal closed with the process
            break
        if not chunk:
            break
        shown += chunk
    assert process.wait(timeout=600) == 0, shown
    text = shown.decode(errors="replace")
    assert "3/3" in text and "fps" in text and "frame/s" in text, text


def test_the_video_dims_unsure_pixels_over_a_fixed_scale_with_depths():
    disparity = np.tile(np.linspace(10, 30, 64, dtype=np.float32), (40, 1))
    confidence = np.ones_like(disparity)
    confidence[:, :32] = 0.2
    sure = preview.video_frame(disparity, np.ones_like(disparity), 0.88, 0, 40)
    frame = preview.video_frame(disparity, confidence, 0.88, 0, 40)
    assert frame.shape[1] > 64 and frame.shape[0] == 40  # the bar beside the view
    assert frame[:, :32].mean() < 0.6 * sure[:, :32].mean()
    assert np.array_equal(frame[:, 32:64], sure[:, 32:64])
    # The colours hold their disparity whatever the frame holds: the scale is the range.
    half = preview.video_frame(disparity[:, 32:], confidence[:, 32:], 0.88, 0, 40)
    assert np.array_equal(half[:, :32], sure[:, 32:64])
    depths = preview.video_frame(disparity, confidence, 0.88, 0, 40,
                                 depth_of=lambda d: 1000.0 / d if d > 0 else np.inf)
    assert np.array_equal(depths[:, :64], frame[:, :64])
    assert not np.array_equal(depths[:, 64:], frame[:, 64:])  # labels in depth


CALIB = """cam0=[100 0 48; 0 100 24; 0 0 1]
cam1=[100 0 48; 0 100 24; 0 0 1]
doffs=0
baseline=0.1
width=96
height=48
ndisp=12
"""


def test_each_frame_s_depth_and_cloud(tmp_path, rng):
    """--depth-frames (PFM, or 16-bit PNG in millimetres) and --cloud-frames beside the
    disparities: a scene 4 px away at f = 100 px and B = 0.1 m lies at 2.5 m."""
    from plyfile import PlyData

    left, right = write_folders(tmp_path, rng, ["0.png", "1.png"])
    (tmp_path / "calib.txt").write_text(CALIB)
    args = ["video", left, right, "--calib", tmp_path / "calib.txt", "--max-disp", 8]
    result = invoke(*args, "-o", tmp_path / "a.avi", "--depth-frames", tmp_path / "z",
                    "--cloud-frames", tmp_path / "c", "--frames", tmp_path / "d")
    assert result.exit_code == 0, result.output
    for k in range(2):
        depth = io.read_pfm(tmp_path / "z" / f"{k:06d}.pfm")
        known = np.isfinite(depth)
        assert known.mean() > 0.5 and np.median(depth[known]) == pytest.approx(2.5, rel=0.02)
        points = PlyData.read(str(tmp_path / "c" / f"{k:06d}.ply"))["vertex"]
        assert len(points) == known.sum()
        assert np.median(points["z"]) == pytest.approx(2.5, rel=0.02)
    result = invoke(*args, "-o", tmp_path / "b.avi", "--depth-frames", tmp_path / "mm",
                    "--depth-png", "--max-depth", 10)
    assert result.exit_code == 0, result.output
    millimetres = cv2.imread(str(tmp_path / "mm" / "000001.png"), cv2.IMREAD_UNCHANGED)
    assert millimetres.dtype == np.uint16
    assert np.median(millimetres[millimetres > 0]) == pytest.approx(2500, rel=0.02)
    assert (millimetres > 0).sum() == np.isfinite(
        io.read_pfm(tmp_path / "z" / "000001.pfm")).sum()


@pytest.mark.parametrize("extra, said", [
    (["--depth-frames", "z"], "need --calib"),
    (["--depth-png"], "give --depth-frames too"),
    (["--depth-frames", "z", "--depth-png", "--calib", "calib.txt"], "--max-depth"),
    (["--depth-frames", "z", "--depth-png", "--max-depth", 70, "--calib", "calib.txt"],
     "65.535"),
    (["--frames", "z", "--cloud-frames", "z", "--calib", "calib.txt"], "different folders"),
])
def test_depth_and_cloud_frames_refused_before_the_work(tmp_path, rng, monkeypatch, extra,
                                                        said):
    left, right = write_folders(tmp_path, rng, ["0.png", "1.png"])
    (tmp_path / "calib.txt").write_text(CALIB)
    monkeypatch.chdir(tmp_path)
    result = invoke("video", left, right, "-o", "d.avi", "--max-disp", 8, *extra)
    assert result.exit_code == 2 and said in result.output, result.output
    assert not (tmp_path / "d.avi").exists() and not (tmp_path / "z").exists()


def test_a_folder_beside_a_missing_one_names_the_missing_one(tmp_path, rng):
    left, _ = write_folders(tmp_path, rng, ["0.png"])
    result = invoke("video", left, tmp_path / "nosuch", "-o", tmp_path / "d.avi")
    assert result.exit_code == 1 and "nosuch: file not found" in result.output, result.output
    assert not (tmp_path / "d.avi").exists()


def test_a_frame_of_another_size_mid_stream_is_named_with_both_sizes(tmp_path, rng):
    """The video holds one size: a frame of another size stops the command naming the
    frame and both sizes, before anything lands (it read "could not be written ... is the
    disk full?")."""
    left, right = write_folders(tmp_path, rng, ["000001.png", "000002.png"])
    small = cv2.resize(cv2.imread(str(left / "000002.png")), (64, 32))
    cv2.imwrite(str(left / "000003.png"), small)
    cv2.imwrite(str(right / "000003.png"), small)
    result = invoke("video", left, right, "-o", tmp_path / "v.avi", "--max-disp", 12,
                    "--frames", tmp_path / "fr", "--config", "fast")
    assert result.exit_code == 1, result.output
    line = result.output.strip().splitlines()[-1]
    assert "000003.png is 64x32, the frames before it 96x48" in line
    assert "disk full" not in result.output
    assert not (tmp_path / "v.avi").exists() and not (tmp_path / "fr").exists()
