"""What `accurate`'s surfaces step moves: the pixels it fixes and breaks, by kind of pixel.

For each scene of each dataset, as it is and darkened (``scripts/dark_views.py``'s views:
``--gain``, ``--sigma``), the config's match without its surfaces and depth edges steps,
then ``surfaces.spread_planes`` on it (the right view as matched: after the exposure
correction). Counted over the non-occluded pixels with ground truth, per dataset and kind
of view: the share moved, and the pixels it fixes and breaks (wrong: by the dataset's
headline measure, as ``vsmatch eval`` scores it), by the pixel's texture in units of what
the view's noise alone gives
(the Sobel texture over 5.66 x the pair's estimated noise, 5.66 being the texture of noise
of one grey level; over 1 where the noise reads below 1 / 5.66, as it reads 0 on many clean
views), and by how far inside the right view the match lay before (x - d).

    python scripts/surface_moves.py [CONFIG] [--datasets eth3d middlebury2014-quarter]
        [--gain 0.3] [--sigma 1.5] [--data-root DIR]
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from dark_views import dark_scene
from vsmatch import datasets, evaluation, photometric, pipeline, surfaces
from vsmatch.config import with_changes
from vsmatch.images import grey_levels
from vsmatch.noise import estimate_pair_noise
from vsmatch.sensitivity import texture

#: The texture of sensor noise of one grey level (``sensitivity.texture``, measured).
NOISE_TEXTURE = 5.66
TEXTURE_BINS = (0, 2, 4, 8, 16, np.inf)
INSIDE_BINS = (-np.inf, 0, 8, 16, 32, 64, np.inf)


def moves(scene: datasets.Scene, cfg, scoring: evaluation.Scoring) -> dict[str, np.ndarray]:
    """Per pixel of ``scene`` (non-occluded, with ground truth): moved, fixed and broken
    (wrong by ``scoring``), texture in noise units, and how far inside the right view the
    match lay."""
    before_cfg = dataclasses.replace(
        cfg, surfaces=dataclasses.replace(cfg.surfaces, enabled=False),
        edges=dataclasses.replace(cfg.edges, enabled=False))
    result = pipeline.run(scene.left, scene.right, max_disp=scene.max_disp, config=before_cfg)
    # The right view as matched: the match's own exposure map, not a second first match.
    right = (scene.right if result.photometric is None
             else photometric.apply(scene.right, result.photometric))
    spread = surfaces.spread_planes(result.disparity, result.confidence, result.labels,
                                    scene.left, right, scene.max_disp, result.config,
                                    result.colour_weight, result.curve["margin"])
    known = evaluation.headline_mask(scene) & np.isfinite(scene.ground_truth)
    wrong_before = scoring.bad_map(result.disparity, scene.ground_truth)
    wrong_after = scoring.bad_map(spread.disparity, scene.ground_truth)
    with np.errstate(invalid="ignore"):
        moved = ~(np.abs(spread.disparity - result.disparity) <= 0.5)
    noise = max(estimate_pair_noise(scene.left, scene.right), 1.0 / NOISE_TEXTURE)
    inside = (np.arange(known.shape[1], dtype=np.float32)[None, :]
              - np.nan_to_num(result.disparity, nan=0, posinf=0, neginf=0))
    return {"moved": moved[known], "fixed": (wrong_before & ~wrong_after)[known],
            "broken": (wrong_after & ~wrong_before)[known],
            "texture": (texture(grey_levels(scene.left)) / (NOISE_TEXTURE * noise))[known],
            "inside": inside[known]}


def by_bins(values: np.ndarray, fixed: np.ndarray, broken: np.ndarray, bins) -> str:
    """``[lo, hi): +fixed / -broken`` for each bin of ``values``."""
    index = np.digitize(values, bins) - 1
    parts = []
    for k in range(len(bins) - 1):
        inside = index == k
        parts.append(f"[{bins[k]:g}, {bins[k + 1]:g}): +{int((fixed & inside).sum())} / "
                     f"-{int((broken & inside).sum())}")
    return ", ".join(parts)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", default="accurate")
    parser.add_argument("--datasets", nargs="+", default=["eth3d", "middlebury2014-quarter"])
    parser.add_argument("--gain", type=float, default=0.3)
    parser.add_argument("--sigma", type=float, default=1.5)
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    cfg = with_changes(args.config, [])
    for dataset in args.datasets:
        scoring = evaluation.scoring_for(dataset)
        scenes = datasets.load_dataset(dataset, args.data_root)
        for kind in ("as is", "darkened"):
            parts = [moves(s if kind == "as is" else
                           dark_scene(s, args.gain, args.sigma, seed), cfg, scoring)
                     for seed, s in enumerate(scenes)]
            joined = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
            fixed, broken = joined["fixed"], joined["broken"]
            print(f"{dataset} {kind}: moved {100 * joined['moved'].mean():.1f} %, fixed "
                  f"{int(fixed.sum())}, broken {int(broken.sum())}")
            print(f"  by texture / noise's: "
                  f"{by_bins(joined['texture'], fixed, broken, TEXTURE_BINS)}")
            print(f"  by px inside the right view: "
                  f"{by_bins(joined['inside'], fixed, broken, INSIDE_BINS)}", flush=True)


if __name__ == "__main__":
    main()
