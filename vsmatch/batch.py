"""Matching many pairs: a CSV list or a folder of pairs, failures collected, not fatal."""

from __future__ import annotations

import csv
import functools
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from . import io, pipeline
from .confidence import keep_confident
from .config import Config
from .executors import Executor
from .executors.serial import SerialExecutor
from .search_range import resolve_range


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
    source: str = ""  # where the job was listed ("pairs.csv, line 3"), for messages

    def describe(self) -> str:
        return self.source or str(self.left)


@dataclass(frozen=True)
class PairOutcome:
    """What one pair gave: an error message (None on success), the range and seconds."""

    error: str | None
    min_disp: int | None = None
    max_disp: int | None = None
    seconds: float = 0.0


def job_outputs(job: PairJob, with_confidence: bool) -> list[Path]:
    """The files a job writes: its disparity, and its confidence when asked."""
    return [job.output] + ([confidence_path(job.output)] if with_confidence else [])


def check_plan(jobs: list[PairJob], *, with_confidence: bool = False,
               sources: tuple[Path, ...] = ()) -> None:
    """Refuse, before any work, a plan in which an output (a disparity, or a confidence
    file when asked) names any row's input or a ``sources`` file (the pair list itself),
    also through links, or two rows write one file; the message names both rows. Linear
    in the rows: each path is looked up by its resolved name and by its file on disk."""
    inputs: dict[object, tuple[PairJob | None, Path]] = {}
    for path in sources:
        for key in (io.resolved(path), _file_key(Path(path))):
            if key is not None:
                inputs.setdefault(key, (None, Path(path)))
    for job in jobs:
        for path in (job.left, job.right):
            for key in (io.resolved(path), _file_key(path)):
                if key is not None:
                    inputs.setdefault(key, (job, path))
    outputs: dict[object, PairJob] = {}
    for job in jobs:
        for output in job_outputs(job, with_confidence):
            keys = [k for k in (io.resolved(output), _file_key(output)) if k is not None]
            for key in keys:
                if key in inputs:
                    other, path = inputs[key]
                    whose = (f"the pair list {path}" if other is None
                             else f"the input {path} of {other.describe()}")
                    raise BatchError(f"{job.describe()}: the output {output} would overwrite "
                                     f"{whose}")
                if key in outputs and outputs[key] is not job:
                    raise BatchError(f"{job.describe()} and {outputs[key].describe()} both "
                                     f"write {output}")
            for key in keys:
                outputs[key] = job


def writable(folder: Path) -> bool:
    return os.access(folder, os.W_OK)


def check_output_files(jobs: list[PairJob]) -> list[Path]:
    """Refuse, before any work, an output that is not a .pfm or .png file name, or whose
    folder cannot be made or written; the message names the row. Returns the output
    folders that do not exist yet (the caller makes them once the whole plan holds)."""
    missing: dict[Path, None] = {}
    for job in jobs:
        output = job.output
        if output.suffix.lower() not in io.DISPARITY_FORMATS:
            raise BatchError(f"{job.describe()}: the output {output} must end in .pfm "
                             "(float32) or .png (16-bit)")
        if output.is_dir():
            raise BatchError(f"{job.describe()}: the output {output} is a folder")
        folder = output.parent
        try:
            io.followed_folder(folder)
        except OSError as exc:
            raise BatchError(f"{job.describe()}: the output folder {exc}") from None
        existing = folder
        while not existing.exists() and existing != existing.parent:
            existing = existing.parent
        if not existing.is_dir():
            raise BatchError(f"{job.describe()}: the output folder {folder} cannot be made "
                             f"({existing} is a file)")
        if not writable(existing):
            raise BatchError(f"{job.describe()}: the output folder {existing} is not "
                             "writable")
        if existing != folder:
            missing[folder] = None
    return list(missing)


def _file_key(path: Path) -> tuple | None:
    """(device, inode) of an existing file: the same file under two names (hard links)."""
    try:
        info = path.stat()
    except OSError:
        return None
    return info.st_dev, info.st_ino


