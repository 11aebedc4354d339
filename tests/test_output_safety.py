"""Outputs never overwrite an input, never leave a partial file, and fail in one line when
the disk does."""

import os
from pathlib import Path

import cv2
import numpy as np
import pytest
from cli_helpers import (
    HEIGHT,
    WIDTH,
    files_in,
    invoke,
    one_line_error,
    smooth_pair,
    write_opencv_rig,
    write_pair,
)
from test_video import frame_count

from vsmatch import io, pipeline


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


def fake_dataset(root):
    scene = root / "middlebury2" / "tsukuba"
    scene.mkdir(parents=True)
    for name in ("imL.png", "imR.png", "groundtruth.png"):
        (scene / name).write_bytes(b"data")
    return scene


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


def disk_free(folder):
    stats = os.statvfs(folder)
    return stats.f_bavail * stats.f_frsize


def test_a_failing_cloud_leaves_no_disparity_and_names_the_file(pair_files, tmp_path,
                                                                 monkeypatch):
    import errno

    def disk_full(self, path):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("plyfile.PlyData.write", disk_full)
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8,
                    "--focal", 100, "--baseline", 1, "--depth", tmp_path / "z.pfm",
                    "--cloud", tmp_path / "c.ply")
    line = one_line_error(result)
    assert "c.ply" in line and "No space left" in line
    assert files_in(tmp_path) == ["l.png", "r.png"]


def test_video_refuses_an_output_over_an_input_or_its_link(tmp_path, rng):
    left, right = write_videos(tmp_path, rng)
    before = left.read_bytes()
    line = one_line_error(invoke("video", left, right, "-o", left, "--max-disp", 16))
    assert "would overwrite the input" in line
    (tmp_path / "link.avi").symlink_to(right)
    line = one_line_error(invoke("video", left, right, "-o", tmp_path / "link.avi",
                                 "--max-disp", 16))
    assert "would overwrite the input" in line
    assert left.read_bytes() == before and (tmp_path / "link.avi").is_symlink()


def test_rectified_views_never_overwrite_the_inputs(tmp_path, rng):
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


def test_eval_and_bench_write_nothing_into_the_data_set(tmp_path):
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


def test_rectified_views_are_written_with_the_run_or_not_at_all(tmp_path, rng):
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


def test_a_video_the_writer_could_not_finish_is_an_error(tmp_path, rng, monkeypatch):
    from vsmatch import frames

    left, right = write_videos(tmp_path, rng)
    monkeypatch.setattr(frames.cv2, "VideoWriter", DroppingWriter)
    line = one_line_error(invoke("video", left, right, "-o", tmp_path / "d.avi",
                                 "--max-disp", 16))
    assert "d.avi" in line and "holds 2 of 4 frames" in line
    assert not [p for p in tmp_path.iterdir() if p.name.startswith((".d", "d."))]


def test_a_video_onto_a_full_disk_fails_in_one_line(tmp_path, rng, small_disk):
    disk = small_disk(600, whole_disk=True)
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


def test_a_video_leaves_another_runs_temporary_alone(tmp_path, rng):
    left, right = write_videos(tmp_path, rng)
    other = tmp_path / ".d.partial.avi"  # the name every run used to write to
    other.write_bytes(b"another run's frames")
    result = invoke("video", left, right, "-o", tmp_path / "d.avi", "--max-disp", 16)
    assert result.exit_code == 0, result.output
    assert other.read_bytes() == b"another run's frames"
    assert frame_count(tmp_path / "d.avi") == 4


def test_frames_folder_is_refused_when_full_and_replaced_whole(tmp_path, rng):
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


def test_frames_folder_may_not_hold_the_inputs(tmp_path, rng):
    """--frames replaces its folder as a whole: one holding an input (or the video) is
    refused by that check's own message, the output's folder existing."""
    inputs = tmp_path / "in"
    inputs.mkdir()
    left, right = write_videos(inputs, rng)
    line = one_line_error(invoke("video", left, right, "-o", tmp_path / "d.avi",
                                 "--frames", inputs, "--overwrite", "--max-disp", 16),
                          code=1)
    assert f"--frames {inputs} holds the input {left}" in line
    assert "a folder of its own" in line
    assert left.exists() and right.exists() and not (tmp_path / "d.avi").exists()
    (tmp_path / "fr").mkdir()
    line = one_line_error(invoke("video", left, right, "-o", tmp_path / "fr" / "d.avi",
                                 "--frames", tmp_path / "fr", "--max-disp", 16), code=1)
    assert f"--frames {tmp_path / 'fr'} holds the output" in line


def test_unpaired_video_frames_fail_with_both_counts(tmp_path, rng):
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


def test_an_output_that_is_a_folder_is_refused_before_matching(tmp_path, rng,
                                                                  monkeypatch):
    views = write_pair(tmp_path, rng)
    (tmp_path / "d.pfm").mkdir()
    monkeypatch.setattr(pipeline, "run", lambda *a, **k: pytest.fail("matched anyway"))
    line = one_line_error(invoke("run", *views, "-o", tmp_path / "d.pfm", "--max-disp", 16))
    assert "d.pfm: is a folder" in line and ".tmp" not in line


def test_an_unwritable_folder_is_named_not_a_temporary(tmp_path, rng, monkeypatch):
    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied", str(tmp_path / ".im0.xyz.tmp.png"))
    monkeypatch.setattr(io.tempfile, "mkstemp", refuse)
    with pytest.raises(OSError) as caught:
        io.imwrite_atomic(tmp_path / "im0.png", np.zeros((4, 4), np.uint8))
    assert str(caught.value).startswith(f"{tmp_path / 'im0.png'}: could not be written")
    assert ".tmp" not in str(caught.value)
