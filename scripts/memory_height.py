"""How peak memory grows with the height: the 4x Adirondack pair and its twice-as-tall copy
(its upside-down copy below it) matched with `default` under a memory budget, each in its
own process; peak resident memory (the kernel's high-water mark) and time.

    python scripts/memory_height.py [--data-root DIR] [--budget 1024] [--budget 256]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

CHILD = """
import json, sys, time
import numpy as np
from vsmatch import bench, datasets, pipeline
from vsmatch.config import config_from_dict, load_config
root, budget, tall = sys.argv[1] or None, int(sys.argv[2]), sys.argv[3] == "tall"
[scene] = datasets.load_dataset("middlebury2014-quarter", root, names=["Adirondack"])
left, right, truth, mask, max_disp = bench.upscaled_scene(scene, 4)
if tall:
    left, right = (np.ascontiguousarray(np.concatenate([a, a[::-1]])) for a in (left, right))
cfg = config_from_dict({"memory": {"max_mb": budget}}, base=load_config("default"))
pipeline.run(left[:48, :64], right[:48, :64], max_disp=16, config=cfg)
start = time.perf_counter()
pipeline.run(left, right, max_disp=max_disp, config=cfg)
print(json.dumps({"size": left.shape[1::-1], "seconds": time.perf_counter() - start,
                  "peak_mb": bench._peak_rss_mb()}))
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default="")
    parser.add_argument("--budget", type=int, action="append")
    args = parser.parse_args()
    for budget in args.budget or [1024]:
        for kind in ("flat", "tall"):
            out = subprocess.run([sys.executable, "-c", CHILD, args.data_root, str(budget),
                                  kind], capture_output=True, text=True, check=True)
            run = json.loads(out.stdout.strip().splitlines()[-1])
            print(f"budget {budget} MB, {run['size'][0]}x{run['size'][1]}: peak "
                  f"{run['peak_mb']:.0f} MB, {run['seconds']:.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
