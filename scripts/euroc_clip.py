"""The EuRoC clip (48 raw frames of a drone, ../shared/data/real-cameras/euroc-clip) through
``vsmatch.StereoMatcher`` with its sensor.yaml pair, as ``vsmatch video cam0/ cam1/`` runs it:
frames per second with and without the temporal mode beside SGBM on the same rectified
frames, and a picture of frames side by side (left view above, disparity below).

    python scripts/euroc_clip.py [--data-root D] [--config fast] [--picture docs/euroc_clip.png]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vsmatch import io, preview  # noqa: E402
from vsmatch.frames import FolderPairs  # noqa: E402
from vsmatch.matcher import StereoMatcher  # noqa: E402
from vsmatch.peers import sgbm_matcher  # noqa: E402

SHOWN = 4  # frames in the picture, spread over the clip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-root", default="../shared/data")
    parser.add_argument("--config", default="fast")
    parser.add_argument("--picture", default=None)
    args = parser.parse_args()
    clip = Path(args.data_root) / "real-cameras" / "euroc-clip"
    calib = [str(clip / "cam0" / "sensor.yaml"), str(clip / "cam1" / "sensor.yaml")]
    frames = list(FolderPairs(str(clip / "cam0"), str(clip / "cam1")))
    runs = {}
    for temporal in (False, True):
        matcher = StereoMatcher(config=args.config, calib=calib, temporal=temporal)
        matcher.compute(*frames[0])  # compiles, finds the range
        matcher = StereoMatcher(config=args.config, calib=calib, temporal=temporal)
        out, seconds = [], []
        for left, right in frames:
            start = time.perf_counter()
            out.append(matcher.compute(left, right))
            seconds.append(time.perf_counter() - start)
        runs[temporal] = (matcher, out, seconds)
    matcher = runs[True][0]
    low, high = matcher.range
    rectified = [matcher.rectify(left, right) for left, right in frames]
    sgbm = {}
    for name, mode in (("SGBM HH", cv2.STEREO_SGBM_MODE_HH),
                       ("SGBM 5-direction", cv2.STEREO_SGBM_MODE_SGBM)):
        stereo = sgbm_matcher(high, min_disp=low, mode=mode)
        seconds = []
        for left, right in rectified:
            start = time.perf_counter()
            stereo.compute(left, right)
            seconds.append(time.perf_counter() - start)
        sgbm[name] = seconds
    size = rectified[0][0].shape[1::-1]
    print(f"EuRoC clip: {len(frames)} frames of {size[0]}x{size[1]}, disparities {low}..{high}, "
          f"config {args.config}; frames per second after the first:")
    for temporal, (_, out, seconds) in runs.items():
        changes = [np.abs(b - a)[np.isfinite(a) & np.isfinite(b)] for a, b in zip(out, out[1:])]
        moving = 100 * np.mean([np.mean(c > 1) for c in changes])
        label = "temporal" if temporal else "per frame"
        print(f"  vsmatch {label:10s} {1 / np.mean(seconds[1:]):5.1f} fps, pixels moving by "
              f"more than 1 px between frames {moving:4.1f} %")
    for name, seconds in sgbm.items():
        print(f"  {name:18s} {1 / np.mean(seconds[1:]):5.1f} fps")
    if args.picture:
        shown = np.linspace(0, len(frames) - 1, SHOWN).round().astype(int)
        views = [cv2.cvtColor(rectified[k][0], cv2.COLOR_GRAY2BGR)
                 if rectified[k][0].ndim == 2 else rectified[k][0] for k in shown]
        disps = [preview.colour_disparity(runs[True][1][k], high, low) for k in shown]
        picture = np.vstack([np.hstack(views), np.hstack(disps)])
        scale = min(1.0, 1600 / picture.shape[1])
        picture = cv2.resize(picture, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        io.imwrite_atomic(args.picture, picture)
        print(f"wrote {args.picture} (frames {', '.join(str(k) for k in shown)})")


if __name__ == "__main__":
    main()
