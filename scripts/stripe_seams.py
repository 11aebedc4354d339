"""How much do the memory budget's stripes change the result?

Matches each Middlebury 2014 quarter-size scene, and Adirondack upscaled 2x (the level the
4x pair's full search runs on), in one piece and under smaller ``memory.max_mb`` budgets
that cut the full search into stripes (``memory.overlap`` rows of overlap), and prints the
stripe count, the share of pixels whose disparity differs from one piece by more than
0.5 px, and bad (2 x factor) on non-occluded pixels. The vertical scanline passes and the
aggregation's vertical arms are what stripes cut short.

    python scripts/stripe_seams.py [--data-root DIR] [--budgets 128,256] [--overlap 48]
"""

from __future__ import annotations

import argparse

import numpy as np

from vsmatch import datasets, metrics, pipeline, tiles
from vsmatch.bench import upscaled_scene
from vsmatch.config import config_from_dict, load_config


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--budgets", default="128,256",
                        help="memory.max_mb values for the quarter-size scenes (MB)")
    parser.add_argument("--overlap", type=int, default=48)
    args = parser.parse_args()
    base = load_config(None)
    whole_cfg = config_from_dict({"memory": {"max_mb": 1 << 20}}, base=base)
    scenes = datasets.load_dataset("middlebury2014-quarter", args.data_root)
    cases = [(s.name, s.left, s.right, s.ground_truth, s.masks["nonocc"], s.max_disp, 1)
             for s in scenes]
    adirondack = next(s for s in scenes if s.name == "Adirondack")
    left, right, gt, mask, max_disp = upscaled_scene(adirondack, 2)
    big = [("Adirondack 2x", left, right, gt, mask, max_disp, 2)]

    def compare(group, budget):
        cfg = config_from_dict({"memory": {"max_mb": budget, "overlap": args.overlap}},
                               base=base)
        differ, bad_whole, bad_striped, counts = [], [], [], []
        for name, left, right, gt, mask, max_disp, factor in group:
            one = pipeline.match(left, right, max_disp=max_disp, config=whole_cfg)
            cut = pipeline.match(left, right, max_disp=max_disp, config=cfg)
            counts.append(len(tiles.stripe_layout(
                left.shape[0], pipeline.stripe_rows(left.shape[1], max_disp + 1, cfg),
                args.overlap)))
            with np.errstate(invalid="ignore"):
                differ.append(100 * np.mean(~((cut == one) | (np.abs(cut - one) <= 0.5))))
            bad_whole.append(metrics.bad_percent(one, gt, mask, 2.0 * factor))
            bad_striped.append(metrics.bad_percent(cut, gt, mask, 2.0 * factor))
        print(f"{group[0][0] if len(group) == 1 else 'Middlebury 2014 quarter':<24}"
              f"{budget:>6} MB {np.mean(counts):7.1f} stripes  {np.mean(differ):5.2f} % differ"
              f"  bad {np.mean(bad_whole):.2f} -> {np.mean(bad_striped):.2f}")

    print(f"overlap {args.overlap} rows; bad 2 (x factor) nonocc, one piece -> stripes")
    for budget in (int(b) for b in args.budgets.split(",")):
        compare(cases, budget)
    compare(big, base.memory.max_mb)


if __name__ == "__main__":
    main()
