"""The EuRoC clip (48 raw frames of a drone, ../shared/data/real-cameras/euroc-clip) laid out
as EuRoC ships it (``mav0/cam0/data/*.png``, ``data.csv``, ``sensor.yaml``; a temporary
copy) and read as ``vsmatch video mav0/cam0 mav0/cam1`` reads it, through
``vsmatch.StereoMatcher`` with the two sensor.yaml found there: frames per second with and
without the temporal mode beside SGBM on the same rectified frames, and a picture of frames
side by side (left view above, the video's frame below: pixels under the cloud's threshold
dimmed, a colour bar in depth, metres).

    python scripts/euroc_clip.py [--data-root D] [--config fast] [--picture clip.png]
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vsmatch import geometry, io, preview  # noqa: E402
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
    with tempfile.TemporaryDirectory() as folder:
        mav0 = as_shipped(clip, Path(folder))
        pairs = FolderPairs(str(mav0 / "cam0"), str(mav0 / "cam1"))
        calib = pairs.sensor_files()
        frames = list(pairs)
        measure(frames, calib, args)


def as_shipped(clip: Path, to: Path) -> Path:
    """The clip's flattened cam0/ and cam1/ as EuRoC ships a camera: ``mav0/camN/data/``
    (frames named by time stamp), ``data.csv`` (the index) and ``sensor.yaml``."""
    for camera in ("cam0", "cam1"):
        folder = to / "mav0" / camera
        (folder / "data").mkdir(parents=True)
        shutil.copy(clip / camera / "sensor.yaml", folder / "sensor.yaml")
        lines = ["#timestamp [ns],filename"]
        for frame in sorted((clip / camera).glob("*.png")):
            shutil.copy(frame, folder / "data" / frame.name)
            lines.append(f"{frame.stem},{frame.name}")
        (folder / "data.csv").write_text("\n".join(lines) + "\n")
    return to / "mav0"


def measure(frames, calib, args) -> None:
    runs = {}
    for temporal in (False, True):
        matcher = StereoMatcher(config=args.config, calib=calib, temporal=temporal)
        matcher.compute(*frames[0])  # compiles, finds the range
        matcher = StereoMatcher(config=args.config, calib=calib, temporal=temporal)
        out, seconds, confidences = [], [], []
        for left, right in frames:
            start = time.perf_counter()
            result = matcher.result(left, right)
            seconds.append(time.perf_counter() - start)
            out.append(result.disparity)
            confidences.append(result.confidence)
        runs[temporal] = (matcher, out, seconds, confidences)
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
    for temporal, (_, out, seconds, _) in runs.items():
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
        camera, threshold = matcher.camera, matcher.config.cloud.min_confidence
        disps = [preview.video_frame(runs[True][1][k], runs[True][3][k], threshold, low, high,
                                     geometry.depth_of(camera)) for k in shown]
        width = disps[0].shape[1]
        views = [cv2.copyMakeBorder(v, 0, 0, 0, width - v.shape[1], cv2.BORDER_CONSTANT,
                                    value=(255, 255, 255)) for v in views]
        picture = np.vstack([np.hstack(views), np.hstack(disps)])
        scale = min(1.0, 1600 / picture.shape[1])
        picture = cv2.resize(picture, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        io.imwrite_atomic(args.picture, picture)
        print(f"wrote {args.picture} (frames {', '.join(str(k) for k in shown)})")


if __name__ == "__main__":
    main()
