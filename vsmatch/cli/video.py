"""``vsmatch video``: two videos (or one side by side, or cameras) through one matcher."""

from __future__ import annotations

import contextlib
import time
from pathlib import Path

import click
import cv2
import numpy as np

from .. import confidence, frames, geometry, io, preview
from ..config import DEFAULT_CONFIG_NAME
from ..matcher import StereoMatcher
from ..search_range import PairGeometryError, RangeError
from .common import (MAX_DISP, announce_compilation, check_outputs, config_option, echo, examples,
                     friendly_errors, remove_left_overs, verbose, verbosity_options)

from .main import main

@main.command(epilog=examples(
    "vsmatch video left.mp4 right.mp4 -o disparity.avi --calib stereo.yaml",
    "vsmatch video 0 1 -o live.avi --calib stereo.yaml --config fast",
    "vsmatch video mav0/cam0 mav0/cam1 -o drone.avi --depth-frames depth/",
    "vsmatch video cam0/ cam1/ -o d.avi --calib cam0/sensor.yaml --calib cam1/sensor.yaml"))
@click.argument("left")
@click.argument("right", required=False)
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="The colour disparity video to write (.avi or .mp4).")
@click.option("--side-by-side", is_flag=True,
              help="LEFT holds both views side by side (left half, right half).")
@click.option("--frames", "frames_dir", type=click.Path(file_okay=False), default=None,
              help="Also write each frame's disparity and confidence here "
                   "(NNNNNN.pfm, NNNNNN_confidence.pfm); a folder that holds anything is "
                   "refused unless --overwrite.")
@click.option("--depth-frames", "depth_dir", type=click.Path(file_okay=False), default=None,
              help="Also write each frame's depth here (NNNNNN.pfm in the calibration's "
                   "unit, inf = unknown; or NNNNNN.png with --depth-png), the pixels at or "
                   "above the config's cloud.min_confidence. Needs a calibration.")
@click.option("--depth-png", is_flag=True,
              help="--depth-frames as 16-bit PNGs as depth cameras write them: depth x 1000 "
                   "(millimetres for a calibration in metres), 0 = unknown; needs "
                   "--max-depth of at most 65.535 (the most a PNG holds), farther left out.")
@click.option("--cloud-frames", "cloud_dir", type=click.Path(file_okay=False), default=None,
              help="Also write each frame's coloured point cloud here (NNNNNN.ply), the "
                   "pixels --depth-frames keeps. Needs a calibration.")
