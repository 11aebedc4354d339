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
                                   "and RIGHT, frames paired by name or time stamp)")
    if not camera and not Path(source).is_file():
        raise FrameSourceError(f"{source}: file not found")
    with io.native_stderr_silenced():
        capture = cv2.VideoCapture(int(source)) if camera else cv2.VideoCapture(source)
    if not capture.isOpened():
        what = "camera" if camera else "video"
        raise FrameSourceError(f"{source}: cannot open this {what}")
    return capture


#: Files beside the frames that are no frames and go unsaid: calibrations, EuRoC's index.
COMPANIONS = (".yaml", ".yml", ".csv", ".txt", ".json")


def frame_key(name: str):
    """The order of a frame named ``name``: by the number in it (``2.png`` before
    ``10.png``; time stamps of any number of digits in time order), else by name."""
    stem = Path(name).stem
    if stem.isdigit():
        return (0, int(stem), "")
    parts = re.split(r"(\d+)", stem)
    return (1, 0, tuple((0, int(p), "") if p.isdigit() else (1, 0, p) for p in parts if p))


def camera_folder(folder: str) -> tuple[dict, list[str], Path]:
    """One camera's frames: {key: path}, the files skipped (not frames), and the folder
    its ``sensor.yaml`` would be in. A folder holding ``data/`` and ``data.csv`` is one
    camera of the EuRoC/ASL layout (``mav0/cam0``), its frames as the index names them;
    any other folder holds its frames itself. Two files of one moment are refused."""
    root = Path(folder)
    data, index = root / "data", root / "data.csv"
    if data.is_dir() and index.is_file():
        return _indexed_frames(data, index) + (root,)
    found, skipped = {}, []
    for path in sorted(root.iterdir()):
        if not path.is_file() or path.suffix.lower() in COMPANIONS:
            continue
        if path.name.startswith(".") or path.suffix.lower() not in io.IMAGE_EXTENSIONS:
            skipped.append(path.name)
            continue
        key = frame_key(path.name)
        if key in found:
            raise FrameSourceError(f"{found[key]} and {path}: two frames of one moment; "
                                   "keep one")
        found[key] = path
    return found, skipped, root


