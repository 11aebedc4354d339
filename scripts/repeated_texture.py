"""Repeated texture: whether a config trusts a match a period off.

Synthetic fins (``vsmatch.synthetic.fins_pair``: bright and dark stripes of PERIOD px in
front of a textured wall) for each period and config: the share of fin pixels matched
wrong (more than 1 px off), the share kept at the config's ``cloud.min_confidence``, the
share both (confident and wrong: what a cloud would show), and the share of the visible
wall kept. ``--without-cap`` leaves out the confidence's repeated-texture cap, to see
what it does.

    python scripts/repeated_texture.py [CONFIG ...] [--period 5 --period 8 ...]
        [--without-cap]
"""

from __future__ import annotations

import argparse

import numpy as np

from vsmatch import confidence, pipeline
from vsmatch.config import load_config
from vsmatch.synthetic import fins_pair


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="*", default=["fast", "default", "accurate"])
    parser.add_argument("--period", type=int, action="append")
    parser.add_argument("--without-cap", action="store_true")
    args = parser.parse_args()
    if args.without_cap:
        confidence.cap_repeated = lambda conf, repeated: None
    print("period  config      fins wrong   kept   confident and wrong   wall kept")
    for period in args.period or [5, 8, 12, 16]:
        pair = fins_pair(period)
        fins = pair.disparity == pair.disparity.max()
        wall = ~fins & pair.nonocc
        for name in args.configs:
            result = pipeline.run(pair.left, pair.right, max_disp=pair.max_disp, config=name)
            kept = result.confidence >= load_config(name).cloud.min_confidence
            wrong = ~(np.abs(result.disparity - pair.disparity) <= 1)
            print(f"{period:6d}  {name:10s} {100 * wrong[fins].mean():9.1f} % "
                  f"{100 * kept[fins].mean():5.1f} % {100 * (kept & wrong)[fins].mean():17.1f} %"
                  f" {100 * kept[wall].mean():9.1f} %", flush=True)


if __name__ == "__main__":
    main()
