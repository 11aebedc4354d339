"""Confidence per pixel: how likely the disparity is right, in [0, 1].

What the method already knows, per pixel (:func:`pixel_features`):

- the cost curve where the winner was chosen: the margin to the second minimum at least
  two disparities away, relative to it (a sharp, unique minimum), and the winner's
  distance below the curve's mean; the same margin on the aggregated costs before the
  scanline optimisation;
- the left-right check: passed, or rejected as mismatched or occluded, and how far the
  nearest pixel that passed lies (how far a fill had to reach);
- the support region's size (the cross arms) and the image texture around the pixel;
- the distance to the nearest disparity jump;
- how far inside the right view the match lies; out of view (no right pixel at its
  disparity, x - d < 0) gives confidence 0.

A logistic model of the features and their products two by two (a margin counts for more
where the check passed) combines them, gated by how clearly the neighbourhood matched at
all (the gate of :func:`combine`); its weights are fitted on the developers' data, all datasets
together (``python scripts/fit_confidence.py`` re-fits them and writes
``vsmatch/confidence_weights.json``). The confidence never changes the disparity.

Repeated texture (fins, fences, tiles) is capped apart: a match a period off has as clear
a final curve as the right one, so :func:`repeated_texture` looks for another valley of the
aggregated curve where the left view repeats itself at that offset (:func:`cap_repeated`).

:func:`sparsification` measures a confidence as Hu and Mordohai do: keep the most
confident 5 %, 10 %, ... 100 % of the pixels and average the error rate of what is kept.
"""

from __future__ import annotations

import json
from functools import lru_cache
from importlib import resources

import cv2
import numpy as np

from ._kernels.rows import thread_classes
from ._kernels.confidence import (CHAMFER_STEP, cap_flat, chamfer_distances, cost_curve,
                                  cost_curve_and_rivals, gated_logistic, pixel_terms, repeats_at,
                                  rival_offsets)
from .bands import Bands, of
from .disparity import MISMATCHED, VALID, labels_for_kernels
from .images import grey_levels, plane_blur, upsample_nearest
from .sensitivity import TEXTURE_WINDOW
from .tiles import row_blocks

#: The features, in the order of the model's weights (a constant first).
FEATURES = ("bias", "margin", "margin_sq", "below_mean", "valid", "mismatched",
            "fill_distance", "support", "texture", "jump_distance", "view_edge",
            "raw_margin")
#: Curve features the full search hands on (through stripes and pyramid levels).
CURVE_FEATURES = ("margin", "below_mean", "support", "raw_margin", "repeated")
#: Added to the costs the curve's ratios divide by: a flat curve of tiny costs (a blank
#: pair, where rounding alone separates the minima) must not look sharp. The costs the
#: winner is chosen on are 0.2-2.8 per pixel on real scenes (cones: the 1st-99th
#: percentiles of the best and second costs).
CURVE_FLOOR = 0.5
#: The matchability gate: each margin's mean over a GATE_WINDOW square rising from its
#: FROM to its TO. Measured (scripts/fit_confidence.py): the mean margin of a scene is
#: 0.23-0.49 on the four datasets, 0.07-0.13 on pairs with nothing to match; that of the
#: aggregated costs 0.06-0.30 and at most 0.03. With the margin's gate alone, a small
#: noise pair kept 0.33 on average (streaks the scanline penalties sharpen); with both,
#: those pairs average 0.02 (largest 0.08), and r on the datasets moves by <= 0.01.
GATE_WINDOW, GATE_FROM, GATE_TO = 15, 0.12, 0.2
RAW_GATE_FROM, RAW_GATE_TO = 0.003, 0.01
#: Distances (pixels) beyond which the fill and jump distances count the same.
MAX_DISTANCE = 16.0
#: The densities of the sparsification curve: 5 %, 10 %, ... 100 %.
DENSITIES = np.arange(1, 21) / 20.0


def neighbourhood_margin(margin: np.ndarray) -> np.ndarray:
    """The mean of each pixel's cost-curve ``margin`` (a curve map, :func:`curve_features`)
    over the :data:`GATE_WINDOW` square about it, float32: what the matchability gate judges
    a neighbourhood by."""
    return plane_blur(np.ascontiguousarray(margin[None], dtype=np.float32), GATE_WINDOW)[0]


