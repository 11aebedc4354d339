"""What a confidence value means: the share of pixels right in each band of confidence.

For each dataset (every scene, the hard ones too), a config's confidence on the evaluated
pixels (non-occluded, with ground truth) in bands, each band's share of those pixels and the
share of them right by the dataset's headline measure (bad 1.0, bad 2.0 on Middlebury
2014, D1 on KITTI). ``--dark``: the views darkened as ``scripts/dark_views.py`` makes them
(gain 0.3, noise 1.5).

    python scripts/reliability.py CONFIG [section.key=value ...] [--dark] [--data-root DIR]
"""

from __future__ import annotations

import argparse

import numpy as np

from dark_views import dark_scene
from datasets_table import DATASETS
from vsmatch import datasets, evaluation, pipeline
from vsmatch.config import with_changes

BANDS = (0.0, 0.02, 0.2, 0.5, 0.8, 0.88, 0.95, 1.0001)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config")
    parser.add_argument("changes", nargs="*", metavar="section.key=value")
    parser.add_argument("--dark", action="store_true")
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    cfg = with_changes(args.config, args.changes)
    print("dataset: " + ", ".join(f"[{lo:g}, {min(hi, 1):g}{']' if hi > 1 else ')'}"
                                  for lo, hi in zip(BANDS[:-1], BANDS[1:]))
          + ": share of the pixels / share of them right (%)")
    for name in DATASETS:
        scoring = evaluation.scoring_for(name, None)
        pixels, right = np.zeros(len(BANDS) - 1), np.zeros(len(BANDS) - 1)
        for seed, scene in enumerate(datasets.load_dataset(name, args.data_root)):
            if args.dark:
                scene = dark_scene(scene, 0.3, 1.5, seed)
            result = pipeline.run(scene.left, scene.right, min_disp=scene.min_disp,
                                  max_disp=scene.max_disp, config=cfg)
            evaluated = evaluation.headline_mask(scene) & np.isfinite(scene.ground_truth)
            good = ~scoring.bad_map(result.disparity, scene.ground_truth)
            band = np.digitize(result.confidence[evaluated], BANDS) - 1
            pixels += np.bincount(band, minlength=len(BANDS))[:len(BANDS) - 1]
            right += np.bincount(band, weights=good[evaluated],
                                 minlength=len(BANDS))[:len(BANDS) - 1]
        cells = [f"{100 * n / pixels.sum():.1f} / {100 * r / max(n, 1):.1f}"
                 for n, r in zip(pixels, right)]
        print(f"{name}: " + ", ".join(cells), flush=True)


if __name__ == "__main__":
    main()
