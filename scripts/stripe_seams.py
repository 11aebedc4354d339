"""How much do horizontal stripes change the result? (groundwork for bounded memory)

Matches each Middlebury 2014 quarter-size scene whole, then in stripes of K rows with O
rows of overlap on each side (the noise adaptation computed once on the whole pair), and
prints the share of pixels whose disparity differs by more than 0.5 px and the bad 2.0
of both. The vertical scanline passes are what stripes cut short.

    python scripts/stripe_seams.py [--data-root DIR] [--stripes 64:16,128:32,128:64]
"""

from __future__ import annotations

import argparse

import numpy as np

from vsmatch import datasets, metrics, noise, pipeline
from vsmatch.config import config_from_dict, load_config


def striped(scene, rows: int, overlap: int, cfg) -> np.ndarray:
    height = scene.left.shape[0]
    out = np.empty(scene.left.shape[:2], np.float32)
    for top in range(0, height, rows):
        start, stop = max(0, top - overlap), min(height, top + rows + overlap)
        disp = pipeline.match(scene.left[start:stop], scene.right[start:stop],
                              max_disp=scene.max_disp, config=cfg)
        keep = min(rows, height - top)
        out[top:top + keep] = disp[top - start:top - start + keep]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--stripes", default="64:16,64:32,128:16,128:32,128:64")
    args = parser.parse_args()
    scenes = datasets.load_dataset("middlebury2014-quarter", args.data_root)
    base = load_config(None)
    whole, fixed = {}, {}
    for s in scenes:
        whole[s.name] = pipeline.match(s.left, s.right, max_disp=s.max_disp, config=base)
        sigma = 0.5 * (noise.estimate_noise(s.left) + noise.estimate_noise(s.right))
        fixed[s.name] = config_from_dict({"noise": {"adapt": False}},
                                         base=noise.adapt_to_noise(base, sigma))

    def bad(disps):
        return np.mean([metrics.bad_percent(disps[s.name], s.ground_truth,
                                            s.masks["nonocc"], 2.0) for s in scenes])
    print(f"whole images: bad 2.0 nonocc {bad(whole):.2f}")
    for item in args.stripes.split(","):
        rows, overlap = (int(v) for v in item.split(":"))
        out = {s.name: striped(s, rows, overlap, fixed[s.name]) for s in scenes}
        with np.errstate(invalid="ignore"):
            differ = np.mean([100 * np.mean(~(np.abs(out[n] - whole[n]) <= 0.5)) for n in out])
        print(f"stripes of {rows} rows, overlap {overlap}: {differ:.2f} % of pixels differ by "
              f"more than 0.5 px; bad 2.0 nonocc {bad(out):.2f}")


if __name__ == "__main__":
    main()
