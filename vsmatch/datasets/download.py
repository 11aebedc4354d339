"""Fetching Middlebury 2014 (MiddEval3) into a data root, with pooch.

Two archives per resolution: ``MiddEval3-data-{Q,H,F}.zip`` (images and ``calib.txt`` of
the training and test scenes) and ``MiddEval3-GT0-{Q,H,F}.zip`` (the left ground truth
and masks of the training scenes), both unpacking to ``MiddEval3/training{Q,H,F}/<scene>/``.
The training scenes are merged into ``DIR/middlebury2014-<size>/<scene>/`` (the layout
``vsmatch eval`` reads). The archives are cached in ``DIR/.downloads/`` until the dataset
is complete, so a re-run after a failure fetches only what it lacks; the dataset folder
appears whole or not at all (it is built beside its place and renamed into it).
"""

from __future__ import annotations

import glob
import os
import shutil
import tempfile
import zipfile
from pathlib import Path
from urllib.parse import unquote, urlparse

from ..io import current_umask, output_folder
from .base import DatasetError
from .middlebury2014 import SCENE_FILES, missing_files

BASE_URL = "https://vision.middlebury.edu/stereo/submit3/zip"
RESOLUTIONS = {"Q": "quarter", "H": "half", "F": "full"}
CACHE = ".downloads"


#: What is unpacked of a training scene: what the reader needs, and the right view's
#: ground truth where an archive has it.
KEPT_FILES = (*SCENE_FILES, "disp1GT.pfm", "mask1nocc.png")


#: The most the training scenes of a resolution may unpack to (MB): about 4x what the
#: real ones give (quarter size: 26 MB of training scenes), so an archive member that
#: inflates past it (a zip bomb, a wrong archive) is refused while it is written.
MAX_UNPACKED_MB = {"Q": 200, "H": 800, "F": 3200}
CHUNK = 1 << 20


class DownloadError(DatasetError):
    """A download or an archive that failed; the message is one line."""


def archive_names(resolution: str) -> list[str]:
    return [f"MiddEval3-data-{resolution}.zip", f"MiddEval3-GT0-{resolution}.zip"]


def dataset_path(to: str | Path, resolution: str) -> Path:
    return Path(to) / f"middlebury2014-{RESOLUTIONS[resolution]}"


def is_complete(folder: Path) -> bool:
    """A dataset folder with at least one scene, each with every file it needs."""
    if not folder.is_dir():
        return False
    scenes = [p for p in folder.iterdir() if p.is_dir()]
    return bool(scenes) and not any(missing_files(p) for p in scenes)


def download_middlebury2014(resolution: str, to: str | Path, *, mirror: str | None = None,
                            progress: bool = True, retries: int = 2) -> tuple[Path, bool]:
    """Fetch and unpack the training scenes; returns the dataset folder and whether
    anything was fetched (False when it was already complete)."""
    if resolution not in RESOLUTIONS:
        raise DownloadError(f"unknown resolution '{resolution}' (use Q, H or F)")
    target = dataset_path(to, resolution)
    if is_complete(target):
        return target, False
    if target.exists():
        raise DownloadError(f"{target} exists but is not a complete dataset; move it away "
                            "and run again")
    to = Path(to)
    cache = to / CACHE
    with output_folder(to):
        remove_stale_staging(target)
        try:
            archives = [_fetch(name, mirror or BASE_URL, cache, progress, retries)
                        for name in archive_names(resolution)]
            _unpack_training(archives, resolution, target)
        except BaseException:
            # Archives fetched whole are kept for the next run; an empty cache is not.
            if cache.is_dir() and not any(cache.iterdir()):
                cache.rmdir()
            raise
    shutil.rmtree(cache, ignore_errors=True)
    return target, True


def _local_mirror(base_url: str) -> Path | None:
    """The folder a ``--mirror`` names (a path, or a ``file://`` URL), or None for a URL
    to download from."""
    if base_url.startswith("file://"):
        return Path(unquote(urlparse(base_url).path))
    if "://" not in base_url:
        return Path(base_url)
    return None


