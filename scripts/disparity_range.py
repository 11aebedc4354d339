"""How the automatic disparity range (--max-disp auto) covers the true range, per scene.

For every scene of the datasets found under the data root: the largest non-occluded
ground-truth disparity, the sparse and dense estimates, the range chosen, the official
range, and whether the chosen one covers the truth. Exit status 1 if a scene is not
covered.

    python scripts/disparity_range.py [--data-root DIR]
"""

from __future__ import annotations

import argparse
import sys
import time

from vsmatch import datasets
from vsmatch.search_range import estimate_disparity_range

DATASETS = ("middlebury2", "middlebury-third", "middlebury2014-quarter", "kitti2015")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    print(f"{'dataset':<24}{'scene':<13}{'true max':>9}{'sparse':>8}{'dense':>8}"
          f"{'auto':>6}{'official':>9}{'covered':>8}{'seconds':>8}")
    uncovered = 0
    for name, scenes in datasets.load_available(DATASETS, args.data_root).items():
        for scene in scenes:
            mask = scene.masks.get("nonocc", scene.masks["all"])
            true_max = float(scene.ground_truth[mask].max())
            start = time.perf_counter()
            found = estimate_disparity_range(scene.left, scene.right)
            seconds = time.perf_counter() - start
            covered = found.min_disp <= scene.ground_truth[mask].min() and \
                true_max <= found.max_disp
            uncovered += not covered
            fmt = lambda v: "-" if v is None else f"{v:.1f}"  # noqa: E731
            print(f"{name:<24}{scene.name:<13}{true_max:9.1f}{fmt(found.sparse):>8}"
                  f"{fmt(found.dense):>8}{found.max_disp:6d}{scene.max_disp:9d}"
                  f"{'yes' if covered else 'NO':>8}{seconds:8.2f}", flush=True)
    return 1 if uncovered else 0


if __name__ == "__main__":
    sys.exit(main())
