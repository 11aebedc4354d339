"""Row tiles: the blocks and stripes a stage works in, each with the margin of rows it
reads beyond the rows it keeps. Bookkeeping only: what a tile holds is the stage's."""

from __future__ import annotations

import math


def row_blocks(height: int, rows: int, margin: int, start: int = 0, stop: int | None = None):
    """``(top, bottom, y0, y1)`` of blocks of at most ``rows`` rows tiling ``start ..
    stop`` (default: the whole height), each with the ``margin`` rows on either side that
    the image has: ``y0 .. y1`` is read, ``top .. bottom`` kept."""
    stop = height if stop is None else stop
    for top in range(start, stop, rows):
        bottom = min(stop, top + rows)
        yield top, bottom, max(0, top - margin), min(height, bottom + margin)


def stripe_layout(height: int, rows: int, overlap: int) -> list[tuple[int, int, int, int]]:
    """``(first, stop, core_first, core_stop)`` row ranges of stripes of at most ``rows``
    rows: cores of equal height that tile the image, each with ``overlap`` rows more on
    either side where the image has them."""
    if height <= rows:
        return [(0, height, 0, height)]
    count = math.ceil(height / (rows - 2 * overlap))
    core = math.ceil(height / count)
    layout = []
    for i in range(count):
        core_first, core_stop = i * core, min(height, (i + 1) * core)
        layout.append((max(0, core_first - overlap), min(height, core_stop + overlap),
                       core_first, core_stop))
    return layout
