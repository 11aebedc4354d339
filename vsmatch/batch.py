"""Matching many pairs: a CSV list or a folder of pairs, failures collected, not fatal."""

from __future__ import annotations

import csv
import functools
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from . import io, pipeline
from .config import Config
from .executors import Executor
from .executors.serial import SerialExecutor
from .search_range import estimate_disparity_range

IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".ppm", ".pgm")

#: File names of a pair inside a scene folder, tried in order (Middlebury v2, 2014, 2005/6).
PAIR_NAMES = (("imL", "imR"), ("im0", "im1"), ("view1", "view5"), ("left", "right"))

#: Folders of a recording: left and right frames of the same name (KITTI, KITTI raw,
#: KITTI 2012, and plain left/right).
PAIRED_FOLDERS = (("image_2", "image_3"), ("image_02/data", "image_03/data"),
                  ("colored_0", "colored_1"), ("left", "right"))

#: Suffixes of a pair of files side by side in one folder: NAME_left.png, NAME_right.png.
PAIR_SUFFIXES = (("_left", "_right"), ("_L", "_R"))


class BatchError(ValueError):
    """A batch source that cannot be read; the message is one line."""


@dataclass(frozen=True)
class PairJob:
    left: Path
    right: Path
    output: Path
    max_disp: int | None  # None: estimated from the pair


def read_pair_list(csv_path: str | Path, default_max_disp: int | None) -> list[PairJob]:
    """Rows ``left,right,output[,max_disp]``; relative paths are relative to the CSV's
    folder. A first row starting with ``left`` is a header; blank rows are skipped.
    ``max_disp`` may be ``auto``; an empty one takes ``default_max_disp``."""
    csv_path = Path(csv_path)
    base = csv_path.parent
    jobs = []
    try:
        with csv_path.open(newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise BatchError(f"{csv_path}: cannot read the pair list ({exc})") from None
    for number, row in enumerate(rows, start=1):
        row = [cell.strip() for cell in row]
        if not any(row) or (number == 1 and row[0].lower() == "left"):
            continue
        if len(row) not in (3, 4) or not all(row[:3]):
            raise BatchError(f"{csv_path}, line {number}: expected left,right,output[,max_disp]")
        max_disp = default_max_disp
        if len(row) == 4 and row[3]:
            max_disp = _max_disp_cell(row[3], f"{csv_path}, line {number}")
        left, right, output = (base / cell for cell in row[:3])
        jobs.append(PairJob(left, right, output, max_disp))
    return jobs


def _max_disp_cell(text: str, where: str) -> int | None:
    if text.lower() == "auto":
        return None
    try:
        value = int(text)
    except ValueError:
        raise BatchError(f"{where}: max_disp '{text}' is not a whole number or 'auto'") from None
    if value <= 0:
        raise BatchError(f"{where}: max_disp {value} must be at least 1")
    return value


def _image_with_stem(folder: Path, stem: str) -> Path | None:
    for ext in IMAGE_EXTENSIONS:
        for candidate in (folder / f"{stem}{ext}", folder / f"{stem}{ext.upper()}"):
            if candidate.is_file():
                return candidate
    return None


def find_pairs(folder: str | Path, out_dir: str | Path, *, max_disp: int | None,
               suffix: str = ".pfm") -> list[PairJob]:
    """The pairs in ``folder``: the frames of a recording (:func:`recording_pairs`), else
    each sub-folder holding a pair named as in :data:`PAIR_NAMES`, and files named
    ``NAME_left`` / ``NAME_right`` (or ``_L`` / ``_R``). Each pair's output is
    ``out_dir/NAME`` + ``suffix``."""
    folder, out_dir = Path(folder), Path(out_dir)
    jobs = recording_pairs(folder, out_dir, max_disp=max_disp, suffix=suffix)
    if jobs:
        return jobs
    for sub in sorted(p for p in folder.iterdir() if p.is_dir()):
        for left_stem, right_stem in PAIR_NAMES:
            left, right = _image_with_stem(sub, left_stem), _image_with_stem(sub, right_stem)
            if left and right:
                jobs.append(PairJob(left, right, out_dir / f"{sub.name}{suffix}", max_disp))
                break
    for path in sorted(folder.iterdir()):
        if path.suffix.lower() not in IMAGE_EXTENSIONS:
            continue
        for left_tag, right_tag in PAIR_SUFFIXES:
            if path.stem.endswith(left_tag):
                name = path.stem[: -len(left_tag)]
                right = _image_with_stem(folder, name + right_tag)
                if right:
                    jobs.append(PairJob(path, right, out_dir / f"{name}{suffix}", max_disp))
    return jobs


def recording_pairs(folder: Path, out_dir: Path, *, max_disp: int | None,
                    suffix: str) -> list[PairJob]:
    """The frames of a recording in ``folder`` (see :data:`PAIRED_FOLDERS`): each left
    image with a right image of the same name, in name order; outputs named after them."""
    for left_name, right_name in PAIRED_FOLDERS:
        left_dir, right_dir = folder / left_name, folder / right_name
        if left_dir.is_dir() and right_dir.is_dir():
            frames = sorted(p for p in left_dir.iterdir()
                            if p.suffix.lower() in IMAGE_EXTENSIONS
                            and (right_dir / p.name).is_file())
            return [PairJob(p, right_dir / p.name, out_dir / f"{p.stem}{suffix}", max_disp)
                    for p in frames]
    return []


def match_pair(job: PairJob, config: Config) -> None:
    """Read, match and write one pair; raises with a one-line message on failure."""
    io.check_distinct_paths([job.left, job.right], [job.output])
    left, right = io.read_pair(job.left, job.right)
    max_disp = job.max_disp
    try:
        if max_disp is None:
            max_disp = estimate_disparity_range(left, right).max_disp
        pipeline.check_pair(left, right, max_disp, config)
    except ValueError as exc:
        raise ValueError(f"{job.left}: {exc}") from None
    disp = pipeline.match(left, right, max_disp=max_disp, config=config)
    io.write_disparity(job.output, disp)


def _match_pair_quietly(job: PairJob, *, config: Config) -> str | None:
    """:func:`match_pair` in a worker: the error message, or None."""
    try:
        match_pair(job, config)
    except (ValueError, OSError) as exc:
        return " ".join(str(exc).split())
    return None


def run_batch(jobs: list[PairJob], config: Config, *, executor: Executor | None = None,
              on_done: Callable[[PairJob, str | None], None] | None = None
              ) -> list[tuple[PairJob, str]]:
    """Match every job; returns the failures as ``(job, message)``, in job order.

    The pairs run on ``executor`` (default: one after the other in this process), one
    task per pair. ``on_done(job, error)`` follows each pair as it completes. Temporary
    files that a killed task left beside its output are removed at the end.
    """
    failures = {}
    task = functools.partial(_match_pair_quietly, config=config)
    try:
        with executor or SerialExecutor() as runner:
            for job, error in runner.map_unordered(task, jobs):
                if error is not None:
                    failures[job] = error
                if on_done is not None:
                    on_done(job, error)
    finally:
        for job in jobs:
            io.remove_stale_temporaries(job.output)
    return [(job, failures[job]) for job in jobs if job in failures]
