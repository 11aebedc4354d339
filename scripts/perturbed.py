"""How a config's figures hold under changes of the input too small to matter: each scene
as it is, with sensor noise of ``--sigma`` grey levels on each view (``evaluation.
with_sensor_noise``: the noise protocol's random numbers, seeded by ``--seed``, the scene
and the view; with ``--seeds N`` each scene's figure is the mean over the seeds ``--seed`` ..
``--seed`` + N - 1), and with ``--cut`` columns cut from the left of both views (``evaluation.
without_left_columns``: the content moves against the pixel grid and the image's border).
A step that gains only on the scene as it is was tuned to it; a method that transfers moves
by about as much as the noise explains. Per dataset: the mean headline figure (as ``vsmatch
eval`` reports it) of each variant over the standard scenes (the hard ones apart, as in
``scripts/datasets_table.py``), and every scene whose figure rises by more than ``--flag``
points in either.

    python scripts/perturbed.py CONFIG [CONFIG ...] [--sigma 1] [--cut 3] [--flag 2]
        [--seed 0] [--seeds 1] [--datasets middlebury2 ...] [--data-root DIR]
        [--set section.key=value]
"""

from __future__ import annotations

import argparse

import numpy as np

from vsmatch import datasets, evaluation
from vsmatch.config import with_changes

from datasets_table import DATASETS, HARD


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="+")
    parser.add_argument("--sigma", type=float, default=1.0)
    parser.add_argument("--cut", type=int, default=3)
    parser.add_argument("--flag", type=float, default=2.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--seeds", type=int, default=1, help="noise seeds from --seed on")
    parser.add_argument("--datasets", nargs="+", default=list(DATASETS))
    parser.add_argument("--set", dest="changes", action="append", default=[],
                        metavar="section.key=value", help="applied to every config")
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    methods = {name: with_changes(name, args.changes) for name in args.configs}
    seeds = "" if args.seeds == 1 else f" ({args.seeds} seeds)"
    labels = ("as is", f"noise {args.sigma:g}{seeds}", f"cut {args.cut}")
    for dataset in args.datasets:
        scenes = datasets.load_dataset(dataset, args.data_root)
        noisy = [[evaluation.with_sensor_noise(s, i, args.sigma, seed)
                  for i, s in enumerate(scenes)]
                 for seed in range(args.seed, args.seed + args.seeds)]
        cut = [evaluation.without_left_columns(s, args.cut) for s in scenes]
        as_is, cut_report = (evaluation.evaluate(v, methods, dataset=dataset)
                             for v in (scenes, cut))
        noisy_reports = [evaluation.evaluate(v, methods, dataset=dataset) for v in noisy]
        for name in methods:
            per_seed = [evaluation.headline_figures(report, name) for report in noisy_reports]
            noise = {scene: float(np.mean([f[scene] for f in per_seed]))
                     for scene in per_seed[0]}
            figures = [evaluation.headline_figures(as_is, name), noise,
                       evaluation.headline_figures(cut_report, name)]
            standard = " / ".join(f"{np.mean([v for s, v in f.items() if s not in HARD]):.2f}"
                                  for f in figures)
            hard = "".join(f"; {scene} " + " / ".join(f"{f[scene]:.2f}" for f in figures)
                           for scene in figures[0] if scene in HARD)
            changed = {scene: max(figures[1][scene], figures[2][scene]) for scene in figures[0]}
            rising = [f"{scene} {figures[0][scene]:.2f} -> {worst:.2f}"
                      for scene, worst in changed.items()
                      if worst > figures[0][scene] + args.flag]
            print(f"{dataset} {name}: {' / '.join(labels)} {standard}{hard}"
                  + (f"; rising: {', '.join(rising)}" if rising else ""), flush=True)


if __name__ == "__main__":
    main()
