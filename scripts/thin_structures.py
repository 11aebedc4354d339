"""Thin structures: whether a config keeps a wire's width.

Synthetic wires (``vsmatch.synthetic.wires_pair``: vertical wires THICKNESS px wide every
40 px, 20 disparities in front of a textured wall) for each thickness and config: how
wide the wires are drawn (pixels within 1 of the wires' disparity, as a multiple of the
wires' own), the wall pixels drawn as wire (fattening) and how many of them are kept at
the config's ``cloud.min_confidence`` (confident and wrong: what a cloud would show), and
the wire pixels right and kept. ``--set section.key=value`` changes every config
(``--set bands.guide=null``: the bands centred on each pixel's own coarse estimate).
``--fence``: a chain-link fence instead (``vsmatch.synthetic.fence_pair``: diagonal wires
crossing, diamond holes ``--spacing`` px wide along the rows, 32 unless told), and
``--wall-contrast`` its wall's texture; the wall's pixels matched right are printed too.
``sgbm-5``, ``sgbm-hh``: OpenCV's StereoSGBM (block size 3, as ``vsmatch bench``), all its
valid pixels counted as kept.

    python scripts/thin_structures.py [CONFIG ...] [--thickness 3 --thickness 5 ...]
        [--set section.key=value] [--fence [--spacing 32] [--wall-contrast 30]]
"""

from __future__ import annotations

import argparse

import cv2
import numpy as np

from vsmatch import pipeline
from vsmatch.config import with_changes
from vsmatch.disparity import INVALID_DISPARITY
from vsmatch.peers import sgbm_matcher
from vsmatch.synthetic import fence_pair, wires_pair

SGBM_MODES = {"sgbm-5": cv2.STEREO_SGBM_MODE_SGBM, "sgbm-hh": cv2.STEREO_SGBM_MODE_HH}


def matched(pair, name: str, changes: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """The disparity of ``pair`` by config ``name`` (or an SGBM mode) and the pixels kept."""
    if name in SGBM_MODES:
        raw = sgbm_matcher(pair.max_disp, 1, mode=SGBM_MODES[name]).compute(pair.left,
                                                                          pair.right)
        disparity = np.where(raw >= 0, raw / np.float32(16), INVALID_DISPARITY)
        return disparity, raw >= 0
    cfg = with_changes(name, changes)
    result = pipeline.run(pair.left, pair.right, max_disp=pair.max_disp, config=cfg)
    return result.disparity, result.confidence >= cfg.cloud.min_confidence


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="*", default=["fast", "default", "accurate"])
    parser.add_argument("--thickness", type=int, action="append")
    parser.add_argument("--set", dest="changes", action="append", default=[],
                        metavar="section.key=value")
    parser.add_argument("--fence", action="store_true")
    parser.add_argument("--spacing", type=int, default=32)
    parser.add_argument("--wall-contrast", type=float, default=30.0)
    args = parser.parse_args()
    print("px  config      drawn   wall as wire   of them kept   wire right   wire kept"
          + ("   wall right" if args.fence else ""))
    for thickness in args.thickness or ([2, 3] if args.fence else [2, 3, 5]):
        pair = (fence_pair(thickness, args.spacing, wall_contrast=args.wall_contrast)
                if args.fence
                else wires_pair(thickness))
        wire = pair.disparity == pair.disparity.max()
        wall = pair.nonocc & ~wire
        for name in args.configs:
            disparity, kept = matched(pair, name, args.changes)
            as_wire = np.abs(disparity - pair.disparity.max()) <= 1
            fat = as_wire & ~wire
            line = (f"{thickness:2d}  {name:10s} {as_wire.sum() / wire.sum():5.2f}x "
                    f"{fat.sum():10d} px {(fat & kept).sum():10d} px "
                    f"{100 * as_wire[wire].mean():9.1f} % {100 * kept[wire].mean():9.1f} %")
            if args.fence:
                right = np.abs(disparity - pair.disparity.min()) <= 1
                line += f" {100 * right[wall].mean():10.1f} %"
            print(line, flush=True)


if __name__ == "__main__":
    main()
