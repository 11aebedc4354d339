#!/usr/bin/env python3
"""What the photometric stage learns and buys, scene by scene.

For every scene of the datasets: the median colour difference of the first match's pixels
before and after the right view's colour map, the colour term's weight, and the headline
figure with the stage on and off (the config's other values unchanged).

    python scripts/exposure.py [--config NAME|PATH] [--datasets A,B] [--data-root DIR]
"""

from __future__ import annotations

import argparse

import numpy as np

from vsmatch import datasets, evaluation, pipeline
from vsmatch.config import config_from_dict, load_config


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="default")
    ap.add_argument("--datasets", default="middlebury2014-quarter,kitti2015")
    ap.add_argument("--data-root", default=None)
    args = ap.parse_args()
    base = config_from_dict({"photometric": {"enabled": True}}, base=load_config(args.config))
    off = config_from_dict({"photometric": {"enabled": False}}, base=base)
    print(f"{'dataset':<24}{'scene':<13}{'before':>7}{'after':>7}{'weight':>7}"
          f"{'on':>8}{'off':>8}")
    for name in args.datasets.split(","):
        scoring = evaluation.scoring_for(name)
        on_all, off_all = [], []
        for s in datasets.load_dataset(name, args.data_root):
            result = pipeline.run(s.left, s.right, max_disp=s.max_disp, config=base)
            figures = []
            for disp in (result.disparity,
                         pipeline.match(s.left, s.right, max_disp=s.max_disp, config=off)):
                scored = evaluation.score_scene(disp, s, scoring)
                figures.append(evaluation.headline_figure(scored))
            on_all.append(figures[0])
            off_all.append(figures[1])
            fit = result.photometric
            learnt = ("" if fit is None else
                      f"{fit.before:7.2f}{fit.residual:7.2f}{result.colour_weight:7.2f}")
            print(f"{name:<24}{s.name:<13}{learnt:>21}{figures[0]:8.2f}{figures[1]:8.2f}",
                  flush=True)
        print(f"{name:<24}{'mean':<13}{'':>21}{np.mean(on_all):8.2f}{np.mean(off_all):8.2f}")


if __name__ == "__main__":
    main()
