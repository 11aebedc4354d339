"""Error measures of a disparity map against ground truth: pure functions over arrays.

Every function takes the estimate ``disp`` (float, ``inf`` or NaN where the method gave no
disparity), the ground truth ``gt`` in pixels and a boolean ``mask`` of the pixels to
score (the caller leaves unknown ground truth out of it). How an invalid estimate counts:

- bad-x (Middlebury), D1 and out-x (KITTI): as a bad pixel;
- avgerr, rms and the error quantiles A50..A99: left out, as MiddEval3's ``evaldisp``
  does; ``invalid`` gives their share, so a sparse map cannot hide behind them.
"""

from __future__ import annotations

import numpy as np

#: Bad-pixel thresholds of the MiddEval3 tables.
MIDDLEBURY_THRESHOLDS = (0.5, 1.0, 2.0, 4.0)

#: Error quantiles of the MiddEval3 tables (A50 is the median error).
QUANTILES = (50, 90, 95, 99)


def bad_name(threshold: float) -> str:
    """The measure's name for a bad-pixel threshold: ``bad1.0``, ``bad0.5``."""
    return f"bad{threshold:.1f}"


def _errors(disp: np.ndarray, gt: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, int]:
    """Absolute errors of the valid estimates in ``mask``, and the count of mask pixels."""
    estimate = np.asarray(disp, dtype=np.float64)[mask]
    valid = np.isfinite(estimate)
    return np.abs(estimate[valid] - np.asarray(gt, dtype=np.float64)[mask][valid]), \
        int(mask.sum())


#: How close to a whole number a disparity's fraction must be to count as "integer".
INTEGER_TOLERANCE = 0.1


def integer_share(disp: np.ndarray, mask: np.ndarray) -> float:
    """Of the valid estimates in ``mask``, the share within :data:`INTEGER_TOLERANCE` of a
    whole number: 0.2 for an even spread of fractions (as ground truth has), more for a
    matcher that locks to pixels, whose clouds come out in layers."""
    values = np.asarray(disp, dtype=np.float64)[mask]
    values = values[np.isfinite(values)]
    if values.size == 0:
        return float("nan")
    distance = np.abs(values - np.round(values))
    return float(np.mean(distance <= INTEGER_TOLERANCE))


def bad_pixel_map(disp: np.ndarray, gt: np.ndarray, threshold: float) -> np.ndarray:
    """True where the estimate is off by more than ``threshold``; invalid estimates are bad."""
    with np.errstate(invalid="ignore"):
        good = np.abs(disp.astype(np.float64) - gt) <= threshold
    return ~good


def bad_percent(disp: np.ndarray, gt: np.ndarray, mask: np.ndarray,
                threshold: float = 1.0) -> float:
    """Percentage of ``mask`` pixels off by more than ``threshold`` pixels, or invalid."""
    count = int(mask.sum())
    if count == 0:
        return float("nan")
    return 100.0 * float(bad_pixel_map(disp, gt, threshold)[mask].sum()) / count


def middlebury_measures(disp: np.ndarray, gt: np.ndarray, mask: np.ndarray,
                        thresholds=MIDDLEBURY_THRESHOLDS) -> dict[str, float]:
    """MiddEval3's measures: bad-x for each threshold, invalid (%), avgerr, rms, A50..A99."""
    errors, count = _errors(disp, gt, mask)
    if count == 0:
        return {}
    out = {bad_name(t): bad_percent(disp, gt, mask, t) for t in thresholds}
    out["invalid"] = 100.0 * (count - errors.size) / count
    out["integer_share"] = integer_share(disp, mask)
    if errors.size:
        out["avgerr"] = float(errors.mean())
        out["rms"] = float(np.sqrt(np.mean(errors ** 2)))
        for q, value in zip(QUANTILES, np.percentile(errors, QUANTILES)):
            out[f"A{q}"] = float(value)
    return out


def d1_map(disp: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """KITTI 2015's outliers: error > 3 px and > 5 % of the true disparity, or invalid."""
    with np.errstate(invalid="ignore"):
        error = np.abs(disp.astype(np.float64) - gt)
        good = (error <= 3.0) | (error <= 0.05 * np.abs(gt))
    return ~good


def kitti_measures(disp: np.ndarray, gt: np.ndarray, mask: np.ndarray) -> dict[str, float]:
    """KITTI's measures: D1 (2015), out-2/3/4/5 (2012: error > x px), invalid, avgerr."""
    errors, count = _errors(disp, gt, mask)
    if count == 0:
        return {}
    out = {"D1": 100.0 * float(d1_map(disp, gt)[mask].sum()) / count}
    for t in (2, 3, 4, 5):
        out[f"out{t}"] = bad_percent(disp, gt, mask, float(t))
    out["invalid"] = 100.0 * (count - errors.size) / count
    out["bad0.5"] = bad_percent(disp, gt, mask, 0.5)
    out["integer_share"] = integer_share(disp, mask)
    if errors.size:
        out["avgerr"] = float(errors.mean())
    return out
