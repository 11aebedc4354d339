"""``vsmatch video``: two videos (or one side by side, or cameras) through one matcher."""

from __future__ import annotations

import contextlib
import re
import time
from pathlib import Path

import click
import cv2
import numpy as np

from .. import io
from ..batch import IMAGE_EXTENSIONS
from ..matcher import StereoMatcher
from .common import (MAX_DISP, check_outputs, check_outside, config_option, echo, examples,
                     friendly_errors, verbose, verbosity_options)

from .main import main

#: Output containers and the codec OpenCV writes them with here.
VIDEO_CODECS = {".avi": "MJPG", ".mp4": "mp4v"}


#: The largest camera index OpenCV takes (a C int).
MAX_CAMERA_INDEX = 2**31 - 1


def _open(source: str) -> cv2.VideoCapture:
    """A video file, or a camera index (``0``, ``1``, ...). FFmpeg's own complaints
    ("moov atom not found") are kept off stderr: our one line says what is wrong."""
    camera = source.isdigit()
    if camera and int(source) > MAX_CAMERA_INDEX:
        raise click.ClickException(f"{source}: no camera has this index (0..."
                                   f"{MAX_CAMERA_INDEX})")
    if not camera and Path(source).is_dir():
        raise click.ClickException(f"{source}: a folder; give two folders of frames (LEFT "
                                   "and RIGHT, frames paired by name)")
    if not camera and not Path(source).is_file():
        raise click.ClickException(f"{source}: file not found")
    with io.native_stderr_silenced():
        capture = cv2.VideoCapture(int(source)) if camera else cv2.VideoCapture(source)
    if not capture.isOpened():
        what = "camera" if camera else "video"
        raise click.ClickException(f"{source}: cannot open this {what}")
    return capture


class FolderPairs:
    """Two folders of frames (``cam0/``, ``cam1/``) as a video: the frames of the same file
    name, in name order, each pair read as ``vsmatch run`` reads one (16-bit frames keep
    one scale). Frames named by their time stamp in nanoseconds (EuRoC, ROS bag exports)
    give the frame rate."""

    def __init__(self, left: str, right: str):
        def frames(folder):
            return {p.name: p for p in Path(folder).iterdir()
                    if p.is_file() and p.suffix.lower() in IMAGE_EXTENSIONS}
        lefts, rights = frames(left), frames(right)
        self.names = sorted(lefts.keys() & rights.keys())
        if not self.names:
            raise click.ClickException(f"{left} and {right}: no frames of the same name")
        self.paths = [(lefts[n], rights[n]) for n in self.names]
        alone = len(lefts.keys() ^ rights.keys())
        self._unpaired = None if not alone else (
            f"{left} has {len(lefts)} frames, {right} {len(rights)}: {alone} frame"
            f"{'s' if alone > 1 else ''} without a partner of the same name, counted as "
            "failed")

    def __iter__(self):
        for left, right in self.paths:
            yield io.read_pair(left, right)

    def fps(self) -> float:
        stamps = [Path(n).stem for n in self.names]
        if len(stamps) < 2 or not all(s.isdigit() and len(s) >= 16 for s in stamps):
            return 0.0
        step = float(np.median(np.diff([int(s) for s in stamps])))
        return 1e9 / step if step > 0 else 0.0

    def unpaired(self) -> str | None:
        return self._unpaired


class FramePairs:
    """Pairs of frames until a source ends; one side-by-side source is split. Counts
    the frames each source gave, and after the end those left without a partner."""

    def __init__(self, names: list[str], sources: list[cv2.VideoCapture]):
        self.names, self.sources = names, sources
        self.read = [0] * len(sources)

    def _next(self, k: int):
        with io.native_stderr_silenced():
            ok, frame = self.sources[k].read()
        if ok:
            self.read[k] += 1
        return frame if ok else None

    def __iter__(self):
        while True:
            frame = self._next(0)
            if frame is None:
                return
            if len(self.sources) == 1:
                half = frame.shape[1] // 2
                yield (np.ascontiguousarray(frame[:, :half]),
                       np.ascontiguousarray(frame[:, half:2 * half]))
                continue
            other = self._next(1)
            if other is None:
                return
            yield frame, other

    def unpaired(self) -> str | None:
        """After the pairs ran out: the frames one source has beyond the other's end,
        counted to the end of a file (a camera gives one more at least), or None."""
        if len(self.sources) == 1:
            return None
        longer = 0 if self.read[0] > self.read[1] else 1
        if self.read[0] == self.read[1]:  # the left ended: has the right more?
            longer = 1
            if self._next(1) is None:
                return None
        if not self.names[longer].isdigit():
            while self._next(longer) is not None:
                pass
        a, b = self.read
        extra = abs(a - b)
        return (f"{self.names[0]} has {a} frames, {self.names[1]} {b}: {extra} frame"
                f"{'s' if extra > 1 else ''} without a partner, counted as failed")


