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
        [--per-scene] [--stretch C] [--lit-quarter]

``--per-scene`` prints each scene's figure as it is and darkened too. ``--lit-quarter``
keeps the light of each view's top-right quarter (a lamp or a window in a dark room: the
view's contrast stays high, as a real dark scene's with a bright part does). ``--stretch C``
scales both views of each scene, as they are and darkened, by one gain so that the left
view's contrast (its 90th less its 10th grey-level percentile) reaches C where it is lower,
before the match: a prototype of thresholds that follow the light (docs/results.md, "What
transfers, and what is still short").
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from vsmatch import datasets, evaluation
from vsmatch.config import with_changes
from vsmatch.surfaces import view_contrast
from vsmatch.synthetic import darkened

from datasets_table import HARD, halves


def dark_scene(scene: datasets.Scene, gain: float, sigma: float, seed: int,
               gamma: float = 1.0, lit_quarter: bool = False) -> datasets.Scene:
    """``scene`` with both views darkened, each with its own noise (seeded by ``seed``);
    with ``lit_quarter``, the top-right quarter of each view keeps its light (the same
    noise)."""
    views = []
    for view, view_seed in ((scene.left, 2 * seed), (scene.right, 2 * seed + 1)):
        dark = darkened(view, gain, sigma, view_seed, gamma)
        if lit_quarter:
            height, width = view.shape[:2]
            lit = darkened(view, 1.0, sigma, view_seed)  # the same noise, the light kept
            dark[:height // 2, width // 2:] = lit[:height // 2, width // 2:]
        views.append(dark)
    return dataclasses.replace(scene, left=views[0], right=views[1])


def stretched(scene: datasets.Scene, contrast: float) -> datasets.Scene:
    """``scene`` with both views scaled by one gain so that the left view's contrast
    reaches ``contrast`` (as it is where it already does, or with ``contrast`` 0)."""
    gain = contrast / max(view_contrast(scene.left), 1.0)
    if gain <= 1.0:
        return scene

    def scaled(view: np.ndarray) -> np.ndarray:
        return np.clip(np.rint(view.astype(np.float32) * np.float32(gain)), 0,
                       255).astype(np.uint8)

    return dataclasses.replace(scene, left=scaled(scene.left), right=scaled(scene.right))


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
    parser.add_argument("--per-scene", action="store_true")
    parser.add_argument("--stretch", type=float, default=0.0, metavar="C")
    parser.add_argument("--lit-quarter", action="store_true")
    args = parser.parse_args()
    methods = {name: with_changes(name, args.changes) for name in args.configs}
    for dataset in args.datasets:
        scenes = datasets.load_dataset(dataset, args.data_root)
        dark = [stretched(dark_scene(s, args.gain, args.sigma, seed, args.gamma,
                                     args.lit_quarter), args.stretch)
                for seed, s in enumerate(scenes)]
        scenes = [stretched(s, args.stretch) for s in scenes]
        for name, cfg in methods.items():
            as_is = evaluation.headline_figures(
                evaluation.evaluate(scenes, {name: cfg}, dataset=dataset), name)
            low = evaluation.headline_figures(
                evaluation.evaluate(dark, {name: cfg}, dataset=dataset), name)
            worst = max(low, key=low.get)
            choose, confirm = halves([scene for scene in low if scene not in HARD])
            print(f"{dataset} {name}: as is {np.mean(list(as_is.values())):.2f}, dark "
                  f"{np.mean(list(low.values())):.2f} (worst {worst} {low[worst]:.2f}; "
                  f"halves {np.mean([low[s] for s in choose]):.2f} / "
                  f"{np.mean([low[s] for s in confirm]):.2f})")
            if args.per_scene:
                for scene, value in low.items():
                    print(f"  {scene:20s} as is {as_is[scene]:6.2f}, dark {value:6.2f}")


if __name__ == "__main__":
    main()
