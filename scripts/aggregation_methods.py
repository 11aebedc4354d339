"""Time the two ways of summing over the crosses, running sums (orthogonal integral
images, the library's) and direct sums, on the standard pairs.

    python scripts/aggregation_methods.py [--data-root DIR] [--config NAME]

Prints, per pair, the volume's shape, the mean arm length and the milliseconds of one
aggregation of the config's cost volume by each method (fastest of 3), then the totals.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from vsmatch import aggregation, bench, level
from vsmatch.config import load_config


def fastest_ms(fn, repeats: int = 3) -> float:
    fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return 1000 * min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--config", default="default")
    args = parser.parse_args()
    cfg = load_config(args.config)
    totals = dict.fromkeys(aggregation.AGGREGATION_METHODS, 0.0)
    print(f"{'pair':12s} {'volume':>16s} {'arm':>5s}" +
          "".join(f"{m:>9s}" for m in totals))
    for scene, _ in bench.standard_pairs(args.data_root):
        volume, (grad_l, theta_l), (grad_r, theta_r) = level.matching_costs(
            scene.left, scene.right, scene.max_disp + 1, cfg.cost, cfg.arms.kappa != 0)
        arms_l = aggregation.cross_arms(scene.left, theta_l, grad_l, cfg.arms)
        arms_r = aggregation.cross_arms(scene.right, theta_r, grad_r, cfg.arms)
        work, scratch = np.empty_like(volume), np.empty_like(volume)
        row = []
        for method in totals:
            def once():
                work[...] = volume
                aggregation.aggregate_cross(work, arms_l, arms_r, scratch=scratch,
                                            iterations=cfg.aggregation.iterations,
                                            method=method)
            ms = fastest_ms(once)
            totals[method] += ms
            row.append(f"{ms:9.1f}")
        shape = "x".join(map(str, volume.shape))
        print(f"{scene.name:12s} {shape:>16s} {arms_l.mean():5.1f}" + "".join(row))
    print(f"{'total':12s} {'':>16s} {'':>5s}" + "".join(f"{v:9.1f}" for v in totals.values()))


if __name__ == "__main__":
    main()