#: The files ``--frames`` holds: NNNNNN.pfm and NNNNNN_confidence.pfm.
FRAME_FILE = re.compile(r"\d{6}(_confidence)?\.pfm")


def is_frame_file(entry: Path) -> bool:
    """An earlier run's frame file (what ``--overwrite`` may replace)."""
    return entry.is_file() and not entry.is_symlink() and bool(
        FRAME_FILE.fullmatch(entry.name))


def write_video(path: str, pictures, fps: float, codec: str) -> int:
    """Write ``pictures`` (BGR, one size) to the video ``path``; the number written. The
    file is opened again and its frames counted: a writer that could not write (a full
    disk) is an OSError, never a short video."""
    writer, count = None, 0
    try:
        for picture in pictures:
            if writer is None:
                writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*codec), fps,
                                         picture.shape[1::-1])
                if not writer.isOpened():
                    raise OSError("OpenCV cannot write this video")
            writer.write(picture)
            count += 1
    finally:
        if writer is not None:
            writer.release()
    if count:
        written = video_frame_count(path)
        if written != count:
            raise OSError(f"the file holds {written} of {count} frames (is the disk full?)")
    return count


def video_frame_count(path: str) -> int:
    """The frames of a video file that decode (a file cut short by a full disk may still
    claim every frame in its header)."""
    count = 0
    with io.native_stderr_silenced():
        capture = cv2.VideoCapture(path)
        try:
            while capture.isOpened() and capture.read()[0]:
                count += 1
        finally:
            capture.release()
    return count


@main.command(epilog=examples(
    "vsmatch video left.mp4 right.mp4 -o disparity.avi --calib stereo.yaml",
    "vsmatch video both.mp4 --side-by-side -o d.mp4 --frames frames/",
    "vsmatch video 0 1 -o live.avi --calib stereo.yaml --config fast",
    "vsmatch video cam0/ cam1/ -o d.avi --calib cam0/sensor.yaml --calib cam1/sensor.yaml"))
@click.argument("left")
@click.argument("right", required=False)
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="The colour disparity video to write (.avi or .mp4).")
@click.option("--side-by-side", is_flag=True,
              help="LEFT holds both views side by side (left half, right half).")
@click.option("--frames", "frames_dir", type=click.Path(file_okay=False), default=None,
              help="Also write each frame's disparity and confidence here "
                   "(NNNNNN.pfm, NNNNNN_confidence.pfm); a folder that holds anything is "
                   "refused unless --overwrite.")
@click.option("--overwrite", is_flag=True,
              help="Replace a --frames folder of an earlier run's frames, as a whole (a "
                   "folder that holds anything else is refused).")
@click.option("--max-disp", type=MAX_DISP, default=None,
              help="Largest disparity searched; default: the calibration's, else found "
                   "from the first frame (and again when the scene comes closer).")
@click.option("--min-disp", type=int, default=None, help="Smallest disparity searched.")
@click.option("--calib", type=click.Path(dir_okay=False), multiple=True,
              help="As for 'vsmatch run': a rectified pair's calibration or a raw rig's.")
@click.option("--max-frames", type=click.IntRange(min=1), default=None,
              help="Stop after this many frames.")
@click.option("--temporal/--no-temporal", default=True, show_default=True,
              help="Each frame searches near the last one's disparities and holds them "
                   "where the image holds still (steadier depth, faster); --no-temporal "
                   "matches every frame alone.")
