"""vsmatch's time against OpenCV SGBM (HH and 5-direction) on the twelve standard pairs,
robust to a busy machine.

For each pair (the middlebury2 scenes and the Middlebury 2014 quarter-size ones, official
ranges), runs each given config and SGBM's two modes one after the other for ``--rounds``
rounds and keeps each one's fastest time; prints the sums and the ratios (``vsmatch
bench`` does the same and adds errors, stages and the size series).

    python scripts/speed_ratio.py [--data-root DIR] [--rounds 5] [CONFIG ...]
"""

from __future__ import annotations

import argparse
import time

import cv2

from vsmatch import datasets, pipeline
from vsmatch.bench import STANDARD_DATASETS
from vsmatch.config import load_config
from vsmatch.peers import sgbm_matcher


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("configs", nargs="*", default=["fast", "default"])
    args = parser.parse_args()
    configs = {name: load_config(name) for name in args.configs}
    scenes = [s for name in STANDARD_DATASETS for s in datasets.load_dataset(name, args.data_root)]
    for cfg in configs.values():  # compile or load the kernels
        pipeline.run(scenes[0].left, scenes[0].right, max_disp=scenes[0].max_disp, config=cfg)
    totals = dict.fromkeys([*configs, "sgbm-hh", "sgbm-5"], 0.0)
    for scene in scenes:
        sgbm = sgbm_matcher(scene.max_disp)
        sgbm5 = sgbm_matcher(scene.max_disp, mode=cv2.STEREO_SGBM_MODE_SGBM)
        sgbm.compute(scene.left, scene.right)
        sgbm5.compute(scene.left, scene.right)
        best = dict.fromkeys(totals, float("inf"))
        for _ in range(args.rounds):
            for name, cfg in configs.items():
                start = time.perf_counter()
                pipeline.run(scene.left, scene.right, max_disp=scene.max_disp, config=cfg)
                best[name] = min(best[name], time.perf_counter() - start)
            for name, matcher in (("sgbm-hh", sgbm), ("sgbm-5", sgbm5)):
                start = time.perf_counter()
                matcher.compute(scene.left, scene.right)
                best[name] = min(best[name], time.perf_counter() - start)
        for name in totals:
            totals[name] += best[name]
    for name, total in totals.items():
        print(f"{name:<24}{total:8.3f} s   {total / totals['sgbm-hh']:5.2f} x SGBM HH"
              f"   {total / totals['sgbm-5']:5.2f} x SGBM 5-direction")


if __name__ == "__main__":
    main()
