"""Where the scanline overrules the aggregated costs: who is right, by whether the
aggregated costs' own winner is left-right consistent and by its margin.

For `default` on the chain-link fence (holes 45 and 32 px; ``vsmatch.synthetic.fence_pair``)
and on Middlebury 2014, KITTI and ETH3D: the pixels whose final disparity lies 2 px or more
from the aggregated costs' winner, split by that winner's left-right check (tolerance 1)
and its margin (the second least cost at least 2 px away, less the least, over the curve's
mean less its least); per group the count, the share the final disparity gets right and the
share the aggregated winner gets right (each dataset's headline measure on its evaluated
pixels with truth, as ``vsmatch eval``; the fence: bad 1.0 on its pixels seen in both
views). Written to see whether a confidence cap could find the fence's filled
holes (docs/results.md, "A chain-link fence").

    python scripts/overruled_pixels.py [--data-root DIR]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vsmatch import datasets, disparity, evaluation, level, pipeline  # noqa: E402
from vsmatch.config import load_config  # noqa: E402
from vsmatch.synthetic import fence_pair  # noqa: E402

#: The full search's aggregated volume of the last match (a copy: the volumes are reused).
CAPTURED: dict[str, np.ndarray] = {}
_SCANLINE = level.optimization.scanline_optimise


def _capturing(volume, *args, **kwargs):
    """``scanline_optimise``, keeping a copy of the whole range's aggregated volume."""
    bands = kwargs.get("bands")
    if bands is None or bands.is_full:
        CAPTURED["aggregated"] = volume.copy()
    return _SCANLINE(volume, *args, **kwargs)


def overruled(left, right, max_disp, truth, valid, scoring, cfg):
    """The number of overruled ``valid`` pixels and, per group, (name, count, % final
    right, % aggregated right) by ``scoring``'s headline measure; None where the match did
    not search the whole range at full size."""
    CAPTURED.clear()
    final = pipeline.run(left, right, max_disp=max_disp, config=cfg).disparity
    aggregated = CAPTURED.get("aggregated")
    if aggregated is None or aggregated.shape[:2] != truth.shape:
        return None
    raw_l, raw_r = disparity.winner_takes_all_both(aggregated)
    raw_ok = disparity.left_right_check(raw_l, raw_r, n_disp=aggregated.shape[2],
                                        tolerance=1) == disparity.VALID
    over = valid & np.isfinite(final) & (np.abs(final - raw_l) >= 2)
    final_right = ~scoring.bad_map(final, truth)
    raw_right = ~scoring.bad_map(raw_l.astype(np.float32), truth)
    candidates = np.arange(aggregated.shape[2])[None, None, :]
    best = np.take_along_axis(aggregated, raw_l[..., None], -1)[..., 0]
    second = np.where(np.abs(candidates - raw_l[..., None]) >= 2, aggregated, np.inf).min(-1)
    margin = (second - best) / np.maximum(aggregated.mean(-1) - best, 1e-6)
    groups = (("raw LR-ok margin<0.1", raw_ok & (margin < 0.1)),
              ("raw LR-ok 0.1-0.3", raw_ok & (margin >= 0.1) & (margin < 0.3)),
              ("raw LR-ok margin>=0.3", raw_ok & (margin >= 0.3)),
              ("raw inconsistent", ~raw_ok))
    rows = []
    for name, group in groups:
        m = over & group
        n = int(m.sum())
        rows.append((name, n, 100 * final_right[m].mean() if n else 0.0,
                     100 * raw_right[m].mean() if n else 0.0))
    return int(over.sum()), rows


def _print(rows) -> None:
    for name, n, final_right, raw_right in rows:
        print(f"  {name:24s} {n:7d}  final right {final_right:5.1f} %  aggregated right "
              f"{raw_right:5.1f} %")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    level.optimization.scanline_optimise = _capturing
    cfg = load_config("default")
    for spacing in (45, 32):
        pair = fence_pair(spacing=spacing)
        count, rows = overruled(pair.left, pair.right, pair.max_disp, pair.disparity,
                                np.isfinite(pair.disparity) & pair.nonocc,
                                evaluation.Scoring.bad(1.0), cfg)
        print(f"fence, holes {spacing} px: {count} overruled")
        _print(rows)
    for name in ("middlebury2014-quarter", "kitti2015", "eth3d"):
        scoring = evaluation.scoring_for(name)
        totals: dict[str, list[float]] = {}
        for scene in datasets.load_dataset(name, args.data_root):
            truth = scene.ground_truth
            valid = evaluation.headline_mask(scene) & np.isfinite(truth)
            found = overruled(scene.left, scene.right, scene.max_disp, truth, valid,
                              scoring, cfg)
            for group, n, final_right, raw_right in ([] if found is None else found[1]):
                total = totals.setdefault(group, [0, 0.0, 0.0])
                total[0] += n
                total[1] += final_right * n
                total[2] += raw_right * n
        print(name)
        _print([(group, int(n), f / max(n, 1), r / max(n, 1))
                for group, (n, f, r) in totals.items()])


if __name__ == "__main__":
    main()
