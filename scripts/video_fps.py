"""Frames per second of a video's worth of pairs: StereoMatcher (each config) against
OpenCV SGBM (HH and 5-direction) on the same frames.

The frames are real pairs repeated (a Middlebury 2014 quarter-size scene, a KITTI 2015
frame): the matcher finds the range on the first frame and keeps it, as in a video.

    python scripts/video_fps.py [--data-root DIR] [--frames 10] [CONFIG ...]
"""

from __future__ import annotations

import argparse
import time

import cv2

from vsmatch import StereoMatcher, datasets
from vsmatch.peers import sgbm_matcher

SCENES = (("middlebury2014-quarter", "Adirondack"), ("kitti2015", "000000"))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--frames", type=int, default=10)
    parser.add_argument("configs", nargs="*", default=["fast", "default"])
    args = parser.parse_args()
    for dataset, name in SCENES:
        scene = datasets.load_dataset(dataset, args.data_root, names=[name])[0]
        rates = {}
        for config in args.configs:
            stereo = StereoMatcher(config=config)
            stereo.compute(scene.left, scene.right)  # kernels loaded, range found
            start = time.perf_counter()
            for _ in range(args.frames):
                stereo.compute(scene.left, scene.right)
            rates[f"vsmatch {config}"] = args.frames / (time.perf_counter() - start)
            low, high = stereo.range
        for mode, flag in (("SGBM HH", cv2.STEREO_SGBM_MODE_HH),
                           ("SGBM 5-dir", cv2.STEREO_SGBM_MODE_SGBM)):
            sgbm = sgbm_matcher(high, 3, min_disp=low, mode=flag)
            start = time.perf_counter()
            for _ in range(args.frames):
                sgbm.compute(scene.left, scene.right)
            rates[mode] = args.frames / (time.perf_counter() - start)
        size = f"{scene.left.shape[1]}x{scene.left.shape[0]}"
        print(f"{dataset}/{name} {size}, disparities {low}..{high}: "
              + ", ".join(f"{k} {v:.2f} fps" for k, v in rates.items()), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
