"""Thin structures: whether a config keeps a wire's width.

Synthetic wires (``vsmatch.synthetic.wires_pair``: vertical wires THICKNESS px wide every
40 px, 20 disparities in front of a textured wall) for each thickness and config: how
wide the wires are drawn (pixels within 1 of the wires' disparity, as a multiple of the
wires' own), the wall pixels drawn as wire (fattening) and how many of them are kept at
the config's ``cloud.min_confidence`` (confident and wrong: what a cloud would show), and
the wire pixels right and kept. ``--set section.key=value`` changes every config
(``--set bands.guide=null``: the bands centred on each pixel's own coarse estimate).

    python scripts/thin_structures.py [CONFIG ...] [--thickness 3 --thickness 5 ...]
        [--set section.key=value]
"""

from __future__ import annotations

import argparse

import numpy as np

from vsmatch import pipeline
from vsmatch.config import with_changes
from vsmatch.synthetic import wires_pair


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="*", default=["fast", "default", "accurate"])
    parser.add_argument("--thickness", type=int, action="append")
    parser.add_argument("--set", dest="changes", action="append", default=[],
                        metavar="section.key=value")
    args = parser.parse_args()
    print("px  config      drawn   wall as wire   of them kept   wire right   wire kept")
    for thickness in args.thickness or [2, 3, 5]:
        pair = wires_pair(thickness)
        wire = pair.disparity == pair.disparity.max()
        for name in args.configs:
            cfg = with_changes(name, args.changes)
            result = pipeline.run(pair.left, pair.right, max_disp=pair.max_disp, config=cfg)
            kept = result.confidence >= cfg.cloud.min_confidence
            as_wire = np.abs(result.disparity - pair.disparity.max()) <= 1
            fat = as_wire & ~wire
            print(f"{thickness:2d}  {name:10s} {as_wire.sum() / wire.sum():5.2f}x "
                  f"{fat.sum():10d} px {(fat & kept).sum():10d} px "
                  f"{100 * as_wire[wire].mean():9.1f} % {100 * kept[wire].mean():9.1f} %",
                  flush=True)


if __name__ == "__main__":
    main()