@config_option
@verbosity_options
@click.pass_context
@friendly_errors
def video(ctx, left, right, output, side_by_side, frames_dir, overwrite, max_disp,
          min_disp, calib, max_frames, temporal, config):
    """Match the frames of two videos (or of one side-by-side video, of two cameras
    given by index, or of two folders of frames paired by file name, as EuRoC's cam0/
    and cam1/) and write the disparity as a colour video.

    Frames of one video without a partner in the other are counted as failed (exit 1).
    """
    from tqdm import tqdm

    out = Path(output)
    if out.suffix.lower() not in VIDEO_CODECS:
        raise click.BadParameter(f"'{output}' must end in .avi or .mp4", param_hint="'-o'")
    if side_by_side == (right is not None):
        raise click.UsageError("give LEFT and RIGHT, or one LEFT with --side-by-side")
    names = [left] + ([] if right is None else [right])
    inputs = [n for n in names if not n.isdigit()] + list(calib)
    check_outputs(inputs, [output], folders={frames_dir: []} if frames_dir else {})
    if frames_dir is not None:  # the folder is replaced as a whole: nothing else in it
        check_outside(Path(frames_dir), [*inputs, output], "--frames folder")
        try:
            io.check_replaceable_folder(frames_dir, overwrite=overwrite, ours=is_frame_file)
        except OSError as exc:
            raise click.ClickException(str(exc)) from None
    stereo = StereoMatcher(max_disp=max_disp, min_disp=min_disp, config=config,
                           calib=list(calib) or None, temporal=temporal)
    if len(names) == 2 and all(Path(name).is_dir() for name in names):
        sources, pairs = [], FolderPairs(*names)
        fps = pairs.fps() or 10.0
    else:
        sources = [_open(name) for name in names]
        _check_frame_rates(names, sources)
        fps = sources[0].get(cv2.CAP_PROP_FPS) or 10.0
        pairs = FramePairs(names, sources)
    count, start = 0, time.perf_counter()
    quiet = ctx.find_root().obj.get("quiet")

    full = 0  # frames that searched the whole range

    def pictures(frames_folder: Path | None):
        nonlocal count, full
        with tqdm(total=max_frames, disable=quiet, unit="frame", leave=False) as bar:
            for frame_l, frame_r in pairs:
                result = stereo.result(frame_l, frame_r)
                full += stereo.temporal is None or stereo.temporal.reason is not None
                low, high = stereo.range or result.search_range
                yield io.colour_disparity(result.disparity, high, low)
                if frames_folder is not None:
                    io.write_disparity(frames_folder / f"{count:06d}.pfm", result.disparity)
                    io.write_confidence(frames_folder / f"{count:06d}_confidence.pfm",
                                        result.confidence)
                count += 1
                bar.update(1)
                bar.set_postfix_str(f"{count / (time.perf_counter() - start):.2f} fps")
                if max_frames is not None and count >= max_frames:
                    return

    try:
        with io.all_or_none():  # the video and the frames folder together, or neither
            staged = (io.staged_folder(frames_dir, overwrite=overwrite,
                                               ours=is_frame_file) if frames_dir
                      else contextlib.nullcontext(None))
            with staged as frames_folder:
                io.write_atomic(out, lambda tmp: _write_or_refuse(
                    tmp, pictures(frames_folder), fps, out, left))
        stopped = max_frames is not None and count >= max_frames
        unpaired = None if stopped else pairs.unpaired()
    finally:
        for source in sources:
            source.release()
    seconds = time.perf_counter() - start
    verbose(ctx, f"{count} frames in {seconds:.1f} s ({count / seconds:.2f} fps), "
                 f"disparities {stereo.range[0]}..{stereo.range[1]}"
                 if stereo.range else f"{count} frames in {seconds:.1f} s")
    rate = f", {count / seconds:.2f} fps" if count and seconds > 0 else ""
    searched = (f"; {full} searched the whole range, {count - full} near the last frame"
                if temporal else "")
    echo(ctx, f"wrote {output} ({count} frames{rate}{searched})")
    if unpaired is not None:
        raise click.ClickException(unpaired)


def _check_frame_rates(names: list[str], sources: list[cv2.VideoCapture]) -> None:
    """Two video files of different frame rates would pair frames of different moments
    (a camera's rate is what it delivers: not checked)."""
    if len(sources) != 2 or any(name.isdigit() for name in names):
        return
    rates = [source.get(cv2.CAP_PROP_FPS) for source in sources]
    if all(rate > 0 for rate in rates) and abs(rates[0] - rates[1]) > 0.01 * max(rates):
        for source in sources:
            source.release()
        raise click.ClickException(
            f"{names[0]} runs at {rates[0]:g} frames per second and {names[1]} at "
            f"{rates[1]:g}: frame by frame they would pair different moments")


def _write_or_refuse(tmp: str, pictures, fps: float, out: Path, left: str) -> None:
    if write_video(tmp, pictures, fps, VIDEO_CODECS[out.suffix.lower()]) == 0:
        raise click.ClickException(f"{left}: no frame could be read")
