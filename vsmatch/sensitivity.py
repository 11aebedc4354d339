"""Visual sensitivity: Sobel gradient magnitude G and direction theta (paper eq. 1-3, 6)."""

from __future__ import annotations

import cv2
import numpy as np

from ._kernels.sobel import gradient_magnitude


def presmooth(image: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian blur of a view before all stages (same dtype); sigma 0 leaves it as is."""
    if sigma <= 0:
        return image
    return cv2.GaussianBlur(image, (0, 0), sigmaX=sigma, sigmaY=sigma,
                            borderType=cv2.BORDER_REFLECT_101)


def visual_sensitivity(grey: np.ndarray, direction: bool = True
                       ) -> tuple[np.ndarray, np.ndarray | None]:
    """Return ``(G, theta)``, both float32 (H, W).

    ``G = sqrt(Gx^2 + Gy^2)`` with the 3x3 Sobel templates, and ``theta = atan2(Gy, Gx)``,
    the direction of fastest grey change (atan2 keeps the quadrant). ``direction=False``
    gives None for theta: only direction-guided arms (``arms.kappa`` != 0) read it, and
    atan2 costs ten times the rest.
    """
    grey = np.ascontiguousarray(grey, dtype=np.float32)
    if not direction:
        # The magnitude alone in one pass (two cv2.Sobel filters and NumPy's passes took
        # five): on grey levels, whole numbers, the same values.
        magnitude = np.empty_like(grey)
        gradient_magnitude(grey, magnitude)
        return magnitude, None
    gx, gy = sobel(grey)
    return np.sqrt(gx * gx + gy * gy), np.arctan2(gy, gx).astype(np.float32)


#: The square (pixels) :func:`texture` averages the gradient over.
TEXTURE_WINDOW = 5


def texture(grey: np.ndarray) -> np.ndarray:
    """How much the image varies about each pixel: |gx| + |gy| of the Sobel derivatives,
    averaged over a :data:`TEXTURE_WINDOW` square (float32; 8 for a gradient of one grey
    level a pixel)."""
    gx, gy = sobel(grey)
    return cv2.blur(np.abs(gx) + np.abs(gy), (TEXTURE_WINDOW, TEXTURE_WINDOW))


def sobel(grey: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 3 x 3 Sobel derivatives along x and y (float32; borders mirrored)."""
    gx = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3, borderType=cv2.BORDER_REFLECT_101)
    gy = cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3, borderType=cv2.BORDER_REFLECT_101)
    return gx, gy
