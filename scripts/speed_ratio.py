"""vsmatch's time against OpenCV SGBM (HH and 5-direction) on the twelve standard pairs,
robust to a busy machine.

For each pair (the middlebury2 scenes and the Middlebury 2014 quarter-size ones, official
ranges), runs each given config and SGBM's two modes one after the other for ``--rounds``
rounds and keeps each one's fastest time; prints the sums and the ratios. It is
``vsmatch bench``'s timing of the pairs alone (without SGBM 3-way, stages, start-up,
memory and the size series).

    python scripts/speed_ratio.py [--data-root DIR] [--rounds 5] [CONFIG ...]
"""

from __future__ import annotations

import argparse

from vsmatch.bench import standard_pairs, time_pairs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("configs", nargs="*", default=["fast", "default"])
    args = parser.parse_args()
    report = time_pairs(standard_pairs(args.data_root), args.configs, args.rounds,
                        peers=("sgbm-hh", "sgbm-5"))
    for name, total in report["total"].items():
        print(f"{name:<24}{total['seconds']:8.3f} s   {total['x_sgbm-hh']:5.2f} x SGBM HH"
              f"   {total['x_sgbm-5']:5.2f} x SGBM 5-direction")


if __name__ == "__main__":
    main()