def _fetch(name: str, base_url: str, cache: Path, progress: bool, retries: int) -> Path:
    """One archive in the cache (downloaded unless there already, or copied from a mirror
    folder); pooch writes it under a temporary name and renames it when complete."""
    folder = _local_mirror(base_url)
    if folder is not None:
        source = folder / name
        if not folder.is_dir():
            raise DownloadError(f"--mirror {base_url}: no such folder (give a folder that "
                                "holds the archives, or an http(s) or ftp URL)")
        if not source.is_file():
            raise DownloadError(f"{source}: not in the mirror folder")
        target = cache / name
        if not target.is_file():
            cache.mkdir(parents=True, exist_ok=True)
            partial = cache / f".{name}.partial"
            shutil.copyfile(source, partial)
            os.replace(partial, target)
        return target
    import pooch
    import requests

    pooch.get_logger().setLevel("WARNING")
    fetcher = pooch.create(path=cache, base_url=base_url.rstrip("/") + "/",
                           registry={name: None}, retry_if_failed=retries)
    url = f"{base_url.rstrip('/')}/{name}"
    try:
        return Path(fetcher.fetch(name, progressbar=progress))
    except requests.HTTPError as exc:
        status = exc.response.status_code if exc.response is not None else "?"
        raise DownloadError(f"{url}: the server answered HTTP {status}") from None
    except requests.RequestException as exc:
        reason = type(exc).__name__
        raise DownloadError(f"{url}: download failed ({reason}); check the network or "
                            "give --mirror") from None


def _staging_prefix(target: Path) -> str:
    return f".{target.name}."


def remove_stale_staging(target: Path) -> None:
    """Remove the hidden staging folders that a killed unpack of ``target`` left (an
    unpack that fails removes its own). Only for when no download is under way."""
    if target.parent.is_dir():
        for folder in target.parent.glob(glob.escape(_staging_prefix(target)) + "*"):
            if folder.is_dir():
                shutil.rmtree(folder, ignore_errors=True)


def _unpack_training(archives: list[Path], resolution: str, target: Path) -> None:
    """Merge ``MiddEval3/training<R>/<scene>/`` of every archive into ``target``."""
    prefix = f"MiddEval3/training{resolution}/"
    staging = Path(tempfile.mkdtemp(prefix=_staging_prefix(target), dir=target.parent))
    budget = [MAX_UNPACKED_MB[resolution] * 2**20]  # bytes still allowed, shared
    try:
        for archive in archives:
            try:
                with zipfile.ZipFile(archive) as zf:
                    for member in zf.infolist():
                        _extract(zf, member, prefix, staging, budget)
            except (zipfile.BadZipFile, EOFError, OSError) as exc:
                archive.unlink(missing_ok=True)  # fetch it again next time
                raise DownloadError(f"{archive.name}: not a readable zip archive ({exc}); "
                                    "it was removed, run again to fetch it anew") from None
        scenes = sorted(p for p in staging.iterdir() if p.is_dir())
        if not scenes:
            raise DownloadError(f"the archives hold no {prefix} scenes")
        for scene in scenes:
            lacking = missing_files(scene)
            if lacking:
                raise DownloadError(f"scene {scene.name} lacks {', '.join(lacking)} after "
                                    f"unpacking {', '.join(a.name for a in archives)}")
        # mkdtemp makes the folder private (0700); give it the mode any new folder gets.
        staging.chmod(0o777 & ~current_umask())
        staging.rename(target)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _extract(zf: zipfile.ZipFile, member: zipfile.ZipInfo, prefix: str, into: Path,
             budget: list[int]) -> None:
    """One archive member under ``prefix``, if it is a training scene's file, counted
    against ``budget`` (bytes) as it is written, whatever its header claims."""
    name = member.filename
    if member.is_dir() or not name.startswith(prefix):
        return
    parts = name[len(prefix):].split("/")
    if len(parts) != 2 or parts[1] not in KEPT_FILES or parts[0] in ("", ".", ".."):
        return  # only the files the reader uses, and nothing outside the scene folder
    folder = into / parts[0]
    folder.mkdir(exist_ok=True)
    with zf.open(member) as src, open(folder / parts[1], "wb") as dst:
        while chunk := src.read(CHUNK):
            budget[0] -= len(chunk)
            if budget[0] < 0:
                raise DownloadError(f"{member.filename}: the archive unpacks to more than "
                                    f"the dataset's known size; refused")
            dst.write(chunk)
