"""The README's picture of real scenes: docs/real_scenes.jpg.

A desk (its near top seen at a slant), a white wall behind a ukulele (a raw rig, rectified
first) and a road (a KITTI 2015 frame): the left view, OpenCV SGBM's disparity (HH, holes
black), vsmatch's (default config) and vsmatch accurate's on the same colour scale (its bar
on the right), and vsmatch's confidence (default; white = 1; what the cloud keeps, at or
above the config's cloud.min_confidence, outlined in green).

    python scripts/real_scenes_figure.py [--data-root DIR] [--out docs/real_scenes.jpg]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

import vsmatch
from vsmatch import datasets, preview, rig
from vsmatch.confidence import keep_confident
from vsmatch.peers import sgbm_matcher

#: Width of each tile in the picture.
TILE_WIDTH = 480


def pairs(root: Path):
    """(name, left, right, max_disp) of the three scenes."""
    desk = root / "real-cameras" / "desk"
    left, right = (cv2.imread(str(desk / f"{s}.png")) for s in ("left", "right"))
    yield "desk", left, right, None
    raw = root / "real-cameras" / "ukulele-raw"
    left, right = (cv2.imread(str(raw / f"{s}.png")) for s in ("left", "right"))
    rectifier = rig.Rectifier(rig.read_rig([raw / "rig.yml"]), left.shape[1::-1])
    yield ("white wall", *rectifier.rectify(left, right), None)
    [road] = datasets.load_dataset("kitti2015", root, names=["000000"])
    yield "road", road.left, road.right, 191


def tile(image: np.ndarray, label: str) -> np.ndarray:
    scale = TILE_WIDTH / image.shape[1]
    out = cv2.resize(image, (TILE_WIDTH, round(image.shape[0] * scale)),
                     interpolation=cv2.INTER_AREA)
    cv2.putText(out, label, (8, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (255, 255, 255), 3,
                cv2.LINE_AA)
    cv2.putText(out, label, (8, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 0), 1,
                cv2.LINE_AA)
    return out


def on_scale(disparity: np.ndarray, span: tuple[float, float]) -> np.ndarray:
    """``disparity`` coloured over ``span`` as the preview's bar is; NaN and inf black."""
    finite = np.isfinite(disparity)
    scaled = np.clip((np.where(finite, disparity, span[0]) - span[0])
                     * (255.0 / (span[1] - span[0])), 0, 255)
    picture = cv2.applyColorMap(scaled.astype(np.uint8), cv2.COLORMAP_TURBO)
    picture[~finite] = 0
    return picture


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--out", default="docs/real_scenes.jpg")
    args = parser.parse_args()
    root = datasets.dataset_folder("middlebury2", args.data_root).parent
    rows = []
    for name, left, right, max_disp in pairs(root):
        result = vsmatch.run(left, right, max_disp=max_disp)
        low, high = result.search_range
        # Pixels whose match would lie outside the right view black, as SGBM leaves them.
        shown = keep_confident(result.disparity, result.confidence, 0.0)
        ours = preview.disparity_preview(shown, None, 0.0)
        width = left.shape[1]
        # SGBM on the same range and the same colours (its holes black).
        raw = sgbm_matcher(high, 3, min_disp=low).compute(left, right).astype(np.float32)
        theirs = np.where(raw >= 16 * low, raw / 16.0, np.nan).astype(np.float32)
        span = preview.colour_range(shown, np.isfinite(shown))  # the bar's
        sgbm = on_scale(theirs, span)
        accurate = vsmatch.run(left, right, max_disp=high, min_disp=low, config="accurate")
        accurate = on_scale(keep_confident(accurate.disparity, accurate.confidence, 0.0), span)
        bar = ours[:, width:]
        conf = cv2.cvtColor((255 * result.confidence).astype(np.uint8), cv2.COLOR_GRAY2BGR)
        kept = (result.confidence >= vsmatch.load_config().cloud.min_confidence
                ).astype(np.uint8)
        edges = cv2.dilate(kept, np.ones((3, 3), np.uint8)) - kept
        conf[edges > 0] = (0, 200, 0)
        rows.append(np.hstack([tile(left, name), tile(sgbm, "OpenCV SGBM"),
                               tile(ours[:, :width], "vsmatch default"),
                               tile(accurate, "vsmatch accurate"),
                               tile(conf, "confidence"),
                               cv2.resize(bar, (bar.shape[1], round(left.shape[0] *
                                                                    TILE_WIDTH / width)))]))
    width = max(r.shape[1] for r in rows)
    picture = np.vstack([np.pad(r, ((0, 4), (0, width - r.shape[1]), (0, 0)),
                                constant_values=255) for r in rows])
    cv2.imwrite(args.out, picture, [cv2.IMWRITE_JPEG_QUALITY, 85])
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
