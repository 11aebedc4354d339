"""What a range found from the pair costs when it reaches below 0: the standard Middlebury
2014 quarter-size scenes cropped against each other so that half their range is negative
(as a verged rig sees), matched with the true range given and with the range found.

    python scripts/range_bottom.py [--data-root DIR] [--config NAME]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from vsmatch import datasets, pipeline
from vsmatch.search_range import estimate_disparity_range

HARD = ("Vintage",)


def cropped(scene, shift: int):
    """Left x + shift against right x: every disparity moves by -shift; unknown stays."""
    mask = scene.masks["nonocc"][:, shift:]
    gt = scene.ground_truth[:, shift:]
    truth = np.where(gt > 0, gt - shift, np.nan)
    return (np.ascontiguousarray(scene.left[:, shift:]),
            np.ascontiguousarray(scene.right[:, :-shift]), truth, mask & np.isfinite(truth))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--config", default="default")
    args = parser.parse_args()
    given_all, found_all = [], []
    print(f"{'scene':<12}{'truth':>12}{'found':>12}{'bad 2.0 given':>15}{'found':>8}")
    for scene in datasets.load_dataset("middlebury2014-quarter", args.data_root):
        if scene.name in HARD:
            continue
        shift = round(float(scene.ground_truth[scene.masks["nonocc"]].max()) / 2)
        left, right, truth, known = cropped(scene, shift)
        found = estimate_disparity_range(left, right)
        figures = []
        for low, high in ((scene.min_disp - shift, scene.max_disp - shift),
                          (found.min_disp, found.max_disp)):
            disp = pipeline.match(left, right, min_disp=low, max_disp=high, config=args.config)
            figures.append(100 * float(np.mean(~(np.abs(disp - truth) <= 2.0)[known])))
        given_all.append(figures[0])
        found_all.append(figures[1])
        low, high = math.floor(truth[known].min()), math.ceil(truth[known].max())
        print(f"{scene.name:<12}{f'{low}..{high}':>12}{f'{found.min_disp}..{found.max_disp}':>12}"
              f"{figures[0]:>15.2f}{figures[1]:>8.2f}", flush=True)
    print(f"{'mean':<36}{np.mean(given_all):>15.2f}{np.mean(found_all):>8.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
