"""Depth edges decided again, pixel by pixel, by adaptive support weights.

Cross-based aggregation and the census window both reach a few pixels past a depth edge,
so a surface in front spills its disparity 1-3 px onto the one behind it, and the spilt
pixels pass the left-right check (both views spill alike). Here each pixel within
``edges.reach`` px of a step along its row to a disparity more than ``edges.jump`` px
behind it weighs that disparity against its own, over a window whose pixels count by how
like the centre their colour is (Yoon and Kweon's adaptive support weights, as PatchMatch
Stereo uses them): the pixels of the surface behind, whatever colour the one in front
has, decide. The cost is the colour and x-gradient difference (truncated) against the
right view as matched (after any exposure correction). Only steps back are weighed: a
pixel is moved onto the surface behind it, never onto one in front; and only where the
view has texture (a blank wall's window tells nothing).
"""

from __future__ import annotations

import numpy as np

from ._kernels.edges import weigh_edge_sides
from .config import EdgesConfig
from .images import as_channels, grey_levels
from .sensitivity import sobel, texture

#: The Sobel x-derivative of a grey ramp of one grey level a pixel.
SOBEL_GAIN = 8.0


def weigh_edges(disp: np.ndarray, confidence: np.ndarray, left: np.ndarray,
                right: np.ndarray, cfg: EdgesConfig) -> tuple[np.ndarray, np.ndarray]:
    """``disp`` with each pixel near a step back along its row given the disparity behind
    the step where that explains the views better, and ``confidence`` with a moved
    pixel's at most ``cfg.moved_confidence`` (float32, new arrays)."""
    disp = np.ascontiguousarray(disp, dtype=np.float32)
    grey_l, grey_r = grey_levels(left), grey_levels(right)
    grad_l = np.ascontiguousarray(sobel(grey_l)[0] / np.float32(SOBEL_GAIN))
    grad_r = np.ascontiguousarray(sobel(grey_r)[0] / np.float32(SOBEL_GAIN))
    skip = np.ascontiguousarray(texture(grey_l) < cfg.min_texture)
    out = np.empty_like(disp)
    weigh_edge_sides(disp, as_channels(left), as_channels(right), grad_l, grad_r, skip,
                     cfg.radius, cfg.colour_scale, cfg.distance_scale, cfg.gradient_share,
                     cfg.colour_cap, cfg.gradient_cap, cfg.reach, cfg.jump, cfg.margin, out)
    moved = np.isfinite(disp) & (out != disp)
    confidence = np.where(moved, np.minimum(confidence, np.float32(cfg.moved_confidence)),
                          confidence).astype(np.float32)
    return out, confidence
