"""How the confidence threshold of --depth and --cloud trades wrong points for kept ones.

For each Middlebury 2014 scene (its calib.txt gives f, baseline and doffs) and each
threshold: the points `vsmatch run --cloud` would write (confidence at or above it), the
share of them whose depth is more than 3 % off the ground truth's (among those whose ground
truth is known), and how many there are against the scene's non-occluded pixels.

    python scripts/cloud_threshold.py [--data-root DIR] [--dataset middlebury2014-quarter]
        [--config default]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from vsmatch import datasets, evaluation, geometry, pipeline

THRESHOLDS = (0.0, 0.5, 0.8, 0.85, 0.88, 0.9, 0.92, 0.95)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--dataset", default="middlebury2014-quarter")
    parser.add_argument("--config", default="default")
    args = parser.parse_args()
    folder = datasets.dataset_folder(args.dataset, args.data_root)
    scenes = datasets.load_dataset(args.dataset, args.data_root)
    wrong = {t: [] for t in THRESHOLDS}
    kept = {t: [] for t in THRESHOLDS}
    print(f"{'scene':<13}" + "".join(f"{'t=' + format(t, 'g'):>14}" for t in THRESHOLDS))
    for scene in scenes:
        calib = geometry.read_calibration(Path(folder) / scene.name / "calib.txt")
        result = pipeline.run(scene.left, scene.right, max_disp=scene.max_disp,
                              config=args.config)
        cells = []
        for t in THRESHOLDS:
            written = np.where(result.confidence >= t, result.disparity, np.float32(np.nan))
            share_wrong, share_kept = evaluation.cloud_measures(written, scene, calib)
            wrong[t].append(100.0 * share_wrong)
            kept[t].append(100.0 * share_kept)
            cells.append(f"{wrong[t][-1]:6.1f}%/{kept[t][-1]:4.0f}%")
        print(f"{scene.name:<13}" + "".join(f"{c:>14}" for c in cells), flush=True)
    print(f"{'mean':<13}" + "".join(f"{np.mean(wrong[t]):6.1f}%/{np.mean(kept[t]):4.0f}%"
                                    .rjust(14) for t in THRESHOLDS))
    print("(points > 3 % off in depth / points written against non-occluded pixels)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
