"""Stereo benchmarks with ground truth: one module per layout, one registry.

The data are read at run time from a *data root*, the folder that holds one sub-folder
per dataset (``middlebury2/``, ``middlebury2014-quarter/``, ``kitti2015/``, ...): the
``--data-root`` option, else the ``VSMATCH_DATA`` environment variable, else the first of
:data:`DEFAULT_DATA_ROOTS` that exists.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from . import eth3d, kitti, middlebury2, middlebury2014, middlebury_third
from .base import DatasetError, Scene, scene_problem

__all__ = ["DATASETS", "Dataset", "DatasetError", "Scene", "dataset_folder", "load_dataset",
           "resolve_data_root"]

#: Where the data are looked for when neither --data-root nor VSMATCH_DATA is given,
#: relative to the current folder (the second fits a checkout beside ``shared/``).
DEFAULT_DATA_ROOTS = ("data", "../shared/data")

_MIDDLEBURY2014_NOTE = "vsmatch datasets download middlebury2014 --resolution {} --to DIR"
_KITTI_NOTE = ("needs a registration on the KITTI benchmark's website: download the "
               "stereo data set and unpack its training/ folder into DIR/{}/")


@dataclass(frozen=True)
class Dataset:
    """How to find, read and score one benchmark."""

    folder: str  # the dataset's folder under the data root
    load: Callable  # (folder, names or None) -> list[Scene]
    metric: str  # "bad" (Middlebury: bad-x at the threshold), "D1" or "out3" (KITTI)
    threshold: float | None  # the headline bad-x threshold (None: fixed by the metric)
    source: str  # how to get it


DATASETS = {
    "middlebury2": Dataset("middlebury2", middlebury2.load, "bad", 1.0,
                           "the Middlebury v2 evaluation files"),
    "middlebury-third": Dataset("middlebury-2005-2006-third", middlebury_third.load,
                                "bad", 1.0, "the Middlebury 2005/2006 data sets, third size"),
    **{f"middlebury2014-{size}": Dataset(f"middlebury2014-{size}", middlebury2014.load,
                                         "bad", 2.0, _MIDDLEBURY2014_NOTE.format(code))
       for size, code in (("quarter", "Q"), ("half", "H"), ("full", "F"))},
    "eth3d": Dataset("eth3d-dev", eth3d.load, "bad", 1.0,
                     "needs ETH3D's low-res two-view training scenes and their ground truth "
                     "from the ETH3D benchmark's website, one folder per scene, in "
                     "DIR/eth3d-dev/"),
    "kitti2015": Dataset("kitti2015", kitti.load_kitti2015, "D1", None,
                         _KITTI_NOTE.format("kitti2015")),
    "kitti2012": Dataset("kitti2012", kitti.load_kitti2012, "out3", None,
                         _KITTI_NOTE.format("kitti2012")),
}


def resolve_data_root(data_root: str | Path | None = None) -> list[Path]:
    """The candidate data roots, in the order they are tried."""
    if data_root is not None:
        return [Path(data_root)]
    if os.environ.get("VSMATCH_DATA"):
        return [Path(os.environ["VSMATCH_DATA"])]
    return [Path(p) for p in DEFAULT_DATA_ROOTS]


def dataset_folder(dataset: str, data_root: str | Path | None = None) -> Path:
    """The folder of ``dataset``; a one-line :class:`DatasetError` says where it looked."""
    if dataset not in DATASETS:
        raise DatasetError(f"unknown dataset '{dataset}' (known: {', '.join(DATASETS)})")
    tried = []
    for root in resolve_data_root(data_root):
        folder = root / DATASETS[dataset].folder
        if folder.is_dir():
            return folder
        tried.append(str(folder.resolve()))
    raise DatasetError(f"dataset '{dataset}' not found; looked in {', '.join(tried)} "
                       "(set --data-root or VSMATCH_DATA)")


def load_dataset(dataset: str, data_root: str | Path | None = None, names=None) -> list[Scene]:
    """The scenes of ``dataset`` (all, or those in ``names``)."""
    folder = dataset_folder(dataset, data_root)
    scenes = DATASETS[dataset].load(folder, names)
    for scene in scenes:
        problem = scene_problem(scene)
        if problem is not None:
            raise DatasetError(f"{folder / scene.name}: {problem}")
    if not scenes:
        raise DatasetError(f"dataset '{dataset}': no scenes in "
                           f"{dataset_folder(dataset, data_root)}")
    return scenes


def load_available(names, data_root: str | Path | None = None,
                   report=print) -> dict[str, list[Scene]]:
    """The scenes of each of ``names`` that is found; a missing one is reported and
    skipped (the scripts measure over whatever data a machine has)."""
    found = {}
    for name in names:
        try:
            found[name] = load_dataset(name, data_root)
        except DatasetError as exc:
            report(f"{name}: skipped ({exc})")
    return found
