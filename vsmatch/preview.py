"""Pictures of disparities: the colour map, error images, and ``--preview``, the
disparity as a picture a person reads at a glance.

The colours span the disparities present (not the whole search range, which would
squeeze a scene of 0..130 into part of a 0..173 scale); a colour bar beside the image
gives their values; pixels the confidence rejects are dimmed and hatched, so what to
trust stands out; invalid pixels are black.
"""

from __future__ import annotations

import cv2
import numpy as np

#: Share of the valid disparities left out at each end when the colour scale is chosen,
#: so that a few stray pixels do not stretch it.
OUTLIER_SHARE = 0.5  # percent
#: Brightness kept by a rejected pixel, and the spacing of the hatching over it.
DIMMED = 0.35
HATCH_SPACING = 6
#: Width of the colour bar and of the gap and labels beside it, in pixels.
BAR_WIDTH = 14
LABEL_WIDTH = 52


def colour_disparity(disp: np.ndarray, max_disp: float, min_disp: float = 0) -> np.ndarray:
    """A colour-mapped view (BGR uint8) of a disparity map over ``min_disp .. max_disp``;
    invalid pixels black."""
    valid = np.isfinite(disp)
    scaled = np.zeros(disp.shape, dtype=np.uint8)
    scale = 255.0 / max(max_disp - min_disp, 1e-6)
    scaled[valid] = np.clip((disp[valid] - min_disp) * scale, 0, 255).astype(np.uint8)
    out = cv2.applyColorMap(scaled, cv2.COLORMAP_TURBO)
    out[~valid] = 0
    return out


def error_image(disp: np.ndarray, bad: np.ndarray, evaluated: np.ndarray,
                max_disp: float) -> np.ndarray:
    """The disparity in grey with bad pixels red and pixels not evaluated darkened."""
    valid = np.isfinite(disp)
    grey = np.zeros(disp.shape, dtype=np.uint8)
    grey[valid] = np.clip(disp[valid] * (255.0 / max(max_disp, 1e-6)), 0, 255).astype(np.uint8)
    out = cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)
    out[~evaluated] //= 3
    out[bad & evaluated] = (0, 0, 255)
    return out


def colour_range(disp: np.ndarray, trusted: np.ndarray) -> tuple[float, float]:
    """The disparities the colours span: those of the trusted pixels (of every valid
    pixel when none is trusted), without the outermost OUTLIER_SHARE at each end."""
    values = disp[trusted & np.isfinite(disp)]
    if values.size == 0:
        values = disp[np.isfinite(disp)]
    if values.size == 0:
        return 0.0, 1.0
    low, high = np.percentile(values, [OUTLIER_SHARE, 100 - OUTLIER_SHARE])
    return float(low), float(max(high, low + 1e-3))


def disparity_preview(disp: np.ndarray, confidence: np.ndarray | None,
                      min_confidence: float) -> np.ndarray:
    """A BGR picture of ``disp``: colours over the disparities present, pixels whose
    confidence is below ``min_confidence`` dimmed and hatched, a colour bar on the
    right with its values."""
    trusted = _trusted(disp, confidence, min_confidence)
    low, high = colour_range(disp, trusted)
    return np.hstack([_shaded(disp, trusted, low, high),
                      colour_bar(disp.shape[0], low, high)])


def video_frame(disp: np.ndarray, confidence: np.ndarray | None, min_confidence: float,
                low: float, high: float, depth_of=None) -> np.ndarray:
    """A frame of the disparity video: as :func:`disparity_preview`, but its colours over
    the searched range ``low .. high`` (the same in every frame, so that a colour keeps
    its depth), and the bar's values depths by ``depth_of`` (disparity -> depth) when
    given."""
    trusted = _trusted(disp, confidence, min_confidence)
    return np.hstack([_shaded(disp, trusted, low, high),
                      colour_bar(disp.shape[0], low, high, depth_of)])


def _trusted(disp: np.ndarray, confidence: np.ndarray | None, min_confidence: float
             ) -> np.ndarray:
    valid = np.isfinite(disp)
    return valid if confidence is None else valid & (confidence >= min_confidence)


def _shaded(disp: np.ndarray, trusted: np.ndarray, low: float, high: float) -> np.ndarray:
    """``disp`` in colours over ``low .. high``; untrusted pixels dimmed and hatched,
    invalid ones black."""
    valid = np.isfinite(disp)
    scaled = np.zeros(disp.shape, np.uint8)
    scaled[valid] = np.clip((disp[valid] - low) * (255.0 / max(high - low, 1e-6)), 0, 255)
    picture = cv2.applyColorMap(scaled, cv2.COLORMAP_TURBO)
    rejected = valid & ~trusted
    ys, xs = np.nonzero(rejected)
    hatch = ((xs + ys) % HATCH_SPACING) == 0
    picture[ys, xs] = (picture[ys, xs] * DIMMED).astype(np.uint8)
    picture[ys[hatch], xs[hatch]] = 160
    picture[~valid] = 0
    return picture


def colour_bar(height: int, low: float, high: float, depth_of=None) -> np.ndarray:
    """A vertical bar, ``high`` at the top, with about five labelled values (the depths
    of those disparities by ``depth_of``, when given)."""
    panel = np.full((height, BAR_WIDTH + LABEL_WIDTH + 6, 3), 255, np.uint8)
    ramp = np.linspace(255, 0, height).astype(np.uint8)[:, None]
    panel[:, 4:4 + BAR_WIDTH] = cv2.applyColorMap(np.repeat(ramp, BAR_WIDTH, 1),
                                                  cv2.COLORMAP_TURBO)
    scale = max(0.3, min(0.45, height / 600))
    ticks = max(2, min(6, height // 40))
    for k in range(ticks):
        y = round(k * (height - 1) / (ticks - 1))
        value = high - k * (high - low) / (ticks - 1)
        text = f"{value:.1f}" if high - low < 20 else f"{value:.0f}"
        if depth_of is not None:
            depth = depth_of(value)
            text = f"{depth:.3g}" if np.isfinite(depth) and depth > 0 else "far"
        baseline_y = min(max(y + 4, 10), height - 2)
        cv2.line(panel, (4 + BAR_WIDTH, y), (8 + BAR_WIDTH, y), (0, 0, 0), 1)
        cv2.putText(panel, text, (10 + BAR_WIDTH, baseline_y), cv2.FONT_HERSHEY_SIMPLEX,
                    scale, (0, 0, 0), 1, cv2.LINE_AA)
    return panel
