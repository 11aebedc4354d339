"""What a config's cloud keeps on every dataset: at ``cloud.min_confidence``, the share of
each dataset's evaluated pixels kept (non-occluded, with ground truth) and the share of the
kept ones wrong by the dataset's headline measure, as means over each fixed half
(``scripts/datasets_table.py``'s halves) and over all its scenes (the hard ones too); and
Hu and Mordohai's r.

    python scripts/confident_errors.py CONFIG [section.key=value ...] [--data-root DIR]
"""

from __future__ import annotations

import time

import numpy as np

from vsmatch import datasets, evaluation, pipeline

from datasets_table import DATASETS, HARD, config_and_data_root, halves


def main() -> None:
    cfg, data_root = config_and_data_root(__doc__.splitlines()[0])
    start = time.perf_counter()
    parts = []
    for name in DATASETS:
        scoring = evaluation.scoring_for(name, None)
        figures = {}
        for scene in datasets.load_dataset(name, data_root):
            result = pipeline.run(scene.left, scene.right, min_disp=scene.min_disp,
                                  max_disp=scene.max_disp, config=cfg)
            evaluated = evaluation.headline_mask(scene) & np.isfinite(scene.ground_truth)
            bad = scoring.bad_map(result.disparity, scene.ground_truth)
            kept = evaluated & (result.confidence >= cfg.cloud.min_confidence)
            r = evaluation.confidence_measures(result.disparity, result.confidence, scene,
                                               scoring)["r"]
            figures[scene.name] = (100 * kept.sum() / max(evaluated.sum(), 1),
                                   100 * (bad & kept).sum() / max(kept.sum(), 1), r)
        choose, confirm = halves([s for s in figures if s not in HARD])

        def mean(scenes, k):
            return np.mean([figures[s][k] for s in scenes])

        every = list(figures)
        parts.append(f"{name} wrong {mean(choose, 1):.2f}/{mean(confirm, 1):.2f} "
                     f"(all {mean(every, 1):.2f}) kept {mean(choose, 0):.1f}/"
                     f"{mean(confirm, 0):.1f} r {mean(every, 2):.3f}")
    print(" | ".join(parts) + f" | {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
