"""Frames in and out: stereo frames from two videos, one side-by-side video, two cameras
or two folders of frames paired by name; colour disparity videos written and checked."""

from __future__ import annotations

import re
from pathlib import Path

import cv2
import numpy as np

from . import io


class FrameSourceError(ValueError):
    """A frame source that cannot be read as one; the message is one line."""


#: Output containers and the codec OpenCV writes them with here.
VIDEO_CODECS = {".avi": "MJPG", ".mp4": "mp4v"}


#: The largest camera index OpenCV takes (a C int).
MAX_CAMERA_INDEX = 2**31 - 1


def open_source(source: str) -> cv2.VideoCapture:
    """A video file, or a camera index (``0``, ``1``, ...). FFmpeg's own complaints
    ("moov atom not found") are kept off stderr: our one line says what is wrong."""
    camera = source.isdigit()
    if camera and int(source) > MAX_CAMERA_INDEX:
        raise FrameSourceError(f"{source}: no camera has this index (0..."
                                   f"{MAX_CAMERA_INDEX})")
    if not camera and Path(source).is_dir():
        raise FrameSourceError(f"{source}: a folder; give two folders of frames (LEFT "
                                   "and RIGHT, frames paired by name)")
    if not camera and not Path(source).is_file():
        raise FrameSourceError(f"{source}: file not found")
    with io.native_stderr_silenced():
        capture = cv2.VideoCapture(int(source)) if camera else cv2.VideoCapture(source)
    if not capture.isOpened():
        what = "camera" if camera else "video"
        raise FrameSourceError(f"{source}: cannot open this {what}")
    return capture


class FolderPairs:
    """Two folders of frames (``cam0/``, ``cam1/``) as a video: the frames of the same file
    name, in name order, each pair read as ``vsmatch run`` reads one (16-bit frames keep
    one scale). Frames named by their time stamp in nanoseconds (EuRoC, ROS bag exports)
    give the frame rate."""

    def __init__(self, left: str, right: str):
        def frames(folder):
            return {p.name: p for p in Path(folder).iterdir()
                    if p.is_file() and p.suffix.lower() in io.IMAGE_EXTENSIONS}
        lefts, rights = frames(left), frames(right)
        self.names = sorted(lefts.keys() & rights.keys())
        if not self.names:
            raise FrameSourceError(f"{left} and {right}: no frames of the same name")
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


def check_frame_rates(names: list[str], sources: list[cv2.VideoCapture]) -> None:
    """Two video files of different frame rates would pair frames of different moments
    (a camera's rate is what it delivers: not checked)."""
    if len(sources) != 2 or any(name.isdigit() for name in names):
        return
    rates = [source.get(cv2.CAP_PROP_FPS) for source in sources]
    if all(rate > 0 for rate in rates) and abs(rates[0] - rates[1]) > 0.01 * max(rates):
        for source in sources:
            source.release()
        raise FrameSourceError(
            f"{names[0]} runs at {rates[0]:g} frames per second and {names[1]} at "
            f"{rates[1]:g}: frame by frame they would pair different moments")
