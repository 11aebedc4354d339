"""The README's picture of the confidence: docs/confidence.jpg.

For a few scenes of different kinds (Middlebury 2014 quarter Adirondack and PianoL, a
KITTI 2015 frame): the left view, vsmatch's disparity (default config), its confidence, and
which errors the default threshold of --depth and --cloud flags.

    python scripts/confidence_figure.py [--data-root DIR] [--out docs/confidence.jpg]
"""

from __future__ import annotations

import argparse

from vsmatch import datasets, evaluation, io, pipeline
from vsmatch.config import load_config
from vsmatch.figure import confidence_figure

SCENES = (("middlebury2014-quarter", "Adirondack"), ("middlebury2014-quarter", "PianoL"),
          ("kitti2015", "000000"))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--out", default="docs/confidence.jpg")
    args = parser.parse_args()
    rows = []
    for dataset, name in SCENES:
        scene = datasets.load_dataset(dataset, args.data_root, names=[name])[0]
        result = pipeline.run(scene.left, scene.right, max_disp=scene.max_disp)
        scoring = evaluation.scoring_for(dataset)
        rows.append(confidence_figure([scene], {name: result}, scoring,
                                      load_config().cloud.min_confidence))
    width = max(r.shape[1] for r in rows)
    import numpy as np

    padded = [np.pad(r, ((0, 0), (0, width - r.shape[1]), (0, 0)), constant_values=255)
              for r in rows]
    io.imwrite_atomic(args.out, np.vstack(padded))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
