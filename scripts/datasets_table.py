"""One config over every dataset at once, as parameters are chosen: each dataset's mean
headline figure (nonocc bad 1.0 on middlebury2, middlebury-third and ETH3D, bad 2.0 on
Middlebury 2014 quarter, D1 on KITTI), the standard scenes apart from the hard ones
(Vintage, terrains_2l, terrains_2s) and the hard ones alone, on one line; and each
dataset's two fixed halves apart (:func:`halves`): a constant is chosen on the first half of
every dataset and kept only where the second half gains too (docs/results.md, "Two halves").

    python scripts/datasets_table.py CONFIG [section.key=value ...] [--data-root DIR]

``section.key=value`` changes one key of the config (YAML values: ``null``, ``true``, 4):
``python scripts/datasets_table.py accurate surfaces.bridge=128``. The figures are those of
``vsmatch eval`` on each dataset.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from vsmatch import datasets, evaluation
from vsmatch.config import with_changes

DATASETS = ("middlebury2", "middlebury-third", "middlebury2014-quarter", "kitti2015", "eth3d")
#: Scenes kept out of the standard means (the README's tables), shown on their own.
HARD = ("Vintage", "terrains_2l", "terrains_2s")


def halves(names: list[str]) -> tuple[list[str], list[str]]:
    """A data set's two fixed halves: its scenes in order of name (case aside), the first,
    third, ... to choose a constant on, the second, fourth, ... to confirm it on."""
    ordered = sorted(names, key=str.lower)
    return ordered[0::2], ordered[1::2]


def config_and_data_root(description: str):
    """A script's ``CONFIG [section.key=value ...] [--data-root DIR]`` arguments: the
    config with its keys changed, and the data root."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("config")
    parser.add_argument("changes", nargs="*", metavar="section.key=value")
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    return with_changes(args.config, args.changes), args.data_root


def main() -> None:
    cfg, data_root = config_and_data_root(__doc__.splitlines()[0])
    start = time.perf_counter()
    parts, hard = [], {}
    for name in DATASETS:
        report = evaluation.evaluate(datasets.load_dataset(name, data_root), {"m": cfg},
                                     dataset=name)
        figures = evaluation.headline_figures(report, "m")
        standard = [v for scene, v in figures.items() if scene not in HARD]
        hard.update({scene: v for scene, v in figures.items() if scene in HARD})
        choose, confirm = halves([scene for scene in figures if scene not in HARD])
        text = (f"{name} {np.mean(standard):.2f} (halves "
                f"{np.mean([figures[s] for s in choose]):.2f} / "
                f"{np.mean([figures[s] for s in confirm]):.2f})")
        if len(standard) < len(figures):
            text += f" (all {np.mean(list(figures.values())):.2f})"
        parts.append(text)
    hard_text = ", ".join(f"{scene} {value:.2f}" for scene, value in hard.items())
    print(f"{' | '.join(parts)} | hard: {hard_text} | {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
