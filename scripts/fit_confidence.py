"""Fit the confidence model on every dataset at once, and measure it against its peers.

For each scene of each dataset under the data root: vsmatch (``--config``, default
``default``) over the official range, the confidence features of every pixel, and
whether its disparity is right by the dataset's measure (bad 1.0 on middlebury2 and the
2005/2006 sets, bad 2.0 on Middlebury 2014, D1 on KITTI). A logistic model of the features
and their products (vsmatch.confidence.term_names) is fitted on every pixel with ground
truth, occluded ones too, each dataset weighing the same and each scene the same within it
(r is measured on the non-occluded pixels); the shipped confidence is that model times the
matchability gate (in vsmatch.confidence.combine), which pairs with nothing to match
(flat grey, unrelated noise, two different scenes) are measured against. Printed per
dataset: Hu and Mordohai's r (0 = a perfect ordering, about 1 = chance) of the fitted model,
of the model fitted without that dataset (held out), of the left-right label alone, of the
cost-curve margin alone, and of SGBM's kept/invalid mask (uniqueness 10, disp12MaxDiff 1)
on its own disparity.

    python scripts/fit_confidence.py [--data-root DIR] [--write]

``--write`` stores the weights in vsmatch/confidence_weights.json.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from vsmatch import confidence, datasets, evaluation, pipeline
from vsmatch.disparity import VALID
from vsmatch.peers import sgbm_fill_from_left, sgbm_matcher

DATASETS = ("middlebury2", "middlebury-third", "middlebury2014-quarter", "kitti2015", "eth3d")
#: Pixels sampled per scene for the fit (all are used for the measures).
SAMPLES = 30000
NEGATIVES = "nothing to match"
WEIGHTS_FILE = Path(__file__).resolve().parents[1] / "vsmatch" / "confidence_weights.json"


def fit_logistic(x: np.ndarray, y: np.ndarray, w: np.ndarray, l2: float = 1e-3,
                 steps: int = 30) -> np.ndarray:
    """Weighted logistic regression by Newton's method (IRLS), a little L2 for stability."""
    beta = np.zeros(x.shape[1])
    w = w / w.sum()
    for _ in range(steps):
        p = 1.0 / (1.0 + np.exp(-np.clip(x @ beta, -30, 30)))
        gradient = x.T @ (w * (p - y)) + l2 * beta
        hessian = (x * (w * p * (1 - p))[:, None]).T @ x + l2 * np.eye(x.shape[1])
        step = np.linalg.solve(hessian, gradient)
        beta -= step
        if np.abs(step).max() < 1e-7:
            break
    return beta


def sgbm_mask(scene) -> tuple[np.ndarray, np.ndarray]:
    """SGBM's own disparity and its kept mask (uniqueness 10, disp12MaxDiff 1)."""
    channels = 1 if scene.left.ndim == 2 else scene.left.shape[2]
    matcher = sgbm_matcher(scene.max_disp, channels, min_disp=scene.min_disp)
    matcher.setUniquenessRatio(10)
    matcher.setDisp12MaxDiff(1)
    raw = matcher.compute(scene.left, scene.right)
    kept = raw >= scene.min_disp * 16
    # Scored dense: the rejected pixels take the nearest kept one to the left.
    return sgbm_fill_from_left(raw, scene.min_disp), kept


def grey_scene(scene):
    """The scene with grey views (the held-out benchmarks include grey-scale cameras)."""
    import dataclasses

    import cv2

    return dataclasses.replace(scene, left=cv2.cvtColor(scene.left, cv2.COLOR_BGR2GRAY),
                               right=cv2.cvtColor(scene.right, cv2.COLOR_BGR2GRAY))


def collect(data_root, config, grey=True):
    """Per dataset, per scene: features, correctness, the evaluated mask and peers; with
    ``grey``, each dataset again with grey views as a dataset of its own."""
    out = {}
    available = datasets.load_available(DATASETS, data_root)
    if grey:
        available.update({f"{name} (grey)": [grey_scene(s) for s in scenes]
                          for name, scenes in list(available.items())})
    for name, scenes in available.items():
        scoring = evaluation.scoring_for(name.split()[0])
        rows = []
        for scene in scenes:
            result = pipeline.run(scene.left, scene.right, max_disp=scene.max_disp,
                                  min_disp=scene.min_disp, config=config)
            features = confidence.pixel_features(result.disparity, result.labels, scene.left,
                                                 result.curve)
            evaluated = evaluation.headline_mask(scene) & np.isfinite(scene.ground_truth)
            correct = ~scoring.bad_map(result.disparity, scene.ground_truth)
            # Fitted on every pixel with ground truth, occluded ones too: --cloud writes
            # them all (r on the non-occluded pixels is better so too).
            known = (scene.masks["all"] & np.isfinite(scene.ground_truth)
                     & ~confidence.out_of_view(result.disparity))
            sgbm_disp, kept = sgbm_mask(scene)
            sgbm_correct = ~scoring.bad_map(sgbm_disp, scene.ground_truth)
            rows.append(dict(name=scene.name, features=features, correct=correct,
                             evaluated=evaluated, known=known,
                             disparity=result.disparity,
                             labels=result.labels, sgbm=(kept, sgbm_correct)))
            print(f"  {name}/{scene.name}", flush=True)
        out[name] = rows
    return out


