"""``vsmatch run``: one pair to a disparity, and depth, cloud, confidence, preview."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from .. import compilation, confidence, geometry, io, pipeline, preview, rig, search_range
from ..config import DEFAULT_CONFIG_NAME, load_config
from .common import (ALPHA, CONFIDENCE_LEVEL, FINITE, MAX_DISP, POSITIVE, announce_compilation,
                     check_outputs, check_png_range, config_option, echo, examples, given,
                     friendly_errors, max_memory_option, remove_left_overs, verbose,
                     verbosity_options, with_budget)

from .main import main


@main.command(epilog=examples(
    "vsmatch run left.png right.png -o disp.pfm --preview disp.png",
    "vsmatch run im0.png im1.png --calib calib.txt -o d.pfm --cloud scene.ply",
    "vsmatch run raw_l.png raw_r.png --calib stereo.yaml -o d.pfm --cloud c.ply"))
@click.argument("left", type=click.Path(dir_okay=True))
@click.argument("right", type=click.Path(dir_okay=True))
@click.option("-o", "--output", type=click.Path(), required=True,
              help="Disparity map to write: .pfm (float32, Middlebury; inf = invalid) or "
                   ".png (16-bit, value = round(256 d), 0 = invalid).")
@click.option("--max-disp", type=MAX_DISP, default=None,
              help="Largest disparity searched, or 'auto' to estimate it from the pair. "
                   "Default: the calibration's range (ndisp, from its dmin or 0), else "
                   "auto (never below the calibration's -doffs).")
@click.option("--min-disp", type=int, default=None,
              help="Smallest disparity searched (may be negative); left pixels with no "
                   "candidate in the range are invalid, as with OpenCV's minDisparity. "
                   "Default: 0, or below 0 when the range found from the pair is.")
@click.option("--calib", type=click.Path(dir_okay=False), multiple=True,
              help="Calibration: a Middlebury 2014 calib.txt or a KITTI "
                   "calib_cam_to_cam.txt of a rectified pair; or a raw rig, whose views "
                   "are rectified first: an OpenCV stereoCalibrate YAML/XML, a Kalibr "
                   "camchain.yaml, or a ROS camera_info or EuRoC sensor.yaml pair (--calib "
                   "left.yaml --calib right.yaml). For --depth and --cloud, and the range.")
@click.option("--alpha", type=ALPHA, default=0.0, show_default=True,
              help="Raw rigs: OpenCV's rectification alpha (0 keeps only valid pixels, "
                   "1 every source pixel).")
@click.option("--rectified", "rectified_dir", type=click.Path(file_okay=False),
              default=None, help="Raw rigs: also keep the rectified pair here (im0.png, "
                                 "im1.png and the rectified rig's calib.txt).")
@click.option("--focal", type=POSITIVE, default=None, help="Focal length in pixels "
              "(instead of --calib; with --baseline).")
@click.option("--baseline", type=POSITIVE, default=None,
              help="Baseline, in the unit depth should come out in.")
@click.option("--cx", type=FINITE, default=None, help="Principal point x (default: centre).")
@click.option("--cy", type=FINITE, default=None, help="Principal point y (default: centre).")
@click.option("--doffs", type=FINITE, default=None,
              help="x-difference of the principal points, right minus left (default 0).")
@click.option("--depth", "depth_path", type=click.Path(dir_okay=False), default=None,
              help="Also write depth f*B/(d + doffs) here (.pfm, inf = unknown).")
@click.option("--cloud", "cloud_path", type=click.Path(dir_okay=False), default=None,
              help="Also write the coloured point cloud here (.ply, binary).")
@click.option("--max-depth", type=POSITIVE, default=None,
              help="Leave points farther than this out of the cloud.")
@click.option("--preview", "preview_path", type=click.Path(dir_okay=False), default=None,
              help="Also write the disparity as a colour image here (.png or .jpg): colours "
                   "over the disparities present with a colour bar, pixels below the "
                   "confidence threshold dimmed and hatched, invalid pixels black.")
@click.option("--confidence", "confidence_path", type=click.Path(dir_okay=False),
              default=None, help="Also write each pixel's confidence in [0, 1] here (.pfm "
              "float32, or .png 16-bit scaled to 0..65535).")
@click.option("--min-confidence", type=CONFIDENCE_LEVEL, default=None, metavar="C",
              help="Mark pixels whose confidence is below C invalid in every output. "
                   "Default: -o stays dense; --depth and --cloud keep pixels at or above "
                   "the config's cloud.min_confidence (0.88 in default and accurate, 0.92 "
                   "in fast; 0 keeps all).")
@config_option
@max_memory_option
@verbosity_options
@click.pass_context
@friendly_errors
def run(ctx, left, right, output, max_disp, min_disp, calib, alpha, rectified_dir, focal,
        baseline, cx, cy,
        doffs, depth_path, cloud_path, max_depth, preview_path, confidence_path,
        min_confidence, config, max_memory):
    """Compute the left-view disparity of a rectified stereo pair.
    """
    out = Path(output)
    _check_output_path(out)
    if depth_path is not None and Path(depth_path).suffix.lower() != ".pfm":
        raise click.BadParameter(f"'{depth_path}' must end in .pfm", param_hint="'--depth'")
    if cloud_path is not None and Path(cloud_path).suffix.lower() != ".ply":
        raise click.BadParameter(f"'{cloud_path}' must end in .ply", param_hint="'--cloud'")
    if preview_path is not None and Path(preview_path).suffix.lower() not in (".png", ".jpg"):
        raise click.BadParameter(f"'{preview_path}' must end in .png or .jpg",
                                 param_hint="'--preview'")
    if confidence_path is not None and (
            Path(confidence_path).suffix.lower() not in io.CONFIDENCE_FORMATS):
        raise click.BadParameter(f"'{confidence_path}' must end in .pfm or .png",
                                 param_hint="'--confidence'")
    raw_rig = rig.read_rig(calib) if calib and rig.is_raw_rig(calib) else None
    _refuse_idle_options(ctx, raw_rig is not None, bool(depth_path or cloud_path or calib),
                         cloud_path is not None)
    outputs = [output, depth_path, cloud_path, preview_path, confidence_path]
    check_outputs([left, right, *calib], outputs, folders=rectified_outputs(rectified_dir))
    camera = None if raw_rig else _calibration(calib, focal, baseline, cx, cy, doffs)
    if raw_rig is not None:
        _refuse_hand_values(_hand_values(focal, baseline, cx, cy, doffs))
    if (depth_path or cloud_path) and camera is None and raw_rig is None:
        raise click.UsageError("--depth and --cloud need --calib, or --focal and --baseline")
    if (depth_path or cloud_path) and camera is not None:
        _check_depth_fits(camera, calib)
    cfg = with_budget(load_config(config), max_memory)
    # Refused before anything is decoded: a range a PNG cannot hold, an image too large.
    if max_disp is not None:
        check_png_range(out, min_disp or 0, max_disp)
    left_image, right_image = io.read_pair(left, right, max_mb=cfg.memory.max_mb,
                                           max_megapixels=cfg.memory.max_megapixels)
    if raw_rig is not None:
        rectifier = rig.Rectifier(raw_rig, left_image.shape[1::-1], alpha)
        left_image, right_image = rectifier.rectify(left_image, right_image)
        camera = rectifier.calibration()
        verbose(ctx, f"rectified with {', '.join(calib)}: f {camera.focal:.1f} px, "
                     f"baseline {camera.baseline:g}")
        if depth_path or cloud_path:
            _check_depth_fits(camera, calib)
    elif camera is not None:
        _check_calibration_size(camera, calib[0] if calib else "--cx/--cy/--doffs",
                                left_image.shape)
    width = left_image.shape[1]
    try:
        pipeline.check_views(left_image, right_image, cfg)
    except ValueError as exc:
        raise click.ClickException(f"{left}: {exc}") from None
    if max_disp is not None and max_disp >= width:
        raise click.BadParameter(f"{max_disp} must be less than the image width ({width})",
                                 param_hint="'--max-disp'")
    if max_disp is None and camera is not None and camera.ndisp is not None and (
            camera.search_range(width) is None):
        verbose(ctx, f"{calib[0]}: ndisp={camera.ndisp} is half the image width or more, "
                      "taken as 'unknown': finding the range from the pair")
    def before_dense_check():
        # Finding the range runs a match of its own (the default config's) once the feature
        # matches passed: compiled ahead with the config's kernels, bands included (the
        # range, which decides them, is not known yet).
        announce_compilation(ctx, config, bands=True, also=(DEFAULT_CONFIG_NAME,))

    try:
        searched = search_range.resolve_range(left_image, right_image, min_disp=min_disp,
                                              max_disp=max_disp, camera=camera,
                                              rectified_here=raw_rig is not None,
                                              before_dense_check=before_dense_check)
    except ValueError as exc:
        raise click.ClickException(f"{left}: {exc}") from None
    if searched.found is not None:
        verbose(ctx, f"{left}: {searched.found.describe()}")
    else:
        # Given a range, a pair the method cannot see is wrong is still named.
        problem = search_range.pair_problem(search_range.feature_matches(
            left_image, right_image, max_width=search_range.CHECK_WIDTH))
        if problem is not None:
            if raw_rig is not None:
                problem = search_range.said_of_rig(problem)
            echo(ctx, f"warning: {left}: {problem}", err=True)
    min_disp, max_disp = searched.min_disp, searched.max_disp
    check_png_range(out, min_disp, max_disp)
    try:
        pipeline.check_pair(left_image, right_image, max_disp, cfg, min_disp)
    except ValueError as exc:
        raise click.ClickException(f"{left}: {exc}") from None
    verbose(ctx, f"searching disparities {min_disp}..{max_disp}")
    announce_compilation(ctx, config, bands=compilation.searches_bands(
        cfg, left_image.shape, min_disp, max_disp))
    result = pipeline.run(left_image, right_image, max_disp=max_disp, min_disp=min_disp,
                          config=cfg)
    remove_left_overs(ctx, outputs)
    disp = result.disparity
    if min_confidence is not None:  # every output, the disparity too
        disp = confidence.keep_confident(disp, result.confidence, min_confidence)
    # Depth and clouds keep only what is likely right unless told otherwise.
    kept_at = cfg.cloud.min_confidence if min_confidence is None else min_confidence
    metric_disp = confidence.keep_confident(result.disparity, result.confidence, kept_at)
    # Every output of the run, or none of them (nor the --rectified folder).
    with io.output_folder(rectified_dir), io.all_or_none():
        io.write_disparity(out, disp)
        if rectified_dir is not None:
            write_rectified(rectified_dir, left_image, right_image, camera,
                            (min_disp, max_disp))
        if depth_path is not None:
            io.write_depth(depth_path, geometry.depth_from_disparity(metric_disp, camera))
        if cloud_path is not None:
            points, colours = geometry.point_cloud(metric_disp, left_image, camera,
                                                   max_depth=max_depth)
            io.write_point_cloud(cloud_path, geometry.ply_vertices(points, colours))
            verbose(ctx, f"{len(points)} points in the cloud (confidence >= {kept_at:g}"
                          f"; {int(np.isfinite(result.disparity).sum()) - len(points)} left out)")
            if len(points) == 0:
                depth_note = "" if max_depth is None else f" and --max-depth {max_depth:g}"
                echo(ctx, f"warning: {cloud_path} holds no points: no pixel reached the "
                          f"confidence of {kept_at:g} (cloud.min_confidence, --min-confidence)"
                          f"{depth_note}", err=True)
        if preview_path is not None:
            io.imwrite_atomic(preview_path, preview.disparity_preview(
                disp, result.confidence, kept_at))
        if confidence_path is not None:
            io.write_confidence(confidence_path, result.confidence)
    _report_run(ctx, result)
    for path in outputs:
        if path is not None:
            echo(ctx, f"wrote {path}")
    piled = search_range.range_end_warning(result.disparity, min_disp, max_disp)
    if piled is not None:
        echo(ctx, f"warning: {left}: {piled}", err=True)


def rectified_outputs(folder) -> dict[Path, list[Path]]:
    """The folder ``--rectified`` / ``rectify --to`` names, and the files written in it."""
    if folder is None:
        return {}
    return {Path(folder): [Path(folder) / name for name in RECTIFIED_FILES]}


RECTIFIED_FILES = ("im0.png", "im1.png", "calib.txt")


def _refuse_idle_options(ctx, raw_rig: bool, metric: bool, cloud: bool) -> None:
    """Options that would do nothing here are refused, not ignored (``metric``: depth or
    a cloud is asked for, or a calibration file given, beside which values by hand are
    refused on their own)."""
    if not raw_rig:
        for name in ("rectified_dir", "alpha"):
            if given(ctx, name):
                option = "--rectified" if name == "rectified_dir" else "--alpha"
                raise click.UsageError(f"{option} is for a raw rig's --calib (its views are "
                                       "rectified here)")
    if not metric:
        hand = [f"--{n}" for n in ("focal", "baseline", "cx", "cy", "doffs")
                if ctx.params.get(n) is not None]
        if hand:
            raise click.UsageError(f"{', '.join(hand)} give the camera for --depth and "
                                   "--cloud, and neither is asked for")
    if not cloud and ctx.params.get("max_depth") is not None:
        raise click.UsageError("--max-depth limits the --cloud, which is not asked for")


def _check_output_path(path: Path) -> None:
    suffix = path.suffix.lower()
    if suffix not in io.DISPARITY_FORMATS:
        raise click.BadParameter(f"'{path}' must end in .pfm (float32) or .png (16-bit)",
                                 param_hint="'-o'")


def _check_depth_fits(camera: geometry.Calibration, calib) -> None:
    problem = camera.depth_problem()
    if problem is not None:
        where = calib[0] if calib else "--focal x --baseline"
        raise click.ClickException(f"{where}: {problem}")


def _check_calibration_size(camera: geometry.Calibration, path, shape) -> None:
    problem = camera.size_problem(shape)
    if problem is not None:
        raise click.ClickException(f"{path}: {problem}")


def _calibration(calib, focal, baseline, cx, cy, doffs) -> geometry.Calibration | None:
    """The camera from --calib, or from --focal and --baseline, or None."""
    given = _hand_values(focal, baseline, cx, cy, doffs)
    if calib:
        _refuse_hand_values(given)
        if len(calib) > 1:
            raise click.UsageError("two --calib files are a ROS camera_info pair of a raw "
                                   "rig; a rectified pair has one calibration file")
        return geometry.read_calibration(calib[0])
    if not given:
        return None
    if focal is None or baseline is None:
        raise click.UsageError("--focal and --baseline go together")
    return geometry.Calibration(focal=focal, baseline=baseline, cx=cx, cy=cy,
                                doffs=doffs or 0.0)


def _hand_values(focal, baseline, cx, cy, doffs) -> list[str]:
    """The options of a camera given by hand that are set."""
    return [k for k, v in {"--focal": focal, "--baseline": baseline, "--cx": cx, "--cy": cy,
                           "--doffs": doffs}.items() if v is not None]


def _refuse_hand_values(given: list[str]) -> None:
    """Beside a calibration file (a calib.txt, or a raw rig's, which gives the rectified
    camera) values by hand would be ignored: refused."""
    if given:
        raise click.UsageError(f"give --calib or {', '.join(given)}, not both")


def _report_run(ctx: click.Context, result: pipeline.MatchResult) -> None:
    """Under --verbose: the estimated noise and the stage times."""
    if result.noise_sigma is not None:
        floor = result.config.noise.floor
        action = "adapted" if result.noise_sigma > floor else "no adaptation"
        verbose(ctx, f"estimated noise: {result.noise_sigma:.2f} grey levels "
                      f"(floor {floor:g}: {action})")
    if result.photometric is not None:
        fit = result.photometric
        verbose(ctx, f"exposure: matched colours differ by {fit.before:.1f} grey levels, "
                      f"{fit.residual:.1f} after the right view's colour map "
                      f"({fit.matches} pixels); colour term weight "
                      f"{result.colour_weight:.2f}")
    if result.levels or result.stripes > 1:
        verbose(ctx, f"full search {result.levels} pyramid level(s) down, in "
                      f"{result.stripes} stripe(s)")
    times = ", ".join(f"{k} {v:.3f}" for k, v in result.seconds.items())
    verbose(ctx, f"seconds: {times}; total {sum(result.seconds.values()):.3f}")


def write_rectified(folder, left, right, camera: geometry.Calibration,
                    search: tuple[int, int] | None) -> None:
    """im0.png, im1.png and a Middlebury calib.txt of the rectified rig in ``folder``,
    with the range ``search`` (min, max) that was searched, when one was."""
    folder = Path(folder)
    size = left.shape[1::-1]
    with io.all_or_none():
        io.imwrite_atomic(folder / RECTIFIED_FILES[0], left)
        io.imwrite_atomic(folder / RECTIFIED_FILES[1], right)
        io.write_text_atomic(folder / RECTIFIED_FILES[2], rig.middlebury_calib_text(
            camera, size, search))