def cost_curves(volume: np.ndarray, winners: np.ndarray, bands: Bands | None = None
                ) -> tuple[np.ndarray, ...]:
    """Each pixel's best cost, second minimum at least 2 away, and mean cost over its
    in-view candidates (of ``bands``, default the whole range; float32 maps);
    ``disparity.winner_takes_all_with_curve`` gives the same from its own pass."""
    bands = of(volume, bands)
    best, second, mean = (np.empty(volume.shape[:2], np.float32) for _ in range(3))
    cost_curve(volume, bands.lo, bands.count, np.ascontiguousarray(winners, dtype=np.int32),
               1, best, second, mean)
    return best, second, mean


def curve_features(curves: tuple[np.ndarray, ...],
                   arms: np.ndarray | None) -> dict[str, np.ndarray]:
    """The features of each pixel's cost curve (float32 maps) from :func:`cost_curves`:
    ``margin`` = (second minimum at least 2 away - best) / (second + floor),
    ``below_mean`` = (mean - best) / (mean + floor), and ``support`` = log(1 + the
    cross's arm lengths)."""
    best, second, mean = curves
    shape = best.shape
    floor = np.float32(CURVE_FLOOR)
    features = {
        "margin": (second - best) / (second + floor),
        "below_mean": (mean - best) / (mean + floor),
    }
    if arms is None:
        features["support"] = np.zeros(shape, np.float32)
    else:
        features["support"] = np.empty(shape, np.float32)
        log1p_into(arms.astype(np.float32).sum(axis=0), features["support"])
    return {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in features.items()}


#: Repeated texture (fins, fences, tiles): a pixel whose aggregated cost curve has another
#: valley within RIVAL_REACH disparities (behind a rise of at least RIVAL_HUMP x the
#: curve's mean above its best) within RIVAL_LEVEL x (mean - best + RIVAL_FLOOR) of the
#: winner's cost, where the left view repeats itself at that offset (rows +-REPEAT_RADIUS,
#: columns +-REPEAT_REACH at most; below REPEAT_SIMILAR x the difference at half the
#: offset: :func:`repeated_texture`).
#: Measured on synthetic fins of 5-16 px in front of a wall and on the datasets
#: (docs/confidence.md, "Repeated texture"): the view's test is what tells fins from fine
#: random texture (KITTI's near road has such rivals on 10-25 % of its confident pixels,
#: and no repeat).
RIVAL_HUMP, RIVAL_LEVEL, RIVAL_FLOOR, RIVAL_REACH = 0.5, 0.1, 0.05, 32
REPEAT_RADIUS, REPEAT_REACH, REPEAT_SIMILAR = 2, 8, 0.5
#: A repeat is a region's property: a pixel with more than REPEAT_SHARE of its
#: REPEAT_WINDOW square repeating keeps at most RANGE_END_CONFIDENCE (its match could be a
#: period off with as clear a curve as the right one, once the scanline settles it).
REPEAT_WINDOW, REPEAT_SHARE = 15, 0.2


#: The curve map of each pixel's rival offset (:func:`rival_offsets`' lag, signed) as a
#: share of its view's width, 0 where there is none: a level up, where the curves stand
#: for the band search's, the repeat is tested again on the larger view
#: (:func:`curve_a_level_up`).
RIVAL = "rival"


def repeated_texture(aggregated: np.ndarray, winners: np.ndarray,
                     curves: tuple[np.ndarray, ...], grey: np.ndarray) -> np.ndarray:
    """1 where a pixel's match has a rival a repeat of the left view away (float32 0/1
    map; ``aggregated``: the whole-range costs before the scanline optimisation,
    ``winners`` the chosen disparities, ``curves`` their :func:`cost_curves` on
    ``aggregated``, ``grey`` the left view's grey levels)."""
    return _repeats(grey, rivals(aggregated, winners, curves))


def rivals(aggregated: np.ndarray, winners: np.ndarray,
           curves: tuple[np.ndarray, ...]) -> np.ndarray:
    """Each pixel's offset to the rival valley of its ``aggregated`` cost curve (int32, 0
    where none; :func:`repeated_texture`'s arguments)."""
    offsets = np.empty(winners.shape, np.int32)
    rival_offsets(aggregated, np.ascontiguousarray(winners, dtype=np.int32), *curves,
                  RIVAL_HUMP, RIVAL_LEVEL, RIVAL_FLOOR, RIVAL_REACH, offsets)
    return offsets


