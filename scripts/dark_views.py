"""Dark views made from bright ones: how a config holds when the light goes.

Each scene's two views are darkened, as an unlit scene or a short exposure records them:
the grey levels scaled by ``--gain`` (the signal shrinks) and then each view given its own
sensor noise of ``--sigma`` grey levels (the noise does not shrink with the light), rounded
to 8 bits. With ``--gamma`` the grey levels are first raised to that power (as fractions of
255): an underexposed camera's shadows crushed towards black, its highlights kept
(``--gain 1 --gamma 2.2 --sigma 1``). The scene's headline figure (as ``vsmatch eval``
reports it) is printed beside the same config's figure on the views as they are, per
dataset, for each config.

    python scripts/dark_views.py CONFIG [CONFIG ...] [--gain 0.3] [--sigma 1.5] [--gamma 1]
        [--datasets eth3d middlebury2014-quarter] [--data-root DIR] [--set section.key=value]
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from vsmatch import datasets, evaluation
from vsmatch.config import with_changes
from vsmatch.synthetic import darkened


def dark_scene(scene: datasets.Scene, gain: float, sigma: float, seed: int,
               gamma: float = 1.0) -> datasets.Scene:
    """``scene`` with both views darkened, each with its own noise (seeded by ``seed``)."""
    return dataclasses.replace(scene, left=darkened(scene.left, gain, sigma, 2 * seed, gamma),
                               right=darkened(scene.right, gain, sigma, 2 * seed + 1, gamma))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="+")
    parser.add_argument("--gain", type=float, default=0.3)
    parser.add_argument("--sigma", type=float, default=1.5)
    parser.add_argument("--gamma", type=float, default=1.0)
    parser.add_argument("--datasets", nargs="+", default=["eth3d", "middlebury2014-quarter"])
    parser.add_argument("--set", dest="changes", action="append", default=[],
                        metavar="section.key=value", help="applied to every config")
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    methods = {name: with_changes(name, args.changes) for name in args.configs}
    for dataset in args.datasets:
        scenes = datasets.load_dataset(dataset, args.data_root)
        dark = [dark_scene(s, args.gain, args.sigma, seed, args.gamma)
                for seed, s in enumerate(scenes)]
        for name, cfg in methods.items():
            as_is = evaluation.headline_figures(
                evaluation.evaluate(scenes, {name: cfg}, dataset=dataset), name)
            low = evaluation.headline_figures(
                evaluation.evaluate(dark, {name: cfg}, dataset=dataset), name)
            worst = max(low, key=low.get)
            print(f"{dataset} {name}: as is {np.mean(list(as_is.values())):.2f}, dark "
                  f"{np.mean(list(low.values())):.2f} (worst {worst} {low[worst]:.2f})")


if __name__ == "__main__":
    main()
