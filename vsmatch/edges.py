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
from ._kernels.rows import thread_classes
from .config import EdgesConfig
from .images import as_channels, grey_levels
from .sensitivity import sobel, texture
from .tiles import row_blocks

#: The Sobel x-derivative of a grey ramp of one grey level a pixel.
SOBEL_GAIN = 8.0
#: Rows weighed at a time: the gradients and the texture are made for a block and the rows
#: around it its windows read (``edges.radius``, and :data:`FILTER_REACH` more for the
#: filters behind them), so the memory is bounded whatever the image's height. Blocks give
#: the same bytes as one piece (a test).
EDGE_ROWS = 512
#: Rows beyond a window's that its values depend on: the Sobel's one and the texture's
#: 5 x 5 mean's two.
FILTER_REACH = 3


def weigh_edges(disp: np.ndarray, confidence: np.ndarray, left: np.ndarray,
                right: np.ndarray, cfg: EdgesConfig) -> tuple[np.ndarray, np.ndarray]:
    """``disp`` with each pixel near a step back along its row given the disparity behind
    the step where that explains the views better, and ``confidence`` with a moved
    pixel's at most ``cfg.moved_confidence`` (float32, new arrays)."""
    disp = np.ascontiguousarray(disp, dtype=np.float32)
    out = np.empty_like(disp)
    for top, bottom, y0, y1 in row_blocks(disp.shape[0], EDGE_ROWS, cfg.radius + FILTER_REACH):
        rows = slice(y0, y1)
        out[top:bottom] = _weigh_block(disp[rows], left[rows], right[rows],
                                       cfg)[top - y0:bottom - y0]
    moved = np.isfinite(disp) & (out != disp)
    confidence = confidence.astype(np.float32)  # a copy
    np.minimum(confidence, np.float32(cfg.moved_confidence), out=confidence, where=moved)
    return out, confidence


def _weigh_block(disp: np.ndarray, left: np.ndarray, right: np.ndarray,
                 cfg: EdgesConfig) -> np.ndarray:
    """:func:`weigh_edges`' disparities for rows of the views."""
    grey_l, grey_r = grey_levels(left), grey_levels(right)
    grad_l = np.ascontiguousarray(sobel(grey_l)[0] / np.float32(SOBEL_GAIN))
    grad_r = np.ascontiguousarray(sobel(grey_r)[0] / np.float32(SOBEL_GAIN))
    skip = np.ascontiguousarray(texture(grey_l) < cfg.min_texture)
    out = np.empty_like(disp)
    weigh_edge_sides(np.ascontiguousarray(disp), _planes(left), _padded(_planes(right)),
                     grad_l, _padded(grad_r), skip, cfg.radius, cfg.colour_scale,
                     cfg.distance_scale, cfg.gradient_share, cfg.colour_cap, cfg.gradient_cap,
                     cfg.reach, cfg.jump, cfg.margin, thread_classes(), out)
    return out


def _planes(view: np.ndarray) -> np.ndarray:
    """``view``'s channels as (C, H, W) uint8 planes: a window row's pixels of one channel
    lie side by side."""
    return np.ascontiguousarray(np.moveaxis(as_channels(view), 2, 0))


def _padded(values: np.ndarray) -> np.ndarray:
    """``values`` with their last column repeated once more (C-contiguous): a match at the
    last column reads its right neighbour (weighed 0) inside the array."""
    return np.concatenate([values, values[..., -1:]], axis=-1)
