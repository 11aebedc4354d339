#!/usr/bin/env python3
"""What sub-pixel estimation buys: bad 1.0, bad 0.5 and mean absolute error (nonocc).

Runs a config (default: the bundled ``default``) with and without its sub-pixel stage on
both development datasets and prints the dataset means.

    python scripts/precision.py [--config NAME|PATH] [--data-root DIR]
"""

from __future__ import annotations

import argparse

import numpy as np

from vsmatch import datasets, evaluation, match
from vsmatch.config import config_from_dict, load_config


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="default")
    ap.add_argument("--data-root", default=None)
    args = ap.parse_args()
    base = load_config(args.config)
    variants = {"sub-pixel": base,
                "integer": config_from_dict({"subpixel": {"enabled": False}}, base=base)}
    print(f"{'dataset':<18}{'variant':<11}{'bad 1.0':>9}{'bad 0.5':>9}{'mean |err|':>12}")
    for name in ("middlebury2", "middlebury-third"):
        scenes = datasets.load_dataset(name, args.data_root)
        for label, cfg in variants.items():
            bad1, bad05, err = [], [], []
            for s in scenes:
                disp = match(s.left, s.right, max_disp=s.max_disp, config=cfg)
                mask = s.masks["nonocc"]
                bad1.append(evaluation.bad_percent(disp, s.ground_truth, mask, 1.0))
                bad05.append(evaluation.bad_percent(disp, s.ground_truth, mask, 0.5))
                err.append(float(np.abs(disp - s.ground_truth)[mask].mean()))
            print(f"{name:<18}{label:<11}{np.mean(bad1):9.2f}{np.mean(bad05):9.2f}"
                  f"{np.mean(err):12.3f}")


if __name__ == "__main__":
    main()
