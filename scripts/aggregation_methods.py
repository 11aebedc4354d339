"""Time the two aggregation methods pass by pass on middlebury2, to set the rule that
chooses between them (vsmatch.aggregation.direct_is_faster).

    python scripts/aggregation_methods.py [--data-root DIR]

Prints, per scene and pass, the mean arm length along the pass, the milliseconds of
running sums and of direct sums (median of 7), and what the rule chooses.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from vsmatch import aggregation, cost, datasets, sensitivity
from vsmatch._kernels.aggregate import sum_along_arms, sum_over_arms
from vsmatch.config import load_config
from vsmatch.images import mirrored, to_grey


def median_ms(fn, repeats=7):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return 1000 * float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--dataset", action="append", default=None,
                        help="datasets to time (repeatable; default middlebury2)")
    args = parser.parse_args()
    names = args.dataset or ["middlebury2"]
    scenes = [s for name in names for s in datasets.load_dataset(name, args.data_root)]
    cfg = load_config("default")
    print(f"{'scene':12s} {'pass':12s} {'arm':>5s} {'running':>8s} {'direct':>8s}  rule")
    for scene in scenes:
        n_disp = scene.max_disp + 1
        grey_l, grey_r = to_grey(scene.left), to_grey(scene.right)
        grad_l, theta_l = sensitivity.visual_sensitivity(grey_l)
        grad_r, theta_r = sensitivity.visual_sensitivity(grey_r)
        volume = cost.cost_volume(scene.left, scene.right, cost.census_transform(grey_l),
                                  cost.census_transform(grey_r), grad_l, grad_r,
                                  n_disp=n_disp, cfg=cfg.cost)
        arms_l = aggregation.cross_arms(scene.left, theta_l, grad_l, cfg.arms)
        arms_r = aggregation.cross_arms(scene.right, theta_r, grad_r, cfg.arms)
        arms_r_rev = mirrored(arms_r, pad=n_disp, fill=255)  # as aggregate_cross gives them
        out = np.empty_like(volume)
        for along_rows in (True, False):
            axes = (0, 1) if along_rows else (2, 3)
            mean_arm = float(arms_l[axes[0]].mean() + arms_l[axes[1]].mean())
            for normalise in (False, True):
                running = median_ms(lambda: sum_along_arms(volume, arms_l, arms_r_rev, along_rows,
                                                           normalise, out))
                direct = median_ms(lambda: sum_over_arms(volume, arms_l, arms_r_rev,
                                                         along_rows, normalise, out))
                name = ("rows" if along_rows else "columns") + ("/norm" if normalise else "")
                rule = "direct" if aggregation.direct_is_faster(mean_arm, n_disp) else "running"
                print(f"{scene.name:12s} {name:12s} {mean_arm:5.1f} {running:8.1f} "
                      f"{direct:8.1f}  {rule}")


if __name__ == "__main__":
    main()
