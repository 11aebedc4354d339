"""How a config's figures hold under changes of the input too small to matter: each scene
as it is, with sensor noise of ``--sigma`` grey levels added to each view (its own seed a
scene and view), and with ``--cut`` columns cut from the left of both views (the content
moves against the pixel grid and the image's border). A step that gains only on the scene
as it is was tuned to it; a method that transfers moves by about as much as the noise
explains. Per dataset: the mean headline figure (as ``vsmatch eval`` reports it) of each
variant, and every scene whose figure rises by more than ``--flag`` points in either.

    python scripts/perturbed.py CONFIG [CONFIG ...] [--sigma 1] [--cut 3] [--flag 2]
        [--seed 0] [--datasets middlebury2 ...] [--data-root DIR] [--set section.key=value]

``--seed``: the noise's seeds start there (scene i's views take 2 (seed + i) and
2 (seed + i) + 1).
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from vsmatch import datasets, evaluation
from vsmatch.config import with_changes

DATASETS = ("middlebury2", "middlebury-third", "middlebury2014-quarter", "kitti2015", "eth3d")


def with_noise(scene: datasets.Scene, sigma: float, seed: int) -> datasets.Scene:
    """``scene`` with Gaussian noise of ``sigma`` grey levels on each view (seeds 2 ``seed``
    and 2 ``seed`` + 1), rounded to 8 bits."""
    def noisy(view: np.ndarray, view_seed: int) -> np.ndarray:
        noise = np.random.default_rng(view_seed).normal(0.0, sigma, view.shape)
        return np.clip(view.astype(np.float64) + noise, 0, 255).round().astype(np.uint8)
    return dataclasses.replace(scene, left=noisy(scene.left, 2 * seed),
                               right=noisy(scene.right, 2 * seed + 1))


def cut_left(scene: datasets.Scene, columns: int) -> datasets.Scene:
    """``scene`` without its first ``columns`` columns (views, ground truth and masks)."""
    def cut(array: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(array[:, columns:])
    return dataclasses.replace(scene, left=cut(scene.left), right=cut(scene.right),
                               ground_truth=cut(scene.ground_truth),
                               masks={name: cut(mask) for name, mask in scene.masks.items()})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="+")
    parser.add_argument("--sigma", type=float, default=1.0)
    parser.add_argument("--cut", type=int, default=3)
    parser.add_argument("--flag", type=float, default=2.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--datasets", nargs="+", default=list(DATASETS))
    parser.add_argument("--set", dest="changes", action="append", default=[],
                        metavar="section.key=value", help="applied to every config")
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    methods = {name: with_changes(name, args.changes) for name in args.configs}
    labels = ("as is", f"noise {args.sigma:g}", f"cut {args.cut}")
    for dataset in args.datasets:
        scenes = datasets.load_dataset(dataset, args.data_root)
        noisy = [with_noise(s, args.sigma, args.seed + i) for i, s in enumerate(scenes)]
        variants = (scenes, noisy, [cut_left(s, args.cut) for s in scenes])
        figures = [evaluation.evaluate(v, methods, dataset=dataset) for v in variants]
        for name in methods:
            per_scene = [evaluation.headline_figures(report, name) for report in figures]
            means = " / ".join(f"{np.mean(list(f.values())):.2f}" for f in per_scene)
            flagged = [f"{scene} {per_scene[0][scene]:.2f} -> "
                       f"{max(per_scene[1][scene], per_scene[2][scene]):.2f}"
                       for scene in per_scene[0]
                       if max(per_scene[1][scene], per_scene[2][scene])
                       > per_scene[0][scene] + args.flag]
            print(f"{dataset} {name}: {' / '.join(labels)} {means}"
                  + (f"; rising: {', '.join(flagged)}" if flagged else ""), flush=True)


if __name__ == "__main__":
    main()