@click.option("--max-depth", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Leave points farther than this out of --depth-frames and --cloud-frames.")
@click.option("--overwrite", is_flag=True,
              help="Replace the frame folders of an earlier run, each as a whole (a "
                   "folder that holds anything else is refused).")
@click.option("--max-disp", type=MAX_DISP, default=None,
              help="Largest disparity searched; default: the calibration's, else found "
                   "from the first frame (and again when the scene comes closer).")
@click.option("--min-disp", type=int, default=None, help="Smallest disparity searched.")
@click.option("--calib", type=click.Path(dir_okay=False), multiple=True,
              help="As for 'vsmatch run': a rectified pair's calibration or a raw rig's.")
@click.option("--max-frames", type=click.IntRange(min=1), default=None,
              help="Stop after this many frames.")
@click.option("--temporal/--no-temporal", default=True, show_default=True,
              help="Each frame searches near the last one's disparities and holds them "
                   "where the image holds still (steadier depth, faster); --no-temporal "
                   "matches every frame alone.")
@config_option
@verbosity_options
@click.pass_context
@friendly_errors
def video(ctx, left, right, output, side_by_side, frames_dir, depth_dir, depth_png, cloud_dir,
          max_depth, overwrite, max_disp, min_disp, calib, max_frames, temporal, config):
    """Match the frames of two videos (or of one side-by-side video, of two cameras
    given by index, or of two folders of frames, in the order of the number in their
    names and paired by name or time stamp; EuRoC's mav0/cam0 and mav0/cam1 as they
    ship, their sensor.yaml found there) and write the disparity as a colour video:
    pixels under the config's cloud threshold dimmed, a colour bar (depths with a
    calibration).

    Frames of one video without a partner in the other are counted as failed (exit 1);
    files that are not images and frames that cannot be read are skipped with a word.
    """
    from tqdm import tqdm

    out = Path(output)
    if out.suffix.lower() not in frames.VIDEO_CODECS:
        raise click.BadParameter(f"'{output}' must end in .avi or .mp4", param_hint="'-o'")
    if side_by_side == (right is not None):
        raise click.UsageError("give LEFT and RIGHT, or one LEFT with --side-by-side")
    if depth_png and depth_dir is None:
        raise click.UsageError("--depth-png says how --depth-frames are written: give "
                               "--depth-frames too")
    if depth_png and not (max_depth is not None and max_depth <= PNG_DEPTH_LIMIT):
        raise click.UsageError(f"--depth-png holds depths up to {PNG_DEPTH_LIMIT} (x 1000 in "
                               "16 bits): give --max-depth of at most that")
    names = [left] + ([] if right is None else [right])
    if len(names) == 2 and _same_source(*names):
        what = "camera" if left.isdigit() else ("folder" if Path(left).is_dir() else "video")
        raise click.ClickException(f"LEFT and RIGHT are the same {what} ({left}, {right}): "
                                   f"give each camera's {what}, or one side-by-side video "
                                   "with --side-by-side")
    inputs = [n for n in names if not n.isdigit()] + list(calib)
    folders = {name: folder for name, folder in (("--frames", frames_dir),
                                                 ("--depth-frames", depth_dir),
                                                 ("--cloud-frames", cloud_dir)) if folder}
    check_outputs(inputs, [output], folders={folder: [] for folder in folders.values()})
    if len({io.resolved(folder) for folder in folders.values()}) < len(folders):
        raise click.UsageError(f"{', '.join(folders)} must name different folders")
    for name, folder in folders.items():  # each replaced as a whole: nothing else in it
        others = [f for f in folders.values() if f != folder]
        root = io.resolved(folder)
        for path in [*inputs, output, *others]:
            if io.resolved(path).is_relative_to(root):
                role = "the input" if path in inputs else "the output"
                raise click.ClickException(
                    f"{name} {folder} holds {role} {path}: the folder is replaced as a "
                    f"whole; give {name} a folder of its own")
        try:
            io.check_replaceable_folder(folder, overwrite=overwrite, ours=frames.is_frame_file)
        except OSError as exc:
            raise click.ClickException(str(exc)) from None
    # What an earlier run of these outputs left when it was killed (SIGKILL) goes now.
    remove_left_overs(ctx, [out, *(io.followed_folder(f) for f in folders.values())])
    folder_pairs = len(names) == 2 and all(Path(name).is_dir() for name in names)
    if folder_pairs:
        pairs = frames.FolderPairs(*names)
        if not calib and pairs.sensor_files():  # EuRoC's cameras carry their calibration
            calib = pairs.sensor_files()
            echo(ctx, f"calibration: {calib[0]} and {calib[1]}")
    if (depth_dir or cloud_dir) and not calib:
        raise click.UsageError("--depth-frames and --cloud-frames need --calib (a rectified "
                               "pair's calibration or a raw rig's)")
    if folder_pairs:
        sources, fps = [], pairs.fps() or 10.0
    else:
        for name in names:  # a missing one named before a folder beside it is blamed
            if not name.isdigit() and not Path(name).exists():
                raise frames.FrameSourceError(f"{name}: file not found")
        sources = [frames.open_source(name) for name in names]
        frames.check_frame_rates(names, sources)
        fps = sources[0].get(cv2.CAP_PROP_FPS) or 10.0
        pairs = frames.FramePairs(names, sources)
    stereo = StereoMatcher(max_disp=max_disp, min_disp=min_disp, config=config,
                           calib=list(calib) or None, temporal=temporal)
    announce_compilation(ctx, config, stream=temporal,  # a range to find: default's match
                         also=(DEFAULT_CONFIG_NAME,) if max_disp is None else ())
    count, start = 0, time.perf_counter()
    threshold = stereo.config.cloud.min_confidence  # dimmed below it, as --preview does
    quiet = ctx.find_root().obj.get("quiet")

    full = 0  # frames that searched the whole range
    no_range = []  # frames written empty: no range found yet (dark, blank)

    def pictures(written: dict[str, Path]):
        nonlocal count, full
        total = len(pairs.paths) if isinstance(pairs, frames.FolderPairs) else None
        if max_frames is not None:
            total = max_frames if total is None else min(total, max_frames)
        # A bar in a terminal only (None): a log file gets no carriage returns.
        with tqdm(total=total, disable=True if quiet else None, unit="frame",
                  leave=False) as bar:
            size = None
            for frame_l, frame_r in pairs:
                size = size or frame_l.shape[1::-1]
                if frame_l.shape[1::-1] != size:  # a video holds one size of frame
                    name = getattr(pairs, "current", None) or f"frame {count + 1} of {left}"
                    width, height = frame_l.shape[1::-1]
                    raise click.ClickException(
                        f"{name} is {width}x{height}, the frames before it {size[0]}x"
                        f"{size[1]}: one video holds frames of one size; give the frames of "
                        "each size as a video of their own")
                try:
                    result = stereo.result(frame_l, frame_r)
                except RangeError as exc:
                    if stereo.range is not None or isinstance(exc, PairGeometryError):
                        raise
                    no_range.append(str(exc))  # the range comes from a later frame
                    result = stereo.empty_result(frame_l)
                full += stereo.temporal is None or stereo.temporal.reason is not None
                low, high = stereo.range or result.search_range or (0, 1)
                yield preview.video_frame(result.disparity, result.confidence, threshold,
                                          low, high, geometry.depth_of(stereo.camera))
                write_frame(written, f"{count:06d}", result, stereo, threshold, max_depth,
                            depth_png)
                count += 1
                bar.update(1)
                bar.set_postfix_str(f"{count / (time.perf_counter() - start):.2f} fps")
                if max_frames is not None and count >= max_frames:
                    return

    try:
        with io.all_or_none():  # the video and the frames folder together, or neither
            with contextlib.ExitStack() as stack:
                written = {name: stack.enter_context(io.staged_folder(
                    folder, overwrite=overwrite, ours=frames.is_frame_file))
                    for name, folder in folders.items()}
                io.write_atomic(out, lambda tmp: _write_or_refuse(
                    tmp, pictures(written), fps, out, left), silenced=False)
                if no_range and len(no_range) == count:  # nothing but empty frames
                    raise click.ClickException(f"no frame of {left} gave a disparity range: "
                                               f"{no_range[0]}")
        stopped = max_frames is not None and count >= max_frames
        unpaired = None if stopped else pairs.unpaired()
    finally:
        for source in sources:
            source.release()
    seconds = time.perf_counter() - start
    verbose(ctx, f"{count} frames in {seconds:.1f} s ({count / seconds:.2f} fps), "
                 f"disparities {stereo.range[0]}..{stereo.range[1]}"
                 if stereo.range else f"{count} frames in {seconds:.1f} s")
    rate = f", {count / seconds:.2f} fps" if count and seconds > 0 else ""
    searched = (f"; {full} searched the whole range, {count - full} near the last frame"
                if temporal else "")
    echo(ctx, f"wrote {output} ({count} frames{rate}{searched})")
    if no_range:
        echo(ctx, f"warning: the first {len(no_range)} frame{'s' if len(no_range) > 1 else ''}"
                  " gave no disparity range (dark or blank?) and were written empty",
             err=True)
    for line in getattr(pairs, "skipped", list)():
        echo(ctx, f"warning: {line}", err=True)
    if unpaired is not None:
        raise click.ClickException(unpaired)


def _write_or_refuse(tmp: str, pictures, fps: float, out: Path, left: str) -> None:
    if frames.write_video(tmp, pictures, fps, frames.VIDEO_CODECS[out.suffix.lower()]) == 0:
        raise click.ClickException(f"{left}: no frame could be read")


#: The farthest depth a 16-bit PNG of depth x 1000 holds.
PNG_DEPTH_LIMIT = 65.535


def write_frame(written: dict[str, Path], stem: str, result, stereo: StereoMatcher,
                threshold: float, max_depth: float | None, depth_png: bool) -> None:
    """One frame's files in the folders asked for (``written``: option -> staged folder)."""
    if "--frames" in written:
        io.write_disparity(written["--frames"] / f"{stem}.pfm", result.disparity)
        io.write_confidence(written["--frames"] / f"{stem}_confidence.pfm", result.confidence)
    if "--depth-frames" not in written and "--cloud-frames" not in written:
        return
    kept = confidence.keep_confident(result.disparity, result.confidence, threshold)
    if "--depth-frames" in written:
        depth = geometry.depth_from_disparity(kept, stereo.camera)
        if max_depth is not None:
            depth[depth > max_depth] = np.inf
        if depth_png:
            known = np.isfinite(depth)
            scaled = np.zeros(depth.shape, np.uint16)
            scaled[known] = np.rint(depth[known] * 1000).astype(np.uint16)
            io.imwrite_atomic(written["--depth-frames"] / f"{stem}.png", scaled)
        else:
            io.write_depth(written["--depth-frames"] / f"{stem}.pfm", depth)
    if "--cloud-frames" in written:
        points, colours = geometry.point_cloud(kept, stereo.views[0], stereo.camera,
                                               max_depth=max_depth)
        io.write_point_cloud(written["--cloud-frames"] / f"{stem}.ply",
                             geometry.ply_vertices(points, colours))


def _same_source(left: str, right: str) -> bool:
    """Whether two sources name one camera index, or one file or folder (links and ``..``
    resolved)."""
    if left.isdigit() or right.isdigit():
        return left.isdigit() and right.isdigit() and int(left) == int(right)
    return io.resolved(left) == io.resolved(right)
