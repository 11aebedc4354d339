"""How often the automatic range misses, over more kinds of scene than the benchmarks' own.

Each benchmark scene under the data root is tried as it is and in variants whose true
range is known from its ground truth: the views cropped against each other by c columns
(every disparity moves by -c or +c: a verged rig's negative disparities, or a range that
starts far from 0), at half size, in grey. Synthetic scenes made in code add slanted and
fronto-parallel surfaces (vsmatch.synthetic) and a periodic pattern with a known shift.
A variant misses when the non-occluded truth reaches below the range's bottom or above
its top; a refused pair (too few matches, "swapped", "not rectified") is counted apart.

    python scripts/range_kinds.py [--data-root DIR]
"""

from __future__ import annotations

import argparse
from collections import Counter

import cv2
import numpy as np

from vsmatch import datasets, synthetic
from vsmatch.search_range import RangeError, estimate_disparity_range

DATASETS = ("middlebury2", "middlebury-third", "middlebury2014-quarter", "kitti2015")


def cropped(left, right, gt, mask, shift):
    """The views cropped so that every disparity moves by ``shift`` (either sign)."""
    c = abs(shift)
    if shift > 0:  # L'(x) = L(x), R'(x) = R(x + c): d' = d + c
        return left[:, :-c], right[:, c:], gt[:, :-c] + c, mask[:, :-c]
    # L'(x) = L(x + c), R'(x) = R(x): d' = d - c
    return left[:, c:], right[:, :-c], gt[:, c:] - c, mask[:, c:]


def variants(left, right, gt, mask):
    yield "as is", left, right, gt, mask
    top = float(gt[mask].max())
    for name, shift in (("crop -half", -round(top / 2)), ("crop -max", -round(top)),
                        ("crop +40", 40)):
        yield name, *cropped(left, right, gt, mask, shift)
    half = [cv2.resize(v, (v.shape[1] // 2, v.shape[0] // 2), interpolation=cv2.INTER_AREA)
            for v in (left, right)]
    small_gt = cv2.resize(gt, (gt.shape[1] // 2, gt.shape[0] // 2),
                          interpolation=cv2.INTER_NEAREST) / 2
    small_mask = cv2.resize(mask.astype(np.uint8), (gt.shape[1] // 2, gt.shape[0] // 2),
                            interpolation=cv2.INTER_NEAREST) > 0
    yield "half size", *half, small_gt, small_mask & np.isfinite(small_gt)
    grey = [cv2.cvtColor(v, cv2.COLOR_BGR2GRAY) for v in (left, right)]
    yield "grey", *grey, gt, mask


def periodic(shift: int, period: int = 24, height: int = 200, width: int = 400, seed=0):
    """Vertical bars of one period with a little texture: a left pixel x shows what the
    right pixel x - shift shows."""
    rng = np.random.default_rng(seed)
    xs = np.arange(width + shift)
    row = (127 + 100 * np.sign(np.sin(2 * np.pi * xs / period))).astype(np.float32)
    wide = np.repeat(row[None], height, axis=0) + rng.normal(0, 6, (height, width + shift))
    wide = np.clip(wide, 0, 255).astype(np.uint8)
    left, right = wide[:, shift:shift + width], wide[:, :width]
    gt = np.full((height, width), float(shift), np.float32)
    return left, right, gt, np.ones_like(gt, bool)


def scenes(data_root):
    for name, found in datasets.load_available(DATASETS, data_root).items():
        for scene in found:
            mask = scene.masks.get("nonocc", scene.masks["all"]) & np.isfinite(
                scene.ground_truth)
            yield name, scene.name, scene.left, scene.right, scene.ground_truth, mask
    for seed in range(3):
        pair = synthetic.make_pair(seed=seed)
        yield "synthetic", f"shapes{seed}", pair.left, pair.right, pair.disparity, pair.nonocc
    for shift in (13, 30):
        yield "synthetic", f"bars{shift}", *periodic(shift)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    outcome = Counter()
    print(f"{'dataset':<24}{'scene':<12}{'variant':<12}{'true':>14}{'found':>14}  result")
    for dataset, scene, left, right, gt, mask in scenes(args.data_root):
        kinds = variants(left, right, gt, mask) if dataset != "synthetic" else [
            ("as is", left, right, gt, mask)]
        for variant, vl, vr, vgt, vmask in kinds:
            vl, vr = np.ascontiguousarray(vl), np.ascontiguousarray(vr)
            low, high = float(vgt[vmask].min()), float(vgt[vmask].max())
            try:
                found = estimate_disparity_range(vl, vr)
            except RangeError as exc:
                result, text = "refused", str(exc).split(":")[0][:40]
            else:
                text = f"{found.min_disp}..{found.max_disp}"
                short = []
                if low < found.min_disp:
                    short.append(f"bottom short by {found.min_disp - low:.1f}")
                if high > found.max_disp:
                    short.append(f"top short by {high - found.max_disp:.1f}")
                result = "MISS " + ", ".join(short) if short else "covered"
            outcome[(dataset == "synthetic", result.split()[0])] += 1
            print(f"{dataset:<24}{scene:<12}{variant:<12}{f'{low:.1f}..{high:.1f}':>14}"
                  f"{text:>14}  {result}", flush=True)
    for synthetic_kind in (False, True):
        counts = {k[1]: v for k, v in outcome.items() if k[0] == synthetic_kind}
        total = sum(counts.values())
        print(f"{'synthetic' if synthetic_kind else 'benchmark variants'}: {total} pairs, "
              + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
