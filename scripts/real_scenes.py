"""Every dataset at once, and the real camera pairs as EVALUATION.md measures them.

For each variant (``CONFIG`` or ``CONFIG=YAML``, a YAML mapping merged over the config):
middlebury2 and middlebury-third bad 1.0, Middlebury 2014 quarter bad 2.0 / bad 0.5 /
integer share, KITTI 2015 D1, ETH3D bad 1.0 / bad 0.5 (non-occluded, mean of the scenes),
the mean confidence r; then the real pairs without ground truth: the share of SIFT matches
on the rectified pair that the disparity misses by more than 2 px, and the share of the
cloud (confidence >= the config's ``cloud.min_confidence``) farther than 1.5 x the SIFT
matches' 99th-percentile depth; and the desk's near top (its bottom rows' median
disparity, about 125 px) matched without its calibration.

    python scripts/real_scenes.py [--data-root DIR] [--only eth3d,kitti2015] default fast \\
        "default={cost: {lambda_ad: null}}"
"""

from __future__ import annotations

import argparse
import time

import cv2
import numpy as np
import yaml

import vsmatch
from vsmatch import datasets, evaluation, geometry, pipeline, rig
from vsmatch.confidence import keep_confident
from vsmatch.config import config_from_dict, load_config
from vsmatch.search_range import estimate_disparity_range

#: (dataset, mask, measures reported) in the order of the columns.
DATASETS = (("middlebury2", "nonocc", ("bad1.0",)),
            ("middlebury-third", "nonocc", ("bad1.0",)),
            ("middlebury2014-quarter", "nonocc", ("bad2.0", "bad0.5", "integer_share")),
            ("kitti2015", "all", ("D1",)),
            ("eth3d", "nonocc", ("bad1.0", "bad0.5", "integer_share")))
#: SIFT matches: Lowe's ratio, and how far from one row a match may lie.
RATIO, ROW_TOLERANCE = 0.7, 1.0


def real_pairs(root):
    """(name, rectified left, right, camera) of the real camera pairs."""
    desk = root / "real-cameras" / "desk"
    left, right = (cv2.imread(str(desk / f"{s}.png")) for s in ("left", "right"))
    yield "desk", left, right, geometry.read_calibration(desk / "calib.txt")
    raw = root / "real-cameras" / "ukulele-raw"
    left, right = (cv2.imread(str(raw / f"{s}.png")) for s in ("left", "right"))
    rectifier = rig.Rectifier(rig.read_rig([raw / "rig.yml"]), left.shape[1::-1])
    left, right = rectifier.rectify(left, right)
    yield "ukulele", left, right, rectifier.calibration()


def sift_matches(left, right) -> np.ndarray:
    """(x, y, d) of the SIFT matches on one row, sub-pixel."""
    sift = cv2.SIFT_create()
    keys_l, desc_l = sift.detectAndCompute(cv2.cvtColor(left, cv2.COLOR_BGR2GRAY), None)
    keys_r, desc_r = sift.detectAndCompute(cv2.cvtColor(right, cv2.COLOR_BGR2GRAY), None)
    out = []
    for pair in cv2.BFMatcher(cv2.NORM_L2).knnMatch(desc_l, desc_r, k=2):
        if len(pair) == 2 and pair[0].distance < RATIO * pair[1].distance:
            (xl, yl), (xr, yr) = keys_l[pair[0].queryIdx].pt, keys_r[pair[0].trainIdx].pt
            if abs(yl - yr) <= ROW_TOLERANCE and xl - xr > 0:
                out.append((xl, yl, xl - xr))
    return np.array(out)