def _indexed_frames(data: Path, index: Path) -> tuple[dict, list[str]]:
    """EuRoC's ``data.csv``: ``#timestamp [ns],filename`` a line, the files in ``data/``."""
    found, skipped = {}, []
    for number, line in enumerate(index.read_text(errors="replace").splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        fields = [f.strip() for f in line.split(",")]
        if len(fields) < 2 or not fields[0].isdigit():
            raise FrameSourceError(f"{index}, line {number}: not 'timestamp,filename'")
        path = data / fields[1]
        if not path.is_file():
            skipped.append(fields[1])
            continue
        key = (0, int(fields[0]), "")
        if key in found:
            raise FrameSourceError(f"{index}: time stamp {fields[0]} twice")
        found[key] = path
    return found, skipped


#: Time stamps in nanoseconds have at least this many digits (EuRoC, ROS bag exports).
NANOSECOND_DIGITS = 16


def nanosecond_stamps(keys: list) -> bool:
    """Whether every :func:`frame_key` is a time stamp in nanoseconds."""
    return bool(keys) and all(k[0] == 0 and k[1] >= 10 ** (NANOSECOND_DIGITS - 1)
                              for k in keys)


def paired_keys(lefts: list, rights: list) -> list[tuple]:
    """Left and right frames of one moment, in time order: the same key; between time
    stamps in nanoseconds, the nearest within a quarter of the frame step (two cameras'
    clocks seldom stamp a moment alike)."""
    rights_set = set(rights)
    pairs = [(k, k) for k in lefts if k in rights_set]
    if len(pairs) == len(lefts) or not nanosecond_stamps(lefts + rights):
        return pairs
    left_stamps = np.array([k[1] for k in lefts], np.int64)
    right_stamps = np.array([k[1] for k in rights], np.int64)
    if len(left_stamps) < 2 or not len(right_stamps):
        return pairs
    tolerance = np.median(np.diff(left_stamps)) / 4
    pairs, taken = [], set()
    for key, stamp in zip(lefts, left_stamps):
        nearest = int(np.argmin(np.abs(right_stamps - stamp)))
        if abs(right_stamps[nearest] - stamp) <= tolerance and nearest not in taken:
            taken.add(nearest)
            pairs.append((key, rights[nearest]))
    return pairs


class FolderPairs:
    """Two folders of frames (``cam0/``, ``cam1/``; or EuRoC's ``mav0/cam0`` and
    ``mav0/cam1`` as they ship) as a video: the frames of one moment, in time order, each
    pair read as ``vsmatch run`` reads one (16-bit frames keep one scale). Frames named by
    their time stamp in nanoseconds give the frame rate. Files that are no images and
    frames that cannot be read are skipped (:meth:`skipped` says which)."""

    def __init__(self, left: str, right: str):
        (lefts, skipped_l, self.left_root), (rights, skipped_r, self.right_root) = (
            camera_folder(left), camera_folder(right))
        order = sorted(lefts), sorted(rights)
        self.keys = paired_keys(*order)
        if not self.keys:
            raise FrameSourceError(f"{left} and {right}: no frames of the same name or "
                                   "time stamp")
        self.paths = [(lefts[a], rights[b]) for a, b in self.keys]
        self.not_frames = [str(Path(left) / n) for n in skipped_l] + [
            str(Path(right) / n) for n in skipped_r]
        self.unreadable: list[str] = []
        alone = len(lefts) + len(rights) - 2 * len(self.keys)
        self._unpaired = None if not alone else (
            f"{left} has {len(lefts)} frames, {right} {len(rights)}: {alone} frame"
            f"{'s' if alone > 1 else ''} without a partner of the same name or time stamp, "
            "counted as failed")

    def __iter__(self):
        for left, right in self.paths:
            self.current = left  # the left frame of the pair last given, for messages
            try:
                yield io.read_pair(left, right)
            except io.ImageError as exc:  # a frame cut short by a camera that stopped
                self.unreadable.append(str(exc))

    def sensor_files(self) -> list[str] | None:
        """Both cameras' ``sensor.yaml`` (EuRoC), where both folders hold one."""
        files = [root / "sensor.yaml" for root in (self.left_root, self.right_root)]
        return [str(f) for f in files] if all(f.is_file() for f in files) else None

    def fps(self) -> float:
        stamps = [k[1] for k, _ in self.keys]
        if len(stamps) < 2 or not nanosecond_stamps([k for k, _ in self.keys]):
            return 0.0
        step = float(np.median(np.diff(stamps)))
        return 1e9 / step if step > 0 else 0.0

    def skipped(self) -> list[str]:
        """One line each: the files that are not frames, the frames that could not be read."""
        lines = []
        if self.not_frames:
            shown = ", ".join(self.not_frames[:3]) + (", ..." if len(self.not_frames) > 3
                                                      else "")
            lines.append(f"skipped {len(self.not_frames)} file"
                         f"{'s' if len(self.not_frames) > 1 else ''} that are not images: "
                         f"{shown}")
        lines += [f"skipped a frame: {problem}" for problem in self.unreadable]
        return lines

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


#: The files ``--frames`` holds (NNNNNN.pfm and NNNNNN_confidence.pfm), and
#: ``--depth-frames`` and ``--cloud-frames`` (NNNNNN.pfm or .png, NNNNNN.ply).
FRAME_FILE = re.compile(r"\d{6}((_confidence)?\.pfm|\.png|\.ply)")


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
        for picture in pictures:  # made outside the silenced blocks: a progress bar shows
            with io.native_stderr_silenced():
                if writer is None:
                    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*codec), fps,
                                             picture.shape[1::-1])
                    if not writer.isOpened():
                        raise OSError("OpenCV cannot write this video")
                writer.write(picture)
            count += 1
    finally:
        if writer is not None:
            with io.native_stderr_silenced():
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
