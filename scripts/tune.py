#!/usr/bin/env python3
"""Coordinate search for one parameter set over both development datasets at once.

The objective is the mean of the two datasets' mean ``nonocc`` bad 1.0 (middlebury2, four
scenes; middlebury-third, nine scenes), so no parameter is chosen for one scene. Each round
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


def objective(cfg, scene_sets) -> tuple[float, dict[str, float]]:
    means = {}
    for name, scenes in scene_sets.items():
        scores = [evaluation.score_scene(
            pipeline.match(s.left, s.right, max_disp=s.max_disp, config=cfg), s)["nonocc"]
            for s in scenes]
        means[name] = float(np.mean(scores))
    return float(np.mean(list(means.values()))), means


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
    args = ap.parse_args(argv)

    scene_sets = {d: datasets.load_dataset(d, args.data_root) for d in args.datasets.split(",")}
    current = load_config(args.base).to_dict()
    best, parts = objective(config_from_dict(current), scene_sets)
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
                score, parts = objective(cfg, scene_sets)
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