def real_measures(cfg, left, right, camera) -> tuple[float, float, dict]:
    """SIFT disagreement (%), cloud beyond the depth bound (%), and the result."""
    ndisp = camera.search_range_for(left.shape[1])
    if ndisp is not None:
        low, high = 0, ndisp - 1
    else:
        found = estimate_disparity_range(left, right)
        low, high = found.min_disp, max(found.max_disp, found.min_disp + 1)
    result = pipeline.run(left, right, max_disp=high, min_disp=low, config=cfg)
    matches = sift_matches(left, right)
    xs, ys = np.round(matches[:, 0]).astype(int), np.round(matches[:, 1]).astype(int)
    found = result.disparity[ys, xs]
    with np.errstate(invalid="ignore"):
        disagree = 100.0 * float(np.mean(~(np.abs(found - matches[:, 2]) <= 2)))
    depth = geometry.depth_from_disparity(
        keep_confident(result.disparity, result.confidence,
                       load_config(cfg).cloud.min_confidence), camera)
    sift_depth = camera.focal * camera.baseline / (matches[:, 2] + camera.doffs)
    bound = 1.5 * np.percentile(sift_depth[sift_depth > 0], 99)
    points = depth[np.isfinite(depth)]
    beyond = 100.0 * float(np.mean(points > bound)) if points.size else float("nan")
    return disagree, beyond, {"disparity": result.disparity, "confidence": result.confidence}


def desk_near_top(root, cfg) -> float:
    """The desk's median disparity over its bottom 60 rows (the near desk top, about 125
    px) with the range found from the pair, as `vsmatch run` without --calib searches."""
    desk = root / "real-cameras" / "desk"
    left, right = (cv2.imread(str(desk / f"{s}.png")) for s in ("left", "right"))
    disp = vsmatch.match(left, right, config=cfg)[-60:]
    return float(np.median(disp[np.isfinite(disp)]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--only", default=None, help="comma-separated datasets (and 'real')")
    parser.add_argument("--save", default=None, help="folder for the real pairs' pictures")
    parser.add_argument("variants", nargs="+")
    args = parser.parse_args()
    root = datasets.dataset_folder("middlebury2", args.data_root).parent
    wanted = set(args.only.split(",")) if args.only else None
    chosen = [d for d in DATASETS if wanted is None or d[0] in wanted]
    scene_sets = {name: datasets.load_dataset(name, args.data_root) for name, _, _ in chosen}
    header = [f"{name[:10]} {m}" for name, _, measures in chosen for m in measures]
    if wanted is None or "real" in wanted:
        header += ["r", "desk sift", "desk far", "uku sift", "uku far", "desk near"]
    print("variant | " + " | ".join(header) + " | seconds", flush=True)
    for variant in args.variants:
        name, _, changes = variant.partition("=")
        cfg = config_from_dict(yaml.safe_load(changes) or {}, base=load_config(name))
        cells, rs, start = [], [], time.perf_counter()
        for dataset, mask, measures in chosen:
            report = evaluation.evaluate(scene_sets[dataset], {"m": cfg}, dataset=dataset)
            avg = report["methods"]["m"]["avg"]
            cells += [avg["metrics"][mask][m] for m in measures]
            rs.append(avg["confidence"]["r"])
        if wanted is None or "real" in wanted:
            cells.append(float(np.mean(rs)) if rs else float("nan"))
            for pair_name, left, right, camera in real_pairs(root):
                disagree, beyond, result = real_measures(cfg, left, right, camera)
                cells += [disagree, beyond]
                if args.save:
                    save_pictures(args.save, f"{name}_{pair_name}", left, result,
                                  load_config(cfg).cloud.min_confidence)
            cells.append(desk_near_top(root, cfg))
        print(f"{variant} | " + " | ".join(f"{c:.3f}" if abs(c) < 1 else f"{c:.2f}"
                                           for c in cells)
              + f" | {time.perf_counter() - start:.0f}", flush=True)


def save_pictures(folder, stem, left, result, threshold) -> None:
    from pathlib import Path

    from vsmatch.preview import disparity_preview

    Path(folder).mkdir(parents=True, exist_ok=True)
    picture = disparity_preview(result["disparity"], result["confidence"], threshold)
    cv2.imwrite(str(Path(folder) / f"{stem}.png"), picture)


if __name__ == "__main__":
    main()
