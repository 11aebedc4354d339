"""The hard scenes as pictures, `default` beside `accurate`: docs/hard_scenes.jpg.

Middlebury 2014's Vintage (a blank wall; bad 2.0) and ETH3D's terrains_2l and terrains_2s
(shelves; bad 1.0): a row per scene, the left view, the ground truth, and each config's
disparity and errors (bad pixels red), as ``vsmatch eval --figure`` draws them.

    python scripts/hard_scenes_figure.py [--data-root DIR] [--out docs/hard_scenes.jpg]
"""

from __future__ import annotations

import argparse

import cv2
import numpy as np

from vsmatch import datasets, evaluation
from vsmatch.figure import results_figure

SCENES = {"middlebury2014-quarter": ["Vintage"], "eth3d": ["terrains_2l", "terrains_2s"]}
METHODS = {"default": "default", "accurate": "accurate"}


def dataset_figure(name: str, scenes: list[str], data_root: str | None) -> np.ndarray:
    """One dataset's rows, as ``vsmatch eval --figure`` draws them."""
    loaded = datasets.load_dataset(name, data_root, names=scenes)
    disparities: dict = {}
    report = evaluation.evaluate(loaded, METHODS, dataset=name, disparities=disparities)
    return results_figure(loaded, report, disparities)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--out", default="docs/hard_scenes.jpg")
    args = parser.parse_args()
    parts = [dataset_figure(name, scenes, args.data_root) for name, scenes in SCENES.items()]
    width = max(part.shape[1] for part in parts)
    padded = [cv2.copyMakeBorder(part, 0, 0, 0, width - part.shape[1], cv2.BORDER_CONSTANT,
                                 value=(255, 255, 255)) for part in parts]
    if not cv2.imwrite(args.out, np.vstack(padded), [cv2.IMWRITE_JPEG_QUALITY, 85]):
        raise SystemExit(f"could not write {args.out}")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
