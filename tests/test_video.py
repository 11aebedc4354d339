"""vsmatch video (issue 20): frames of two videos, or one side by side, through one matcher."""

import cv2
import numpy as np
from click.testing import CliRunner

from vsmatch import io
from vsmatch.cli import main


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def write_videos(folder, rng, frames=4, shift=6, size=(128, 64)):
    """left.avi, right.avi and both.avi (side by side) of a textured scene drifting."""
    width, height = size
    base = rng.integers(0, 256, (height // 4 + 1, (width + shift + 2 * frames) // 4 + 2, 3),
                        np.uint8)
    wide = cv2.resize(base, (base.shape[1] * 4, base.shape[0] * 4),
                      interpolation=cv2.INTER_CUBIC)[:height]
    fourcc = cv2.VideoWriter_fourcc(*"MJPG")
    writers = {name: cv2.VideoWriter(str(folder / f"{name}.avi"), fourcc, 10,
                                     (width * (2 if name == "both" else 1), height))
               for name in ("left", "right", "both")}
    for k in range(frames):
        left = np.ascontiguousarray(wide[:, 2 * k:2 * k + width])
        right = np.ascontiguousarray(wide[:, 2 * k + shift:2 * k + shift + width])
        writers["left"].write(left)
        writers["right"].write(right)
        writers["both"].write(np.hstack([left, right]))
    for writer in writers.values():
        writer.release()


def frame_count(path):
    capture = cv2.VideoCapture(str(path))
    count = 0
    while capture.read()[0]:
        count += 1
    return count


def test_two_videos_give_a_disparity_video_and_frames(tmp_path, rng):
    write_videos(tmp_path, rng)
    result = invoke("-v", "video", tmp_path / "left.avi", tmp_path / "right.avi", "-o",
                    tmp_path / "d.avi", "--max-disp", 16, "--frames", tmp_path / "frames",
                    "--config", "paper")
    assert result.exit_code == 0, result.output
    assert "4 frames" in result.output and "fps" in result.output
    assert frame_count(tmp_path / "d.avi") == 4
    disp = io.read_pfm(tmp_path / "frames" / "000003.pfm")
    assert np.mean(np.abs(disp[8:-8, 24:-8] - 6) < 1) > 0.8
    assert (tmp_path / "frames" / "000003_confidence.pfm").exists()
    assert not [p for p in tmp_path.iterdir() if ".partial" in p.name]


def test_side_by_side_gives_the_same_frames(tmp_path, rng):
    write_videos(tmp_path, rng)
    args = ["--max-disp", 16, "--config", "paper", "--max-frames", 2]
    assert invoke("video", tmp_path / "left.avi", tmp_path / "right.avi", "-o",
                  tmp_path / "a.avi", "--frames", tmp_path / "a", *args).exit_code == 0
    result = invoke("video", tmp_path / "both.avi", "--side-by-side", "-o",
                    tmp_path / "b.avi", "--frames", tmp_path / "b", *args)
    assert result.exit_code == 0, result.output
    assert frame_count(tmp_path / "b.avi") == 2
    # Both were compressed alike but not identically: the disparities agree where sure.
    a, b = (io.read_pfm(tmp_path / f / "000001.pfm") for f in ("a", "b"))
    assert np.mean(np.abs(a - b)[8:-8, 24:-8] < 1) > 0.9


def test_video_errors_are_one_line(tmp_path):
    result = invoke("video", tmp_path / "missing.avi", tmp_path / "other.avi", "-o",
                    tmp_path / "d.avi")
    assert result.exit_code == 1 and "missing.avi: file not found" in result.output
    (tmp_path / "text.mp4").write_text("not a video\n")
    (tmp_path / "text2.mp4").write_text("not a video either\n")
    result = invoke("video", tmp_path / "text.mp4", tmp_path / "text2.mp4", "-o",
                    tmp_path / "d.avi")
    assert result.exit_code == 1 and "cannot open this video" in result.output
    assert invoke("video", tmp_path / "a.avi", "-o", tmp_path / "d.avi").exit_code == 2
    result = invoke("video", tmp_path / "a.avi", tmp_path / "b.avi", "-o", tmp_path / "d.gif")
    assert result.exit_code == 2 and ".avi or .mp4" in result.output
    assert not (tmp_path / "d.avi").exists()


def test_the_same_video_folder_or_camera_as_left_and_right_is_refused(tmp_path, rng):
    """One camera given twice would match a view against itself: disparity 0 everywhere,
    confident. Refused before anything is opened or written, links and '..' resolved."""
    write_videos(tmp_path, rng, frames=2)
    (tmp_path / "link.avi").symlink_to(tmp_path / "left.avi")
    (tmp_path / "frames").mkdir()
    cases = [(tmp_path / "left.avi", tmp_path / "link.avi", "same video"),
             (tmp_path / "frames", f"{tmp_path}/frames/../frames", "same folder"),
             ("0", "00", "same camera")]
    for left, right, what in cases:
        result = invoke("video", left, right, "-o", tmp_path / "d.avi", "--max-disp", 16)
        assert result.exit_code == 1, result.output
        assert f"LEFT and RIGHT are the {what}" in result.output
        assert "--side-by-side" in result.output and "Traceback" not in result.output
        assert not (tmp_path / "d.avi").exists()
    # Two different sources still run.
    result = invoke("video", tmp_path / "left.avi", tmp_path / "right.avi", "-o",
                    tmp_path / "d.avi", "--max-disp", 16, "--config", "fast")
    assert result.exit_code == 0, result.output


def test_overwrite_never_deletes_what_vsmatch_did_not_write(tmp_path, rng, monkeypatch):
    """--frames DIR --overwrite replaces a folder of earlier frames only: a user's own
    file or sub-folder in it is refused, kept, and nothing is written; the current folder
    is never a --frames folder."""
    write_videos(tmp_path, rng)
    frames = tmp_path / "frames"
    (frames / "notes").mkdir(parents=True)
    (frames / "000000.pfm").write_bytes(b"old frame")
    (frames / "notes" / "mine.txt").write_text("mine")
    result = invoke("video", tmp_path / "left.avi", tmp_path / "right.avi", "-o",
                    tmp_path / "d.avi", "--frames", frames, "--overwrite", "--max-disp", 16)
    assert result.exit_code == 1 and "notes" in result.output, result.output
    assert (frames / "notes" / "mine.txt").read_text() == "mine"
    assert not (tmp_path / "d.avi").exists()

    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    result = invoke("video", tmp_path / "left.avi", tmp_path / "right.avi", "-o",
                    tmp_path / "e.avi", "--frames", ".", "--overwrite", "--max-disp", 16)
    assert result.exit_code == 1 and "current folder" in result.output, result.output
    assert not (tmp_path / "e.avi").exists()
    assert list(work.iterdir()) == [] and not list(tmp_path.glob(".*old*"))


def test_a_full_frames_folder_is_named_by_its_own_path(tmp_path, rng, small_disk):
    """A write that fails inside the staged --frames folder names the folder the user
    gave, never its temporary, in one line (no libpng line beside it)."""
    disk = small_disk(64, whole_disk=True)
    write_videos(tmp_path, rng)
    result = invoke("video", tmp_path / "left.avi", tmp_path / "right.avi", "-o",
                    tmp_path / "d.avi", "--frames", disk / "fr", "--max-disp", 16)
    assert result.exit_code == 1, result.output
    lines = [line for line in result.output.splitlines() if "Error" in line]
    assert len(lines) == 1 and "could not be written" in lines[0], result.output
    assert f"{disk / 'fr'}/0000" in lines[0] and ".tmp" not in lines[0], lines[0]
    assert not list(disk.iterdir()) and not (tmp_path / "d.avi").exists()


def test_two_videos_of_different_frame_rates_are_refused(tmp_path, rng):
    write_videos(tmp_path, rng)
    capture = cv2.VideoCapture(str(tmp_path / "right.avi"))
    writer = cv2.VideoWriter(str(tmp_path / "slow.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 5,
                             (128, 64))
    while True:
        ok, frame = capture.read()
        if not ok:
            break
        writer.write(frame)
    writer.release()
    capture.release()
    result = invoke("video", tmp_path / "left.avi", tmp_path / "slow.avi", "-o",
                    tmp_path / "d.avi", "--max-disp", 16)
    assert result.exit_code == 1 and "frames per second" in result.output, result.output
    assert not (tmp_path / "d.avi").exists()


def test_two_folders_of_frames_paired_by_name(tmp_path, rng):
    """cam0/ and cam1/ as EuRoC and ROS bag exports lay out a recording: frames paired
    by name, the rate from their nanosecond time stamps; a frame without a partner is
    counted as failed."""
    write_videos(tmp_path, rng)
    for name in ("left", "right"):
        capture = cv2.VideoCapture(str(tmp_path / f"{name}.avi"))
        folder = tmp_path / name
        folder.mkdir()
        k = 0
        while True:
            ok, frame = capture.read()
            if not ok:
                break
            cv2.imwrite(str(folder / f"{1403715273262142976 + k * 50_000_000}.png"), frame)
            k += 1
        capture.release()
    result = invoke("-v", "video", tmp_path / "left", tmp_path / "right", "-o",
                    tmp_path / "d.avi", "--max-disp", 16, "--frames", tmp_path / "frames")
    assert result.exit_code == 0, result.output
    assert frame_count(tmp_path / "d.avi") == 4
    assert cv2.VideoCapture(str(tmp_path / "d.avi")).get(cv2.CAP_PROP_FPS) == 20
    disp = io.read_pfm(tmp_path / "frames" / "000003.pfm")
    assert np.mean(np.abs(disp[8:-8, 24:-8] - 6) < 1) > 0.8
    (tmp_path / "left" / "1403715273999999999.png").write_bytes(
        (tmp_path / "left" / "1403715273262142976.png").read_bytes())
    result = invoke("video", tmp_path / "left", tmp_path / "right", "-o",
                    tmp_path / "e.avi", "--max-disp", 16)
    assert result.exit_code == 1 and "1 frame without a partner" in result.output


def test_frames_through_a_link_follow_it_and_a_link_to_nothing_is_refused(tmp_path, rng):
    """--frames naming a link to a folder writes into that folder, the link kept (the link
    was replaced by a folder, its target left empty); a link to nothing is refused before
    anything is written (the video landed, then the frames failed: not both or neither)."""
    write_videos(tmp_path, rng, frames=2)
    args = ["--max-disp", 16, "--config", "fast"]
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    result = invoke("video", tmp_path / "left.avi", tmp_path / "right.avi", "-o",
                    tmp_path / "d.avi", "--frames", tmp_path / "dangling", *args)
    assert result.exit_code == 1, result.output
    assert f"a link to {tmp_path / 'nowhere'}, which does not exist" in result.output
    assert "Errno" not in result.output and not (tmp_path / "d.avi").exists()
    (tmp_path / "target").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "target")
    result = invoke("video", tmp_path / "left.avi", tmp_path / "right.avi", "-o",
                    tmp_path / "d.avi", "--frames", tmp_path / "link", *args)
    assert result.exit_code == 0, result.output
    assert (tmp_path / "link").is_symlink()
    assert sorted(p.name for p in (tmp_path / "target").iterdir()) == [
        f"{k:06d}{s}.pfm" for k in range(2) for s in ("", "_confidence")]


def decoded_frames(path):
    capture = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, frame = capture.read()
        if not ok:
            return frames
        frames.append(frame)


def test_no_temporal_gives_each_frame_runs_bytes_and_the_video_shows_them(tmp_path, rng):
    """--no-temporal matches every frame alone: its --frames are `vsmatch run`'s bytes on
    the same decoded frames; and the video holds those frames, in order (decoded and
    compared with their rendering, within what MJPG's compression changes)."""
    from vsmatch import preview
    from vsmatch.config import load_config

    write_videos(tmp_path, rng, frames=3)
    result = invoke("video", tmp_path / "left.avi", tmp_path / "right.avi", "-o",
                    tmp_path / "d.avi", "--max-disp", 16, "--config", "fast", "--frames",
                    tmp_path / "fr", "--no-temporal")
    assert result.exit_code == 0, result.output
    lefts, rights = (decoded_frames(tmp_path / f"{s}.avi") for s in ("left", "right"))
    shown = decoded_frames(tmp_path / "d.avi")
    assert len(lefts) == len(shown) == 3
    threshold = load_config("fast").cloud.min_confidence
    for k, (left, right) in enumerate(zip(lefts, rights)):
        cv2.imwrite(str(tmp_path / "l.png"), left)
        cv2.imwrite(str(tmp_path / "r.png"), right)
        alone = invoke("run", tmp_path / "l.png", tmp_path / "r.png", "-o",
                       tmp_path / f"run{k}.pfm", "--max-disp", 16, "--config", "fast",
                       "--confidence", tmp_path / f"run{k}_c.pfm")
        assert alone.exit_code == 0, alone.output
        disp = io.read_pfm(tmp_path / "fr" / f"{k:06d}.pfm")
        conf = io.read_pfm(tmp_path / "fr" / f"{k:06d}_confidence.pfm")
        assert disp.tobytes() == io.read_pfm(tmp_path / f"run{k}.pfm").tobytes()
        assert conf.tobytes() == io.read_pfm(tmp_path / f"run{k}_c.pfm").tobytes()
        expected = preview.video_frame(disp, conf, threshold, 0, 16)
        assert shown[k].shape == expected.shape
        assert np.abs(shown[k].astype(int) - expected).mean() < 6  # MJPG's losses only
    # Frames in their order: each decoded frame is nearest its own rendering.
    renders = [preview.video_frame(io.read_pfm(tmp_path / "fr" / f"{k:06d}.pfm"),
                                   io.read_pfm(tmp_path / "fr" / f"{k:06d}_confidence.pfm"),
                                   threshold, 0, 16) for k in range(3)]
    for k, frame in enumerate(shown):
        errors = [np.abs(frame.astype(int) - r).mean() for r in renders]
        assert errors[k] == min(errors), errors
