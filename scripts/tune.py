#!/usr/bin/env python3
"""Coordinate search for one parameter set over several datasets at once.

The objective is the mean over the datasets of each one's headline figure (``nonocc`` bad
1.0 on middlebury2 and middlebury-third, bad 2.0 on Middlebury 2014, D1 on KITTI) divided
by the base config's, so that every dataset counts alike and no parameter is chosen for
one scene. Each round
tries every listed value of every parameter in turn, keeping a change only if it lowers the
objective. The best config is written as YAML.

Example:
    python scripts/tune.py --base paper --out tuned.yaml \
        --grid cost.lambda_gradient=10,20,40 --grid arms.kappa=0,0.5,1
"""

from __future__ import annotations

import argparse
import copy
import sys

import numpy as np
import yaml

from vsmatch import datasets, evaluation, pipeline
from vsmatch.config import ConfigError, config_from_dict, load_config


# The paper's Table 2, "Proposed" row: mean nonocc bad 1.0 on middlebury2 under noise.
PAPER_NOISE = {0.02: 5.02, 0.05: 8.65, 0.10: 17.33, 0.15: 38.46}


def objective(cfg, scene_sets, noise_levels=(), seeds=1, base=None
              ) -> tuple[float, dict[str, float]]:
    """Mean of the datasets' means (each divided by ``base[dataset]`` when given); with
    ``noise_levels``, instead the mean over the
    levels of middlebury2's noisy figure divided by the paper's (below 1 beats the paper)."""
    if noise_levels:
        scenes = scene_sets["middlebury2"]
        report = {"methods": {"m": {}}}
        evaluation.evaluate_noise(scenes, {"m": cfg}, report, levels=list(noise_levels),
                                  seeds=seeds)
        noisy = {f"{lv:g}": report["methods"]["m"]["noise"][f"{lv:g}"]["avg"]["nonocc"]
                 for lv in noise_levels}
        ratios = [noisy[f"{lv:g}"] / PAPER_NOISE[lv] for lv in noise_levels]
        return float(np.mean(ratios)), noisy
    means = {}
    for name, scenes in scene_sets.items():
        scoring = evaluation.scoring_for(name)
        scores = []
        for s in scenes:
            disp = pipeline.match(s.left, s.right, max_disp=s.max_disp, config=cfg)
            result = evaluation.score_scene(disp, s, scoring)
            scores.append(evaluation.headline_figure(result))
        means[name] = float(np.mean(scores))
    if base is None:
        return float(np.mean(list(means.values()))), means
    return float(np.mean([means[k] / base[k] for k in means])), means


def parse_grid(items: list[str]) -> list[tuple[str, str, list]]:
    grid = []
    for item in items:
        key, values = item.split("=", 1)
        section, name = key.split(".", 1)
        grid.append((section, name, [yaml.safe_load(v) for v in values.split(",")]))
    return grid


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", default="paper", help="bundled config name or YAML path")
    ap.add_argument("--grid", action="append", default=[], help="section.key=v1,v2,...")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--data-root", default=None)
    ap.add_argument("--datasets", default="middlebury2,middlebury-third")
    ap.add_argument("--out", default=None, help="write the best config here")
    ap.add_argument("--noise", default="", help="tune for these noise levels instead, "
                    "e.g. 0.02,0.05,0.1,0.15 (objective: mean ratio to the paper's Table 2)")
    ap.add_argument("--seeds", type=int, default=1, help="noise seeds per level")
    args = ap.parse_args(argv)

    scene_sets = {d: datasets.load_dataset(d, args.data_root) for d in args.datasets.split(",")}
    levels = [float(v) for v in args.noise.split(",") if v]
    current = load_config(args.base).to_dict()
    start = None
    if len(scene_sets) > 1 and not levels:  # every dataset relative to the base config's
        _, start = objective(config_from_dict(current), scene_sets)
    score_of = lambda cfg: objective(cfg, scene_sets, levels, args.seeds, start)  # noqa: E731
    best, parts = score_of(config_from_dict(current))
    print(f"start {best:.3f} {parts}", flush=True)
    for rnd in range(args.rounds):
        changed = False
        for section, name, values in parse_grid(args.grid):
            for value in values:
                if current[section][name] == value:
                    continue
                trial = copy.deepcopy(current)
                trial[section][name] = value
                try:
                    cfg = config_from_dict(trial)
                except ConfigError as exc:
                    print(f"round {rnd} {section}.{name}={value}: skipped ({exc})", flush=True)
                    continue
                score, parts = score_of(cfg)
                mark = ""
                if score < best - 1e-9:
                    best, current, changed, mark = score, trial, True, "  <- kept"
                print(f"round {rnd} {section}.{name}={value}: {score:.3f} "
                      f"{ {k: round(v, 3) for k, v in parts.items()} }{mark}", flush=True)
        if not changed:
            break
    print(f"best {best:.3f}")
    print(yaml.safe_dump(current, sort_keys=False))
    if args.out:
        with open(args.out, "w", encoding="utf-8") as fh:
            yaml.safe_dump(current, fh, sort_keys=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