def read_pair_list(csv_path: str | Path, default_max_disp: int | None) -> list[PairJob]:
    """Rows ``left,right,output[,max_disp]``; relative paths are relative to the CSV's
    folder. A first row starting with ``left`` is a header; blank rows are skipped.
    ``max_disp`` may be ``auto``; an empty one takes ``default_max_disp``."""
    csv_path = Path(csv_path)
    base = csv_path.parent
    jobs = []
    try:
        with csv_path.open(newline="", encoding="utf-8-sig") as fh:  # a BOM is dropped
            rows = list(csv.reader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise BatchError(f"{csv_path}: cannot read the pair list ({exc})") from None
    for number, row in enumerate(rows, start=1):
        row = [cell.strip() for cell in row]
        if not any(row) or (number == 1 and row[0].lower() == "left"):
            continue
        if len(row) not in (3, 4) or not all(row[:3]):
            raise BatchError(f"{csv_path}, line {number}: expected left,right,output[,max_disp]")
        if any("\0" in cell for cell in row):
            raise BatchError(f"{csv_path}, line {number}: a cell holds a NUL byte")
        max_disp = default_max_disp
        if len(row) == 4 and row[3]:
            max_disp = _max_disp_cell(row[3], f"{csv_path}, line {number}")
        left, right, output = (base / cell for cell in row[:3])
        jobs.append(PairJob(left, right, output, max_disp, f"{csv_path}, line {number}"))
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
    for ext in io.IMAGE_EXTENSIONS:
        for candidate in (folder / f"{stem}{ext}", folder / f"{stem}{ext.upper()}"):
            if candidate.is_file():
                return candidate
    return None


def find_pairs(folder: str | Path, out_dir: str | Path, *, max_disp: int | None,
               suffix: str = ".pfm") -> tuple[list[PairJob], list[Path]]:
    """The pairs in ``folder``: the frames of a recording (:func:`recording_pairs`), else
    each sub-folder holding a pair named as in :data:`PAIR_NAMES`, and files named
    ``NAME_left`` / ``NAME_right`` (or ``_L`` / ``_R``). Each pair's output is
    ``out_dir/NAME`` + ``suffix``. Also returns a recording's frames that have no
    partner in the other view."""
    folder, out_dir = Path(folder), Path(out_dir)
    jobs, unpaired = recording_pairs(folder, out_dir, max_disp=max_disp, suffix=suffix)
    if jobs or unpaired:
        return jobs, unpaired
    for sub in sorted(p for p in folder.iterdir() if p.is_dir()):
        for left_stem, right_stem in PAIR_NAMES:
            left, right = _image_with_stem(sub, left_stem), _image_with_stem(sub, right_stem)
            if left and right:
                jobs.append(PairJob(left, right, out_dir / f"{sub.name}{suffix}", max_disp))
                break
    for path in sorted(folder.iterdir()):
        if path.suffix.lower() not in io.IMAGE_EXTENSIONS:
            continue
        for left_tag, right_tag in PAIR_SUFFIXES:
            if path.stem.endswith(left_tag):
                name = path.stem[: -len(left_tag)]
                right = _image_with_stem(folder, name + right_tag)
                if right:
                    jobs.append(PairJob(path, right, out_dir / f"{name}{suffix}", max_disp))
    return jobs, []


def recording_pairs(folder: Path, out_dir: Path, *, max_disp: int | None,
                    suffix: str) -> tuple[list[PairJob], list[Path]]:
    """The frames of a recording in ``folder`` (see :data:`PAIRED_FOLDERS`): each left
    image with a right image of the same name, in name order, outputs named after them;
    and the frames of either view that have no partner in the other."""
    for left_name, right_name in PAIRED_FOLDERS:
        left_dir, right_dir = folder / left_name, folder / right_name
        if left_dir.is_dir() and right_dir.is_dir():
            lefts, rights = (
                {p.name: p for p in d.iterdir() if p.suffix.lower() in io.IMAGE_EXTENSIONS}
                for d in (left_dir, right_dir))
            jobs = [PairJob(lefts[name], rights[name],
                            out_dir / f"{lefts[name].stem}{suffix}", max_disp)
                    for name in sorted(lefts.keys() & rights.keys())]
            unpaired = sorted(lefts[n] for n in lefts.keys() - rights.keys()) + sorted(
                rights[n] for n in rights.keys() - lefts.keys())
            return jobs, unpaired
    return [], []


def confidence_path(output: Path) -> Path:
    """Where a pair's confidence goes beside its disparity: NAME_confidence.pfm."""
    return output.with_name(f"{output.stem}_confidence.pfm")


def match_pair(job: PairJob, config: Config, *, with_confidence: bool = False,
               min_confidence: float | None = None) -> PairOutcome:
    """Read, match and write one pair (and its confidence, when asked; pixels below
    ``min_confidence`` marked invalid, when given); raises with a one-line message on
    failure. A range a PNG output cannot hold is refused before the match."""
    start = time.perf_counter()
    io.check_distinct_paths([job.left, job.right], [job.output])
    if job.max_disp is not None:
        _check_png_range(job.output, 0, job.max_disp)
    left, right = io.read_pair(job.left, job.right, max_mb=config.memory.max_mb,
                               max_megapixels=config.memory.max_megapixels)
    try:
        pipeline.check_views(left, right, config)
        searched = resolve_range(left, right, max_disp=job.max_disp)
        min_disp, max_disp = searched.min_disp, searched.max_disp
        _check_png_range(job.output, min_disp, max_disp)
        pipeline.check_pair(left, right, max_disp, config, min_disp)
    except ValueError as exc:
        raise ValueError(f"{job.left}: {exc}") from None
    result = pipeline.run(left, right, max_disp=max_disp, min_disp=min_disp, config=config)
    disp = result.disparity
    if min_confidence is not None:
        disp = keep_confident(disp, result.confidence, min_confidence)
    with io.all_or_none():
        io.write_disparity(job.output, disp)
        if with_confidence:
            io.write_confidence(confidence_path(job.output), result.confidence)
    return PairOutcome(None, min_disp, max_disp, time.perf_counter() - start)


def _check_png_range(path: Path, min_disp: int, max_disp: int) -> None:
    problem = io.png_range_problem(path, min_disp, max_disp)
    if problem is not None:
        raise ValueError(problem)


def _match_pair_quietly(job: PairJob, *, config: Config, **options) -> PairOutcome:
    """:func:`match_pair` in a worker: what it gave, its error as a message."""
    try:
        return match_pair(job, config, **options)
    except (ValueError, OSError) as exc:
        return PairOutcome(" ".join(str(exc).split()))


def run_batch(jobs: list[PairJob], config: Config, *, executor: Executor | None = None,
              on_done: Callable[[PairJob, PairOutcome], None] | None = None,
              with_confidence: bool = False, min_confidence: float | None = None
              ) -> list[tuple[PairJob, str]]:
    """Match every job; returns the failures as ``(job, message)``, in job order.

    The pairs run on ``executor`` (default: one after the other in this process), one
    task per pair. ``on_done(job, outcome)`` follows each pair as it completes. Temporary
    files that a killed task left beside its output are removed at the end.
    """
    failures = {}
    task = functools.partial(_match_pair_quietly, config=config,
                             with_confidence=with_confidence, min_confidence=min_confidence)
    try:
        with executor or SerialExecutor() as runner:
            for job, outcome in runner.map_unordered(task, jobs):
                if isinstance(outcome, str):  # the executor's word for a task that raised
                    outcome = PairOutcome(outcome)
                if outcome.error is not None:
                    failures[job] = outcome.error
                if on_done is not None:
                    on_done(job, outcome)
    finally:
        for job in jobs:
            io.remove_stale_temporaries(job.output)
            io.remove_stale_temporaries(confidence_path(job.output))
    return [(job, failures[job]) for job in jobs if job in failures]
