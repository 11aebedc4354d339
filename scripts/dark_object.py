"""A dark object in a bright scene: whether a config takes it for a blank surface.

The lower half of each scene's left quarter is put in deep shadow: its grey levels scaled
by ``--gain`` in the left view, and the same scene points (by the ground truth) in the right
view, then both views given sensor noise of ``--sigma`` grey levels. A step that judges
texture against a level of the whole view (blank segments, long-armed regions) sees the
shadowed part as blank and fills it from around. Prints, per scene and config, the headline
error (bad 3.0 on KITTI, bad 2.0 elsewhere) over the shadowed region's pixels with ground
truth.

    python scripts/dark_object.py CONFIG [CONFIG ...] [--gain 0.12] [--sigma 1]
        [--set section.key=value] [--data-root DIR]
"""

from __future__ import annotations

import argparse

from vsmatch import datasets, metrics, pipeline
from vsmatch.config import with_changes
from vsmatch.synthetic import shadowed

SCENES = (("kitti2015", ["000000", "000001", "000046"]),
          ("middlebury2014-quarter", ["Adirondack", "Motorcycle", "Piano"]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="+")
    parser.add_argument("--gain", type=float, default=0.12)
    parser.add_argument("--sigma", type=float, default=1.0)
    parser.add_argument("--set", dest="changes", action="append", default=[],
                        metavar="section.key=value", help="applied to every config")
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    methods = {name: with_changes(name, args.changes) for name in args.configs}
    for dataset, names in SCENES:
        threshold = 3.0 if dataset.startswith("kitti") else 2.0
        for scene in datasets.load_dataset(dataset, args.data_root, names=names):
            left, right, region = shadowed(scene.left, scene.right, scene.ground_truth,
                                           args.gain, args.sigma)
            known = scene.masks.get("nonocc", scene.masks["all"]) & region
            figures = []
            for name, cfg in methods.items():
                result = pipeline.run(left, right, max_disp=scene.max_disp, config=cfg)
                bad = metrics.bad_percent(result.disparity, scene.ground_truth, known, threshold)
                figures.append(f"{name} {bad:.2f}")
            print(f"{scene.name:12s} " + "  ".join(figures), flush=True)


if __name__ == "__main__":
    main()
