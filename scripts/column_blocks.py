"""How many columns should a scanline column pass walk side by side?

Times the whole range's column pass (both directions) alone on each of the standard pairs
(the middlebury2 scenes and the Middlebury 2014 quarter-size ones, official ranges) on a
random volume of the pair's size, for chunks of 1, 2, 8, 32 and 128 columns walked side by
side, at each of ``--threads`` (``vsmatch.optimization.COLUMN_CHUNK`` is the one used). The
result does not depend on it.

    python scripts/column_blocks.py [--threads 1,2] [--data-root DIR]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from vsmatch import bench, datasets
from vsmatch._kernels.scanline import LANES, scanline_columns
from vsmatch.bands import of
from vsmatch.config import load_config
from vsmatch.images import colour_change, mirrored

BLOCKS = (1, 2, 8, 32, 128)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threads", default="1,2")
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    for threads in (int(t) for t in args.threads.split(",")):
        with bench.thread_count(threads):
            print(f"{threads} thread{'s' * (threads > 1)}, seconds:")
            time_blocks(args.data_root)


def time_blocks(data_root: str | None) -> None:
    cfg = load_config(None).scanline
    divisors = np.array([1.0, cfg.reduce_one, cfg.reduce_both])
    p1s, p2s = ((value / divisors).astype(np.float32) for value in (cfg.p1, cfg.p2))
    rng = np.random.default_rng(0)
    totals = dict.fromkeys(BLOCKS, 0.0)
    print(f"{'pair':<12}{'size':>14}" + "".join(f"{b:>8}" for b in BLOCKS))
    for name in ("middlebury2", "middlebury2014-quarter"):
        for scene in datasets.load_dataset(name, data_root):
            height, width = scene.left.shape[:2]
            n_disp = scene.max_disp + 1
            volume = rng.random((height, width, n_disp), dtype=np.float32)
            out = np.zeros_like(volume)
            change_l = colour_change(scene.left, cfg.tau, along_rows=False)
            change_r = mirrored(colour_change(scene.right, cfg.tau, along_rows=False),
                                pad=n_disp + LANES, fill=1)
            bands = of(volume, None)
            times = {}
            for block in BLOCKS:
                run = (volume, bands.lo, bands.count, False, change_l, change_r, p1s, p2s,
                       np.float32(0.25), block, out)
                scanline_columns(*run)  # compile, warm the caches
                best = np.inf
                for _ in range(5):
                    start = time.perf_counter()
                    scanline_columns(*run)
                    best = min(best, time.perf_counter() - start)
                times[block] = best
                totals[block] += best
            print(f"{scene.name:<12}{f'{width}x{height}x{n_disp}':>14}"
                  + "".join(f"{times[b]:8.4f}" for b in BLOCKS))
    print(f"{'total':<26}" + "".join(f"{totals[b]:8.3f}" for b in BLOCKS))


if __name__ == "__main__":
    main()
