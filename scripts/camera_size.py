"""Where coarse-to-fine should start: configs on the eight Middlebury 2014 scenes upscaled
to camera size, time and bad (2 x scale) on the non-occluded pixels.

Each variant is ``CONFIG`` or ``CONFIG=YAML`` (a YAML mapping merged over the config):

    python scripts/camera_size.py [--scale 2.05] [--data-root DIR] default \\
        "default={pyramid: {max_row_cells: 100000}}" fast
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import yaml

from vsmatch import datasets, pipeline
from vsmatch.bench import upscaled_scene
from vsmatch.config import config_from_dict, load_config
from vsmatch.metrics import bad_percent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scale", type=float, default=2.05)
    parser.add_argument("--data-root", default=None)
    parser.add_argument("variants", nargs="+")
    args = parser.parse_args()
    scenes = datasets.load_dataset("middlebury2014-quarter", args.data_root)
    threshold = 2 * args.scale
    print(f"scale {args.scale}: bad {threshold:g} on non-occluded pixels, "
          f"scenes {' '.join(s.name for s in scenes)}")
    for variant in args.variants:
        name, _, changes = variant.partition("=")
        cfg = config_from_dict(yaml.safe_load(changes) or {}, base=load_config(name))
        errors, seconds = [], 0.0
        for scene in scenes:
            left, right, truth, mask, max_disp = upscaled_scene(scene, args.scale)
            start = time.perf_counter()
            disp = pipeline.match(left, right, max_disp=max_disp, config=cfg)
            seconds += time.perf_counter() - start
            errors.append(bad_percent(disp, truth, mask, threshold))
        print(f"{variant:<50} mean {np.mean(errors):6.2f}  {seconds:6.1f} s  "
              + " ".join(f"{e:.2f}" for e in errors), flush=True)


if __name__ == "__main__":
    main()
