"""The prototype of ``cost.census_like`` (now in the method as ``--hamming least --colour``),
kept to try its variants: the census counted only over the window's neighbours like the
centre, run through another script (docs/results.md, "A chain-link fence"). The volume it
changes is the plain census's (``cost.census_like`` set to 0 under it).

A neighbour whose grey level differs from the centre's by more than ``--threshold`` is left
out of the left pixel's Hamming distance, which is then scaled back to the whole window
(``--hamming scaled``), counted as it is (``raw``) or given a quarter of the left-out bits as
differing (``prior``), or the smaller of the scaled and the plain distance (``least``: a
blank pixel's like neighbours are noise, and it keeps the edge the plain census sees), or the
plain distance with the unlike neighbours' differing bits counted at most at chance, half of
them (``capped``).
``--both``: the right pixel's mask too; ``--colour``: like in every channel.
``--like-contrast C``: no mask where the like neighbours differ from the centre by less than
C grey levels on average. ``--min-like F``: no mask where fewer than F of the neighbours are
like (a thin thing in the window, not an edge across it).
Full-range cost volumes only (the band search's are as they are), in NumPy: slow, but the
same volume otherwise (with ``--threshold 0`` the figures are those of the plain census).

    python scripts/masked_census.py --threshold 40 scripts/datasets_table.py default
    python scripts/masked_census.py --threshold 40 scripts/thin_structures.py default \\
        --fence --spacing 45 --thickness 3
"""

from __future__ import annotations

import argparse
import dataclasses
import runpy
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vsmatch import cost  # noqa: E402
from vsmatch.images import to_grey  # noqa: E402


def like_neighbours(view: np.ndarray, width: int, height: int, threshold: float,
                    like_contrast: float) -> np.ndarray:
    """Each pixel's mask of the census bits (the census's bit order) whose neighbour lies
    within ``threshold`` grey levels of it (of each channel's, for a colour ``view`` (H, W,
    C)); every bit where the like neighbours differ from it by less than ``like_contrast``
    on average."""
    view = np.ascontiguousarray(view, dtype=np.float32)
    if view.ndim == 2:
        view = view[:, :, None]
    half_w, half_h = width // 2, height // 2
    padded = cv2.copyMakeBorder(view, half_h, half_h, half_w, half_w, cv2.BORDER_REPLICATE)
    if padded.ndim == 2:
        padded = padded[:, :, None]
    rows, cols = view.shape[:2]
    n_bits = width * height - 1
    mask = np.zeros((rows, cols), np.uint64)
    spread = np.zeros((rows, cols), np.float32)
    count = np.zeros((rows, cols), np.float32)
    k = 0
    for dy in range(height):
        for dx in range(width):
            if dy == half_h and dx == half_w:
                continue
            difference = np.abs(padded[dy:dy + rows, dx:dx + cols] - view).max(axis=2)
            like = difference <= threshold
            mask |= like.astype(np.uint64) << np.uint64(n_bits - 1 - k)
            spread += np.where(like, difference, 0)
            count += like
            k += 1
    if like_contrast > 0:
        mask[spread / np.maximum(count, 1) < like_contrast] = np.uint64((1 << n_bits) - 1)
    return mask


def masked_cost_volume(args: argparse.Namespace):
    """``cost.cost_volume`` with the census term counted over the like neighbours."""
    method = cost.cost_volume

    def cost_volume(colour_l, colour_r, census_l, census_r, grad_l, grad_r, *, n_disp, cfg,
                    bands=None, colour_weight=1.0):
        cfg = dataclasses.replace(cfg, census_like=0.0)  # the plain census's volume
        volume = method(colour_l, colour_r, census_l, census_r, grad_l, grad_r,
                        n_disp=n_disp, cfg=cfg, bands=bands, colour_weight=colour_weight)
        if args.threshold <= 0 or (bands is not None and not bands.is_full):
            return volume
        width, height = cfg.census_width, cfg.census_height
        n_bits = width * height - 1
        masks = [like_neighbours(view if args.colour else to_grey(view), width, height,
                                 args.threshold,
                                 args.like_contrast)
                 for view in ((colour_l, colour_r) if args.both else (colour_l,))]
        table = cost.rho(np.arange(n_bits + 1), cfg.lambda_census).astype(np.float32)
        cols = census_l.shape[1]
        for d in range(min(n_disp, cols)):
            differing = census_l[:, d:] ^ census_r[:, :cols - d]
            mask = masks[0][:, d:] if len(masks) == 1 else masks[0][:, d:] & masks[1][:, :cols - d]
            plain = np.bitwise_count(differing)
            kept = np.bitwise_count(mask).astype(np.float64)
            if args.min_like > 0:  # too few like neighbours: the plain distance
                mask = np.where(kept < args.min_like * n_bits, ~np.uint64(0), mask)
                kept = np.bitwise_count(mask & np.uint64((1 << n_bits) - 1)).astype(np.float64)
            counted = np.bitwise_count(differing & mask).astype(np.float64)
            scaled = np.where(kept > 0, counted * n_bits / np.maximum(kept, 1), plain)
            if args.hamming == "scaled":
                hamming = scaled
            elif args.hamming == "least":  # the plain distance where it is the smaller
                hamming = np.minimum(scaled, plain)
            elif args.hamming == "prior":
                hamming = counted + (n_bits - kept) * 0.25
            elif args.hamming == "capped":  # the unlike bits count at most at chance
                hamming = np.minimum(plain, counted + (n_bits - kept) * 0.5)
            else:
                hamming = counted
            masked = (1.0 - np.exp(-hamming / cfg.lambda_census)).astype(np.float32)
            volume[:, d:, d] += masked - table[plain]
        return volume

    return cost_volume


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threshold", type=float, required=True)
    parser.add_argument("--hamming", default="scaled",
                        choices=("scaled", "raw", "prior", "least", "capped"))
    parser.add_argument("--both", action="store_true")
    parser.add_argument("--colour", action="store_true",
                        help="like in every channel, not in grey")
    parser.add_argument("--like-contrast", type=float, default=0.0)
    parser.add_argument("--min-like", type=float, default=0.0,
                        help="the plain distance where fewer of the neighbours are like")
    parser.add_argument("script")
    parser.add_argument("arguments", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    cost.cost_volume = masked_cost_volume(args)
    sys.argv = [args.script] + args.arguments
    runpy.run_path(args.script, run_name="__main__")


if __name__ == "__main__":
    main()
