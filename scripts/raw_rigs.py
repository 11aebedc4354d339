"""Raw rigs made from the Middlebury 2014 quarter-size scenes (each camera turned about 1
degree, k1 = -0.12; exactly as tests/test_rig.py makes them): the cloud of `vsmatch run
--calib stereo.yaml` on the raw views, brought back to the scene's frame, against the
cloud of the rectified original: points more than 3 % off in depth, and points kept.

    python scripts/raw_rigs.py [--data-root DIR] [SCENE ...]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
from click.testing import CliRunner
from plyfile import PlyData

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from test_rig import R_LEFT, cloud_errors, raw_views, write_opencv  # noqa: E402

from vsmatch import datasets, geometry, rig  # noqa: E402
from vsmatch.cli import main as cli  # noqa: E402

SCENES = ("Adirondack", "ArtL", "Jadeplant", "Motorcycle", "Piano", "Teddy")


def points(path: Path) -> np.ndarray:
    vertex = PlyData.read(str(path))["vertex"]
    return np.stack([np.asarray(vertex[a], np.float64) for a in "xyz"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("scenes", nargs="*", default=list(SCENES))
    args = parser.parse_args()
    folder = datasets.dataset_folder("middlebury2014-quarter", args.data_root)
    print("scene: points > 3 % off, original / raw rig; points, raw rig / original")
    for name in args.scenes:
        found = datasets.load_dataset("middlebury2014-quarter", args.data_root,
                                      names=[name])[0]
        calib = geometry.read_calibration(folder / name / "calib.txt")
        (left, right), m = raw_views(found, calib)
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            for file, view in (("raw_l.png", left), ("raw_r.png", right),
                               ("im0.png", found.left), ("im1.png", found.right)):
                cv2.imwrite(str(tmp / file), view)
            write_opencv(tmp / "stereo.yaml", m)
            (tmp / "calib.txt").write_text(rig.middlebury_calib_text(
                calib, m["size"], (0, found.max_disp)))
            for args_ in (["im0.png", "im1.png", "--calib", "calib.txt", "--cloud", "o.ply"],
                          ["raw_l.png", "raw_r.png", "--calib", "stereo.yaml", "--cloud",
                           "r.ply"]):
                paths = [str(tmp / a) if a.endswith((".png", ".ply", ".txt", ".yaml"))
                         else a for a in args_]
                done = CliRunner().invoke(cli, ["run", *paths, "-o", str(tmp / "d.pfm")])
                if done.exit_code != 0:
                    raise SystemExit(done.output)
            rectifier = rig.Rectifier(rig.read_rig([tmp / "stereo.yaml"]), m["size"])
            back = R_LEFT.T @ rectifier.rotations[0].T
            wrong_raw, count_raw = cloud_errors(back @ points(tmp / "r.ply"), calib,
                                                found.ground_truth)
            wrong, count = cloud_errors(points(tmp / "o.ply"), calib, found.ground_truth)
        print(f"{name}: {100 * wrong:.1f} % / {100 * wrong_raw:.1f} %; "
              f"{count_raw / count:.2f}", flush=True)


if __name__ == "__main__":
    main()