def negative_pairs(data_root, rng):
    """Pairs with nothing to match, every pixel's disparity wrong: flat grey, two unrelated
    noise images (sharp and smooth), and the left view of one real scene beside the
    right view of another. Real data never shows these, so the model must see them."""
    import cv2

    pairs = []
    for level in (40, 128, 220):
        flat = np.full((180, 240, 3), level, np.uint8)
        pairs.append((f"flat{level}", flat, flat.copy(), 48))
    for k, (sigma, height, width, max_disp) in enumerate(
            [(s, 180, 240, 48) for s in (0, 1.5, 4)] + [(s, 120, 160, 32) for s in (0, 0, 2)]
            + [(0, 240, 320, 64)]):
        a, b = (rng.integers(0, 256, (height, width, 3), dtype=np.uint8) for _ in range(2))
        if sigma:
            a, b = (cv2.GaussianBlur(v, (0, 0), sigma) for v in (a, b))
        pairs.append((f"noise{k}", a, b, max_disp))
    # Distinct scenes only (MotorcycleE is Motorcycle under other light, PianoL Piano).
    scenes = [s for s in datasets.load_dataset("middlebury2014-quarter", data_root)
              if s.name not in ("MotorcycleE", "PianoL")]
    for first, second in zip(scenes, scenes[1:] + scenes[:1]):
        right = cv2.resize(second.right, first.left.shape[1::-1])
        pairs.append((f"{first.name}+{second.name}", first.left, right, first.max_disp))
    return pairs


def collect_negatives(data_root, config, rng):
    rows = []
    for name, left, right, max_disp in negative_pairs(data_root, rng):
        result = pipeline.run(left, right, max_disp=max_disp, config=config)
        features = confidence.pixel_features(result.disparity, result.labels, left,
                                             result.curve)
        shape = left.shape[:2]
        rows.append(dict(name=name, features=features, correct=np.zeros(shape, bool),
                         evaluated=np.ones(shape, bool),
                         known=~confidence.out_of_view(result.disparity),
                         disparity=result.disparity, labels=result.labels))
    return rows


def model_terms(features: np.ndarray) -> np.ndarray:
    """Each sample's model terms (confidence.term_names) from its features ``(N, F)``."""
    cells = confidence.term_cells()
    return np.stack([features[:, i] * features[:, j] for i, j in cells], axis=1)


def training_set(data, names, rng):
    xs, ys, ws = [], [], []
    for name in names:
        scenes = data[name]
        for scene in scenes:
            idx = np.flatnonzero(scene["known"])
            if idx.size > SAMPLES:
                idx = rng.choice(idx, SAMPLES, replace=False)
            features = scene["features"].reshape(len(confidence.FEATURES), -1)[:, idx].T
            xs.append(model_terms(features))
            ys.append(scene["correct"].ravel()[idx])
            ws.append(np.full(idx.size, 1.0 / (idx.size * len(scenes) * len(names))))
    return np.concatenate(xs), np.concatenate(ys).astype(np.float64), np.concatenate(ws)


def mean_r(scenes, confidence_of) -> tuple[float, float, float, float]:
    """Mean over scenes of r, AUC, optimum and dense error."""
    measures = [confidence.sparsification(confidence_of(s), s["correct"], s["evaluated"])
                for s in scenes]
    return tuple(float(np.mean([m[k] for m in measures]))
                 for k in ("r", "auc", "optimum", "dense"))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--config", default="default")
    parser.add_argument("--write", action="store_true")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    data = collect(args.data_root, args.config)
    names = list(data)
    # The pairs with nothing to match are measured, not fitted: the gate handles them.
    data[NEGATIVES] = collect_negatives(args.data_root, args.config, rng)
    beta = fit_logistic(*training_set(data, names, rng))
    # Held out: without the dataset, in colour and in grey.
    held_out = {n: fit_logistic(*training_set(
        data, [m for m in names if m.split()[0] != n.split()[0]], rng)) for n in names}

    def model(weights):
        return lambda s: confidence.combine(s["features"], s["disparity"],
                                            confidence.weights_matrix(weights))

    print(f"\n{'dataset':<24}{'model':>8}{'held out':>10}{'LR label':>10}{'margin':>8}"
          f"{'SGBM mask':>11}   (r; AUC / optimum / dense error of the model)")
    for name in names:
        scenes = data[name]
        r_model, auc, optimum, dense = mean_r(scenes, model(beta))
        r_held = mean_r(scenes, model(held_out[name]))[0]
        r_label = mean_r(scenes, lambda s: (s["labels"] == VALID).astype(np.float32))[0]
        r_margin = mean_r(scenes, lambda s: s["features"][confidence.FEATURES.index(
            "margin")])[0]
        sgbm = [confidence.sparsification(s["sgbm"][0].astype(np.float32), s["sgbm"][1],
                                          s["evaluated"])["r"] for s in scenes]
        print(f"{name:<24}{r_model:8.3f}{r_held:10.3f}{r_label:10.3f}{r_margin:8.3f}"
              f"{np.mean(sgbm):11.3f}   {auc:.2f} / {optimum:.2f} / {dense:.2f}")
    negatives = [float(model(beta)(s)[s["evaluated"]].mean()) for s in data[NEGATIVES]]
    print(f"pairs with nothing to match: mean confidence {np.mean(negatives):.3f} "
          f"(largest {max(negatives):.3f}, "
          f"{data[NEGATIVES][int(np.argmax(negatives))]['name']})")
    terms = {k: round(float(v), 5) for k, v in zip(confidence.term_names(), beta)}
    print("\nterms:", json.dumps(terms))
    if args.write:
        WEIGHTS_FILE.write_text(json.dumps({
            "note": "fitted by scripts/fit_confidence.py on " + ", ".join(names)
                    + f" with config '{args.config}'",
            "terms": terms}, indent=2) + "\n")
        print(f"wrote {WEIGHTS_FILE}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