def curves_and_rivals(aggregated: np.ndarray, winners: np.ndarray
                      ) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
    """:func:`cost_curves` of the whole-range ``aggregated`` costs and :func:`rivals`, the
    curves read once."""
    curves = tuple(np.empty(winners.shape, np.float32) for _ in range(3))
    offsets = np.empty(winners.shape, np.int32)
    cost_curve_and_rivals(aggregated, np.ascontiguousarray(winners, dtype=np.int32), 1,
                          RIVAL_HUMP, RIVAL_LEVEL, RIVAL_FLOOR, RIVAL_REACH, *curves, offsets)
    return curves, offsets


def repeats_and_rivals(grey: np.ndarray, offsets: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
    """The curve maps ``repeated`` (:func:`repeated_texture`) and :data:`RIVAL` of a level's
    rival ``offsets`` on its left view's ``grey`` levels."""
    return _repeats(grey, offsets), (offsets / np.float32(grey.shape[1])).astype(np.float32)


def curve_a_level_up(curve: dict[str, np.ndarray], left: np.ndarray) -> dict[str, np.ndarray]:
    """A level's curve maps for the view a pyramid level up (``left``, about twice the
    size), where the band search has no whole-range curve of its own: each map repeated
    over the larger view, and a pixel's repeat tested again there, at its rival's offset
    scaled to the larger view and a pixel either side, at the level's own pixels. Fins of
    5 px are 2.5 px a level down, where their rival's repeat does not show in the view:
    `fast` kept 3.4 % of such fins confident and wrong (a period or two off), their repeat
    unseen; 1.1 % so (``scripts/repeated_texture.py``)."""
    shape = left.shape[:2]
    up = {name: upsample_nearest(values, shape) for name, values in curve.items()}
    if RIVAL not in up:
        return up
    # Looked at on the level's own pixels (every other row and column of the larger view,
    # each standing for its 2 x 2 block, as every curve map does): a quarter of the work.
    # A lag doubled is the larger view's within a pixel.
    lag = np.rint(up[RIVAL][::2, ::2] * np.float32(shape[1])).astype(np.int32)
    lag[up["repeated"][::2, ::2] > 0] = 0  # a repeat a level down stays one: not looked at again
    repeats = _repeats(grey_levels(left), lag, spread=1, step=2)
    up["repeated"] = np.maximum(up["repeated"], upsample_nearest(repeats, shape))
    return up


def _repeats(grey: np.ndarray, offsets: np.ndarray, spread: int = 0, step: int = 1
             ) -> np.ndarray:
    """1 where the view (``grey`` levels, whole numbers 0-255) repeats itself at each
    pixel's rival ``offsets``, or within ``spread`` pixels of them (float32); with ``step``
    2, ``offsets`` are those of every other row and column of the view, and so is the
    map."""
    repeated = np.empty(offsets.shape, np.float32)
    repeats_at(np.ascontiguousarray(grey, dtype=np.uint8),
               np.ascontiguousarray(offsets, dtype=np.int32), step, REPEAT_RADIUS,
               REPEAT_REACH, REPEAT_SIMILAR, spread, thread_classes(), repeated)
    return repeated


def pixel_features(disparity: np.ndarray, labels: np.ndarray | None, left: np.ndarray,
                   curve: dict[str, np.ndarray]) -> np.ndarray:
    """The :data:`FEATURES` of every pixel, ``(len(FEATURES), H, W)`` float32."""
    shape = disparity.shape
    out = np.empty((len(FEATURES),) + shape, np.float32)
    row = {name: out[k] for k, name in enumerate(FEATURES)}
    row["bias"].fill(1.0)
    targets = np.empty((2,) + shape, np.bool_)  # valid pixels, disparity jumps
    # How far inside the right view the match lies (near its left edge, little of the
    # support region has a partner).
    inside = np.empty(shape, np.float32)
    gradient = np.empty((1,) + shape, np.float32)
    pixel_terms(*(np.ascontiguousarray(curve[name], dtype=np.float32)
                  for name in ("margin", "below_mean", "raw_margin", "support")),
                labels_for_kernels(labels), VALID, MISMATCHED,
                np.ascontiguousarray(disparity, dtype=np.float32),
                np.ascontiguousarray(grey_levels(left)), np.float32(MAX_DISTANCE),
                row["margin"], row["margin_sq"], row["below_mean"], row["raw_margin"],
                row["support"], row["valid"], row["mismatched"], targets, inside, gradient)
    fill, jump = distances_to(targets)
    log1p_into(fill, row["fill_distance"])
    log1p_into(plane_blur(gradient, TEXTURE_WINDOW)[0], row["texture"])
    log1p_into(jump, row["jump_distance"])
    log1p_into(inside, row["view_edge"])
    return out


def distances_to(targets: np.ndarray) -> np.ndarray:
    """For each (H, W) mask of ``targets`` (K, H, W), each pixel's distance (pixels, at
    most MAX_DISTANCE; float32) to the nearest True one: OpenCV's 3 x 3 chamfer distance
    (distanceTransform, DIST_L2, mask 3), worked out in bands of rows on every core."""
    targets = np.ascontiguousarray(targets, dtype=np.bool_)
    out = np.empty(targets.shape, np.float32)
    # A path of MAX_DISTANCE spans at most MAX_DISTANCE / the shortest step rows.
    halo = int(np.ceil(MAX_DISTANCE / CHAMFER_STEP)) + 1
    band_rows = max(2 * halo, -(-targets.shape[1] // thread_classes()))
    chamfer_distances(targets, np.float32(MAX_DISTANCE), band_rows, halo, out)
    return out


#: Rows of the confidence computed at a time, and the rows around them each block reads:
#: the distance features reach MAX_DISTANCE (chamfer distances of at least 0.955 px a
#: step: 17 rows), the matchability gate half its window, the blob test half its window.
#: Blocks give the same bytes as one piece (a test); they bound the features' memory
#: (48 bytes a pixel) on camera-size pairs.
CONFIDENCE_ROWS = 512
CONFIDENCE_MARGIN = 24


def confidence_map(disparity: np.ndarray, labels: np.ndarray | None, left: np.ndarray,
                   curve: dict[str, np.ndarray], n_disp: int) -> np.ndarray:
    """Each pixel's confidence in [0, 1] (float32): :func:`pixel_features`,
    :func:`combine`, and the caps at the range's ends, on textureless blobs and on pixels
    without texture, in blocks of :data:`CONFIDENCE_ROWS` rows."""
    out = np.empty(disparity.shape, np.float32)
    for top, bottom, y0, y1 in row_blocks(disparity.shape[0], CONFIDENCE_ROWS,
                                          CONFIDENCE_MARGIN):
        rows = slice(y0, y1)
        disp = disparity[rows]
        features = pixel_features(disp, None if labels is None else labels[rows],
                                  left[rows], {k: v[rows] for k, v in curve.items()})
        block = combine(features, disp)
        cap_range_ends(block, disp, n_disp)
        cap_flat_blobs(block, disp, features[FEATURES.index("texture")])
        cap_textureless(block, features[FEATURES.index("texture")])
        cap_repeated(block, curve["repeated"][rows])
        out[top:bottom] = block[top - y0:bottom - y0]
    return out


def log1p_into(values: np.ndarray, out: np.ndarray) -> None:
    """out = log(1 + values), float32 (H, W), by OpenCV's vectorised log: NumPy's float32
    log1p is not vectorised (its four calls took a third of the stage); within 3e-7 of
    log1p on the features' values (0 .. a few hundred)."""
    cv2.log(cv2.add(values, 1.0), dst=out)


def term_cells() -> list[tuple[int, int]]:
    """The model's terms as cells (i, j), i <= j, of the quadratic form over
    :data:`FEATURES` (whose first is the constant 1): the bias, each feature, then each
    product of two features (a feature with itself too)."""
    n = len(FEATURES)
    return ([(0, 0)] + [(0, k) for k in range(1, n)]
            + [(i, j) for i in range(1, n) for j in range(i, n)])


def term_names() -> list[str]:
    """The name of each of :func:`term_cells`, in its order (the keys of
    ``confidence_weights.json``): ``bias``, a feature's name, or ``a*b`` for a product: a
    margin counts for more where the check passed, a texture for less near a jump."""
    return [FEATURES[j] if i == 0 else f"{FEATURES[i]}*{FEATURES[j]}"
            for i, j in term_cells()]


@lru_cache(maxsize=None)
def model_weights() -> np.ndarray:
    """The fitted model as the upper-triangular matrix of its quadratic form over
    :data:`FEATURES` (float32, ``(n, n)``), from the named terms of
    ``confidence_weights.json`` (:func:`term_names`)."""
    text = (resources.files(__package__) / "confidence_weights.json").read_text()
    stored = json.loads(text)["terms"]
    return weights_matrix([stored[name] for name in term_names()])


def weights_matrix(values) -> np.ndarray:
    """The quadratic form's matrix of the terms' ``values`` (in :func:`term_names`'
    order)."""
    n = len(FEATURES)
    matrix = np.zeros((n, n), np.float32)
    for (i, j), value in zip(term_cells(), values, strict=True):
        matrix[i, j] = value
    return matrix


def combine(features: np.ndarray, disparity: np.ndarray,
            weights: np.ndarray | None = None) -> np.ndarray:
    """Confidence in [0, 1] (float32): the logistic model over ``features`` (``weights``:
    the matrix of its quadratic form, default :func:`model_weights`), times the
    matchability gate of the pixel's neighbourhood; 0 where the disparity is invalid or
    points out of the right view (x - d < 0).

    The gate (0 .. 1) rises with the mean cost-curve margins over a :data:`GATE_WINDOW`
    square, of the costs the winner was chosen on and of the aggregated costs before the
    scanline optimisation: where no curve has a clear minimum (a blank wall, two unrelated
    views) nothing was really matched, whatever the other features say. The scanline
    penalties alone can sharpen a curve of unrelated views into a streak, which the
    aggregated costs do not show. Real scenes never show such pairs, so the model cannot
    learn them from the data."""
    weights = model_weights() if weights is None else weights
    # A kernel, not np.tensordot: BLAS's worker threads would keep spinning and slow the
    # next pair's Numba kernels by ~15 % on 2 cores (measured).
    margins = plane_blur(np.stack([features[FEATURES.index("margin")],
                                   features[FEATURES.index("raw_margin")]]), GATE_WINDOW)
    ramps = np.array([GATE_FROM, GATE_TO - GATE_FROM, RAW_GATE_FROM,
                      RAW_GATE_TO - RAW_GATE_FROM], np.float32)
    confidence = np.empty(features.shape[1:], np.float32)
    gated_logistic(np.ascontiguousarray(features, dtype=np.float32),
                   np.asarray(weights, dtype=np.float32), margins, ramps,
                   np.ascontiguousarray(disparity, dtype=np.float32), confidence)
    return confidence


#: The confidence a winner at either end of the searched range keeps at most: its cost
#: curve may still fall beyond the range (the true disparity lies outside it), so it is
#: never trusted for depth and clouds (below every config's ``cloud.min_confidence``).
RANGE_END_CONFIDENCE = 0.5


def cap_range_ends(confidence: np.ndarray, disparity: np.ndarray, n_disp: int) -> None:
    """Cap, in place, the confidence of pixels whose disparity lies within half a pixel
    of 0 or of ``n_disp - 1``, the ends of the range searched (0-based)."""
    with np.errstate(invalid="ignore"):
        ends = (disparity < 0.5) | (disparity > n_disp - 1.5)
    _cap(confidence, ends, RANGE_END_CONFIDENCE)


#: A blob of one value: every disparity of the BLOB_WINDOW square within BLOB_SPREAD px of
#: one another, where the texture feature (log(1 + the blurred gradient)) is below
#: BLOB_TEXTURE: a textureless area the matching could not tell apart, stuck at one value
#: (a real surface fitted by the planes or the sub-pixel fit varies by more).
BLOB_WINDOW, BLOB_SPREAD, BLOB_TEXTURE = 15, 1e-3, float(np.log1p(8.0))


def cap_flat_blobs(confidence: np.ndarray, disparity: np.ndarray,
                   texture: np.ndarray) -> None:
    """Cap, in place, the confidence of blobs of one value in textureless areas at
    :data:`RANGE_END_CONFIDENCE` (below the cloud's threshold)."""
    # Invalid pixels are left out of a square's extent (one of nothing but invalid pixels
    # counts as flat).
    cap_flat(np.ascontiguousarray(disparity, dtype=np.float32),
             np.ascontiguousarray(texture, dtype=np.float32), BLOB_WINDOW // 2,
             np.float32(BLOB_SPREAD), np.float32(BLOB_TEXTURE),
             np.float32(RANGE_END_CONFIDENCE), confidence)


#: A pixel without texture (the texture feature below log(1 + NO_TEXTURE): under an eighth
#: of a grey level a pixel, as accurate's surfaces.flat) keeps at most TEXTURELESS_CONFIDENCE,
#: below every config's cloud.min_confidence: the match saw nothing there, and a faint
#: shading or a grey level of exposure left over can set it a few pixels off with a sharp
#: cost curve (Vintage's wall). The ukulele wall's cloud beyond the room 0.73 -> 0.46 %
#: (scripts/real_scenes.py); r within 0.004. At 0.85 with the cloud's threshold at 0.88
#: (0.9 and 0.92 before): the ukulele's 0.45 % (0.59 % with the cap left at 0.9).
NO_TEXTURE, TEXTURELESS_CONFIDENCE = 1.0, 0.85


def cap_textureless(confidence: np.ndarray, texture: np.ndarray) -> None:
    """Cap, in place, the confidence of pixels without texture (``texture``: the feature)
    at :data:`TEXTURELESS_CONFIDENCE`."""
    _cap(confidence, texture < np.float32(np.log1p(NO_TEXTURE)), TEXTURELESS_CONFIDENCE)


def cap_repeated(confidence: np.ndarray, repeated: np.ndarray) -> None:
    """Cap, in place, the confidence where more than :data:`REPEAT_SHARE` of the
    :data:`REPEAT_WINDOW` square around a pixel is ``repeated`` (the curve feature of
    :func:`repeated_texture`) at :data:`RANGE_END_CONFIDENCE`."""
    share = plane_blur(np.ascontiguousarray(repeated, dtype=np.float32)[None],
                       REPEAT_WINDOW)[0]
    _cap(confidence, share > REPEAT_SHARE, RANGE_END_CONFIDENCE)


def _cap(confidence: np.ndarray, where: np.ndarray, value: float) -> None:
    """``confidence`` at most ``value`` where ``where`` holds, in place."""
    np.minimum(confidence, np.float32(value), out=confidence, where=where)


def keep_confident(disparity: np.ndarray, confidence: np.ndarray,
                   minimum: float) -> np.ndarray:
    """The disparity with pixels below ``minimum`` confidence, and those out of view
    (confidence 0), marked invalid (inf)."""
    out = disparity.copy()
    out[(confidence < minimum) | out_of_view(disparity)] = np.inf
    return out


def out_of_view(disparity: np.ndarray) -> np.ndarray:
    """Pixels without an estimate or whose match would lie left of the right view."""
    columns = np.arange(disparity.shape[1], dtype=np.float32)[None, :]
    with np.errstate(invalid="ignore"):
        return ~np.isfinite(disparity) | (columns - disparity < -0.5)


def sparsification(confidence: np.ndarray, correct: np.ndarray, evaluated: np.ndarray,
                   seed: int = 1234) -> dict[str, float]:
    """Hu and Mordohai's measure over the ``evaluated`` pixels: ``auc`` is the error rate
    (%) of the most confident 5 %, 10 %, ... 100 % averaged, ``optimum`` the same for a
    perfect ordering, ``dense`` the error rate of all, and ``r`` = (auc - optimum) /
    (dense - optimum): 0 a perfect ordering, about 1 no better than chance. Ties are
    broken at random (``seed``), so a constant confidence gives r near 1."""
    conf = confidence[evaluated].astype(np.float64)
    bad = ~correct[evaluated]
    count = conf.size
    if count == 0:
        return {"auc": float("nan"), "optimum": float("nan"), "dense": float("nan"),
                "r": float("nan")}
    tiebreak = np.random.default_rng(seed).random(count)
    order = np.lexsort((tiebreak, -conf))
    bad_sorted = np.cumsum(bad[order])
    perfect = np.cumsum(np.sort(bad))  # the good pixels first
    keep = np.maximum(1, np.round(DENSITIES * count).astype(int))
    auc = float(np.mean(bad_sorted[keep - 1] / keep)) * 100
    optimum = float(np.mean(perfect[keep - 1] / keep)) * 100
    dense = float(bad.mean()) * 100
    spread = dense - optimum
    r = (auc - optimum) / spread if spread > 0 else 0.0
    return {"auc": auc, "optimum": optimum, "dense": dense, "r": float(r)}
