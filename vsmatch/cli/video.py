"""``vsmatch video``: two videos (or one side by side, or cameras) through one matcher."""

from __future__ import annotations

import time
from pathlib import Path

import click
import cv2
import numpy as np

from .. import io
from ..matcher import StereoMatcher
from .common import (MAX_DISP, check_writable_folder, config_option, echo, friendly_errors,
                     verbose, verbosity_options)
from .main import main

#: Output containers and the codec OpenCV writes them with here.
VIDEO_CODECS = {".avi": "MJPG", ".mp4": "mp4v"}


def _open(source: str) -> cv2.VideoCapture:
    """A video file, or a camera index (``0``, ``1``, ...)."""
    capture = cv2.VideoCapture(int(source)) if source.isdigit() else cv2.VideoCapture(source)
    if not capture.isOpened():
        what = "camera" if source.isdigit() else "video"
        raise click.ClickException(f"{source}: cannot open this {what}")
    return capture


def _frames(left: cv2.VideoCapture, right: cv2.VideoCapture | None):
    """Pairs of frames until either source ends; one side-by-side source is split."""
    while True:
        ok, frame = left.read()
        if not ok:
            return
        if right is None:
            half = frame.shape[1] // 2
            yield (np.ascontiguousarray(frame[:, :half]),
                   np.ascontiguousarray(frame[:, half:2 * half]))
            continue
        ok, other = right.read()
        if not ok:
            return
        yield frame, other


@main.command()
@click.argument("left")
@click.argument("right", required=False)
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="The colour disparity video to write (.avi or .mp4).")
@click.option("--side-by-side", is_flag=True,
              help="LEFT holds both views side by side (left half, right half).")
@click.option("--frames", "frames_dir", type=click.Path(file_okay=False), default=None,
              help="Also write each frame's disparity and confidence here "
                   "(NNNNNN.pfm, NNNNNN_confidence.pfm).")
@click.option("--max-disp", type=MAX_DISP, default=None,
              help="Largest disparity searched; default: the calibration's, else found "
                   "from the first frame (and again when the scene comes closer).")
@click.option("--min-disp", type=int, default=None, help="Smallest disparity searched.")
@click.option("--calib", type=click.Path(dir_okay=False), multiple=True,
              help="As for 'vsmatch run': a rectified pair's calibration or a raw rig's.")
@click.option("--max-frames", type=click.IntRange(min=1), default=None,
              help="Stop after this many frames.")
@config_option
@verbosity_options
@click.pass_context
@friendly_errors
def video(ctx, left, right, output, side_by_side, frames_dir, max_disp, min_disp, calib,
          max_frames, config):
    """Match the frames of two videos (or of one side-by-side video, or of two cameras
    given by index) and write the disparity as a colour video.

    \b
    Example:
      vsmatch video left.mp4 right.mp4 -o disparity.avi --calib stereo.yaml
      vsmatch video both.mp4 --side-by-side -o disparity.mp4 --frames out/
    """
    from tqdm import tqdm

    out = Path(output)
    if out.suffix.lower() not in VIDEO_CODECS:
        raise click.BadParameter(f"'{output}' must end in .avi or .mp4", param_hint="'-o'")
    if side_by_side == (right is not None):
        raise click.UsageError("give LEFT and RIGHT, or one LEFT with --side-by-side")
    check_writable_folder(out)
    stereo = StereoMatcher(max_disp=max_disp, min_disp=min_disp, config=config,
                           calib=list(calib) or None)
    sources = [_open(left)] + ([] if right is None else [_open(right)])
    fps = sources[0].get(cv2.CAP_PROP_FPS) or 10.0
    if frames_dir is not None:
        Path(frames_dir).mkdir(parents=True, exist_ok=True)
    writer, tmp, count, start = None, None, 0, time.perf_counter()
    quiet = ctx.find_root().obj.get("quiet")
    try:
        with tqdm(total=max_frames, disable=quiet, unit="frame", leave=False) as bar:
            for frame_l, frame_r in _frames(sources[0], sources[1] if right else None):
                result = stereo.result(frame_l, frame_r)
                low, high = stereo.range or result.search_range
                picture = io.colour_disparity(result.disparity, high, low)
                if writer is None:
                    # Written beside the output under a temporary name, renamed at the end.
                    tmp = out.with_name(f".{out.stem}.partial{out.suffix}")
                    writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(
                        *VIDEO_CODECS[out.suffix.lower()]), fps, picture.shape[1::-1])
                    if not writer.isOpened():
                        raise click.ClickException(f"{output}: OpenCV cannot write this video")
                writer.write(picture)
                if frames_dir is not None:
                    io.write_disparity(Path(frames_dir) / f"{count:06d}.pfm", result.disparity)
                    io.write_confidence(Path(frames_dir) / f"{count:06d}_confidence.pfm",
                                        result.confidence)
                count += 1
                bar.update(1)
                bar.set_postfix_str(f"{count / (time.perf_counter() - start):.2f} fps")
                if max_frames is not None and count >= max_frames:
                    break
        if writer is None:
            raise click.ClickException(f"{left}: no frame could be read")
        writer.release()
        tmp.replace(out)
    finally:
        for source in sources:
            source.release()
        if writer is not None:
            writer.release()
        if tmp is not None and tmp.exists():
            tmp.unlink()
    seconds = time.perf_counter() - start
    verbose(ctx, f"{count} frames in {seconds:.1f} s ({count / seconds:.2f} fps), "
                 f"disparities {stereo.range[0]}..{stereo.range[1]}"
                 if stereo.range else f"{count} frames in {seconds:.1f} s")
    echo(ctx, f"wrote {output} ({count} frames)")
