"""The ``vsmatch`` command: thin wrappers over the library.

Exit status: 0 success; 1 a problem with the inputs, data, config or outputs (one line on
stderr, no traceback, no output file left behind), or an unexpected error (one line;
``--debug`` or ``VSMATCH_DEBUG=1`` shows the traceback); 2 a usage error (bad option or
argument); 130 interrupted (Ctrl-C); 143 terminated (SIGTERM).
"""

from __future__ import annotations

import functools
import json
import math
import os
import signal
import sys
import threading
from pathlib import Path

import click
import numpy as np

from . import (__version__, batch, confidence, datasets, evaluation, geometry, io, pipeline,
               search_range, synthetic)
from .confidence import DEFAULT_MIN_CONFIDENCE
from .config import ConfigError, bundled_config_names, config_from_dict, load_config
from .executors import ExecutorError, make_executor
from .peers import PEER_METHODS

EXPECTED_ERRORS = (ConfigError, io.ImageError, datasets.DatasetError, batch.BatchError,
                   ExecutorError, ValueError, OSError)

#: Exit status after Ctrl-C (128 + SIGINT) and SIGTERM (128 + 15), as shells report them.
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so that it unwinds like Ctrl-C: temporaries
    are removed and the worker processes are ended on the way out."""


def _on_sigterm(signum, frame):
    raise Terminated()


def _stop(exc: BaseException) -> None:
    """The one line and exit status of an interruption."""
    if isinstance(exc, Terminated):
        click.echo("vsmatch: terminated", err=True)
        sys.exit(EXIT_TERMINATED)
    click.echo("vsmatch: interrupted", err=True)
    sys.exit(EXIT_INTERRUPTED)


def _debugging() -> bool:
    ctx = click.get_current_context(silent=True)
    flag = bool(ctx and (ctx.find_root().obj or {}).get("debug"))
    return flag or os.environ.get("VSMATCH_DEBUG", "") not in ("", "0")


def friendly_errors(func):
    """Turn the library's expected errors into one-line ClickExceptions (exit 1), any
    other exception into one line naming the command (the traceback under --debug), and
    Ctrl-C or SIGTERM into a one-line notice with exit status 130 or 143."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except click.ClickException:
            raise
        except EXPECTED_ERRORS as exc:
            if _debugging():
                raise
            raise click.ClickException(_one_line(exc)) from None
        except KeyboardInterrupt as exc:
            _stop(exc)
        except (Exception, RecursionError, MemoryError) as exc:
            if _debugging():
                raise
            ctx = click.get_current_context(silent=True)
            where = " ".join(["vsmatch"] + (ctx.command_path.split()[1:] if ctx else []))
            raise click.ClickException(
                f"{where}: unexpected {type(exc).__name__}: {_one_line(exc)[:300]} "
                "(--debug shows the traceback)") from None
    return wrapper


def verbosity_options(func):
    """-v, -q and --debug after the command name too (``vsmatch run ... -v``)."""
    def setter(key):
        def callback(ctx, param, value):
            if value:
                root = ctx.find_root().obj
                root[key] = True
                if key == "quiet":
                    root["verbose"] = False
                elif key == "verbose":
                    root["verbose"] = not root.get("quiet")
        return callback
    for names, key, text in ((("-q", "--quiet"), "quiet", "Print only errors."),
                             (("-v", "--verbose"), "verbose", "Print more (stage times, "
                              "the range found, ...) on stderr."),
                             (("--debug",), "debug", "Show the traceback of an "
                              "unexpected error.")):
        func = click.option(*names, key + "_flag", is_flag=True, expose_value=False,
                            callback=setter(key), help=text)(func)
    return func


class Finite(click.ParamType):
    """A finite float (nan and inf refused), optionally above a bound."""

    name = "NUMBER"

    def __init__(self, positive: bool = False):
        self.positive = positive

    def convert(self, value, param, ctx):
        if isinstance(value, float) and math.isfinite(value):
            number = value
        else:
            try:
                number = float(value)
            except (TypeError, ValueError):
                self.fail(f"'{value}' is not a number", param, ctx)
            if not math.isfinite(number):
                self.fail(f"'{value}' is not a finite number", param, ctx)
        if self.positive and number <= 0:
            self.fail(f"{number:g} must be greater than 0", param, ctx)
        return number


FINITE, POSITIVE = Finite(), Finite(positive=True)


class ConfidenceLevel(Finite):
    """A confidence threshold in [0, 1]."""

    name = "C"

    def convert(self, value, param, ctx):
        number = super().convert(value, param, ctx)
        if not 0 <= number <= 1:
            self.fail(f"{number:g} is not in [0, 1]", param, ctx)
        return number


CONFIDENCE_LEVEL = ConfidenceLevel()


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip() or type(exc).__name__
    return " ".join(text.split())


def _echo(ctx: click.Context, message: str, *, err: bool = False) -> None:
    if not ctx.find_root().obj.get("quiet"):
        click.echo(message, err=err)


def _verbose(ctx: click.Context, message: str) -> None:
    if ctx.find_root().obj.get("verbose"):
        click.echo(message, err=True)


def config_option(func):
    return click.option(
        "--config", "config", default=None, metavar="NAME|PATH",
        help=f"Method parameters: a bundled config ({', '.join(bundled_config_names())}) "
             "or a YAML file. Default: 'default'.")(func)


def max_memory_option(func):
    return click.option(
        "--max-memory", type=click.IntRange(min=16, max=1 << 20), default=None, metavar="MB",
        help="Working-memory budget of the matching in MB (the config's memory.max_mb, "
             "default 1024); larger images are matched in horizontal stripes.")(func)


def _scheduler_address(value: str | None) -> str | None:
    from .executors.cluster import check_scheduler

    if value is not None:
        try:
            check_scheduler(value)
        except ExecutorError as exc:
            raise click.BadParameter(str(exc).split(": ", 1)[1],
                                     param_hint="'--scheduler'") from None
    return value


def _with_budget(cfg, max_memory: int | None):
    """The config with ``--max-memory`` as its memory budget, if given."""
    if max_memory is None:
        return cfg
    return config_from_dict({"memory": {"max_mb": max_memory}}, base=cfg)


def data_root_option(func):
    return click.option(
        "--data-root", type=click.Path(file_okay=False), default=None,
        help="Folder holding middlebury2/ (and middlebury-2005-2006-third/). Default: "
             "$VSMATCH_DATA, else ./data, else ../shared/data.")(func)


class MaxDisparity(click.ParamType):
    """``--max-disp``: a whole number of pixels, or ``auto`` (None)."""

    name = "N|auto"

    def convert(self, value, param, ctx):
        if value is None or isinstance(value, int):
            return value
        if str(value).strip().lower() == "auto":
            return None
        try:
            number = int(value)
        except ValueError:
            self.fail(f"'{value}' is neither a whole number nor 'auto'", param, ctx)
        if number <= 0:
            self.fail(f"{number} must be at least 1", param, ctx)
        return number


MAX_DISP = MaxDisparity()


class OneLineErrors(click.Group):
    """A group whose every error is one line on stderr: Click's usage errors too, which
    it would otherwise print over four lines with the usage text."""

    def main(self, *args, **kwargs):
        kwargs["standalone_mode"] = False
        try:
            result = super().main(*args, **kwargs)
        except click.UsageError as exc:
            where = exc.ctx.command_path if exc.ctx is not None else "vsmatch"
            click.echo(f"Error: {exc.format_message()} (see '{where} --help')", err=True)
            sys.exit(exc.exit_code)
        except click.ClickException as exc:
            exc.show()
            sys.exit(exc.exit_code)
        except KeyboardInterrupt as exc:
            _stop(exc)
        except click.Abort:
            _stop(KeyboardInterrupt())
        except (Exception, RecursionError, MemoryError) as exc:
            # Outside a command (option parsing, start-up): still one line.
            argv = kwargs.get("args", args[0] if args else None)
            argv = sys.argv[1:] if argv is None else list(argv)
            if os.environ.get("VSMATCH_DEBUG", "") not in ("", "0") or "--debug" in argv:
                raise
            click.echo(f"vsmatch: unexpected {type(exc).__name__}: {_one_line(exc)[:300]} "
                       "(--debug shows the traceback)", err=True)
            sys.exit(1)
        sys.exit(result if isinstance(result, int) else 0)


@click.group(cls=OneLineErrors, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="vsmatch")
@click.option("-q", "--quiet", is_flag=True, help="Print only errors.")
@click.option("-v", "--verbose", is_flag=True,
              help="Also print stage times and the estimated noise (on stderr).")
@click.option("--debug", is_flag=True, help="Show the traceback of an unexpected error "
              "(also VSMATCH_DEBUG=1).")
@click.pass_context
def main(ctx: click.Context, quiet: bool, verbose: bool, debug: bool) -> None:
    """Dense stereo matching guided by visual sensitive information.

    Wang, Pathan and Dev, "Stereo Matching Based on Visual Sensitive Information",
    ICIVC 2021: census and gradient costs, cross-shaped aggregation guided by the
    gradient direction, left-right check and filling.
    """
    ctx.ensure_object(dict)
    ctx.obj["quiet"] = quiet
    ctx.obj["verbose"] = verbose and not quiet
    ctx.obj["debug"] = debug
    _silence_opencv()
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _on_sigterm)


def _silence_opencv() -> None:
    """Keep OpenCV's decoders (libpng, ...) from printing beside our one-line errors."""
    import cv2

    try:
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    except AttributeError:  # an OpenCV build without the logging module
        pass


def _check_output_path(path: Path) -> None:
    suffix = path.suffix.lower()
    if suffix not in io.DISPARITY_FORMATS:
        raise click.BadParameter(f"'{path}' must end in .pfm (float32) or .png (16-bit)",
                                 param_hint="'-o'")
    _check_writable_folder(path)


def _writable(folder: Path) -> bool:
    return os.access(folder, os.W_OK)


@main.command()
@click.argument("left", type=click.Path(dir_okay=True))
@click.argument("right", type=click.Path(dir_okay=True))
@click.option("-o", "--output", type=click.Path(), required=True,
              help="Disparity map to write: .pfm (float32, Middlebury; inf = invalid) or "
                   ".png (16-bit, value = round(256 d), 0 = invalid).")
@click.option("--max-disp", type=MAX_DISP, default=None,
              help="Largest disparity searched, or 'auto' to estimate it from the pair. "
                   "Default: the calibration's ndisp - 1, else auto.")
@click.option("--min-disp", type=int, default=None,
              help="Smallest disparity searched (may be negative); left pixels with no "
                   "candidate in the range are invalid, as with OpenCV's minDisparity. "
                   "Default: 0, or below 0 when the range found from the pair is.")
@click.option("--calib", type=click.Path(dir_okay=False), default=None,
              help="Calibration: a Middlebury 2014 calib.txt or a KITTI "
                   "calib_cam_to_cam.txt (for --depth and --cloud, and the range).")
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
              help="Also write the disparity as a colour image here (.png or .jpg; "
                   "invalid pixels black).")
@click.option("--confidence", "confidence_path", type=click.Path(dir_okay=False),
              default=None, help="Also write each pixel's confidence in [0, 1] here (.pfm "
              "float32, or .png 16-bit scaled to 0..65535).")
@click.option("--min-confidence", type=CONFIDENCE_LEVEL, default=None, metavar="C",
              help="Mark pixels whose confidence is below C invalid in every output. "
                   "Default: -o stays dense; --depth and --cloud keep pixels at or above "
                   f"{DEFAULT_MIN_CONFIDENCE:g} (0 keeps all).")
@config_option
@max_memory_option
@verbosity_options
@click.pass_context
@friendly_errors
def run(ctx, left, right, output, max_disp, min_disp, calib, focal, baseline, cx, cy,
        doffs, depth_path, cloud_path, max_depth, preview_path, confidence_path,
        min_confidence, config, max_memory):
    """Compute the left-view disparity of a rectified stereo pair.

    \b
    Example:
      vsmatch run imL.png imR.png -o disp.pfm --max-disp 59
      vsmatch run im0.png im1.png -o disp.pfm --calib calib.txt --cloud scene.ply
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
    outputs = [output, depth_path, cloud_path, preview_path, confidence_path]
    for extra in outputs[1:]:
        if extra is not None:
            _check_writable_folder(Path(extra))
    io.check_distinct_paths([left, right, calib], outputs)
    camera = _calibration(calib, focal, baseline, cx, cy, doffs)
    if (depth_path or cloud_path) and camera is None:
        raise click.UsageError("--depth and --cloud need --calib, or --focal and --baseline")
    cfg = _with_budget(load_config(config), max_memory)
    # Refused before anything is decoded: a range a PNG cannot hold, an image too large.
    if max_disp is not None:
        _check_png_range(out, min_disp or 0, max_disp)
    left_image, right_image = io.read_pair(left, right, max_mb=cfg.memory.max_mb,
                                           max_megapixels=cfg.memory.max_megapixels)
    width = left_image.shape[1]
    if max_disp is None and camera is not None:
        ndisp = camera.search_range_for(width)
        if ndisp is not None:
            max_disp = (min_disp or 0) + ndisp - 1
        elif camera.ndisp is not None:
            _verbose(ctx, f"{calib}: ndisp={camera.ndisp} is half the image width or more, "
                          "taken as 'unknown': finding the range from the pair")
    if max_disp is not None and max_disp >= width:
        raise click.BadParameter(f"{max_disp} must be less than the image width ({width})",
                                 param_hint="'--max-disp'")
    if max_disp is None:
        found = _estimate_range(left_image, right_image, left)
        _verbose(ctx, f"{left}: {found.describe()}")
        min_disp = found.min_disp if min_disp is None else min_disp
        max_disp = max(found.max_disp, min_disp + 1)
    else:
        # Given a range, a pair the method cannot see is wrong is still named.
        problem = search_range.pair_problem(search_range.feature_matches(
            left_image, right_image, max_width=search_range.CHECK_WIDTH))
        if problem is not None:
            _echo(ctx, f"warning: {left}: {problem}", err=True)
    min_disp = min_disp or 0
    _check_png_range(out, min_disp, max_disp)
    try:
        pipeline.check_pair(left_image, right_image, max_disp, cfg, min_disp)
    except ValueError as exc:
        raise click.ClickException(f"{left}: {exc}") from None
    _verbose(ctx, f"searching disparities {min_disp}..{max_disp}")
    _announce_compilation(ctx)
    result = pipeline.run(left_image, right_image, max_disp=max_disp, min_disp=min_disp,
                          config=cfg)
    for path in outputs:
        if path is not None:
            io.remove_stale_temporaries(path)
    disp = result.disparity
    if min_confidence is not None:  # every output, the disparity too
        disp = confidence.keep_confident(disp, result.confidence, min_confidence)
    # Depth and clouds keep only what is likely right unless told otherwise.
    metric_disp = confidence.keep_confident(
        result.disparity, result.confidence,
        DEFAULT_MIN_CONFIDENCE if min_confidence is None else min_confidence)
    with io.all_or_none():  # every output of the run, or none of them
        io.write_disparity(out, disp)
        if depth_path is not None:
            io.write_depth(depth_path, geometry.depth_from_disparity(metric_disp, camera))
        if cloud_path is not None:
            points, colours = geometry.point_cloud(metric_disp, left_image, camera,
                                                   max_depth=max_depth)
            io.write_point_cloud(cloud_path, geometry.ply_vertices(points, colours))
            _verbose(ctx, f"{len(points)} points in the cloud (confidence >= "
                          f"{DEFAULT_MIN_CONFIDENCE if min_confidence is None else min_confidence:g}"
                          f"; {int(np.isfinite(result.disparity).sum()) - len(points)} left out)")
        if preview_path is not None:
            io.imwrite_atomic(preview_path, io.colour_disparity(disp, max_disp, min_disp))
        if confidence_path is not None:
            io.write_confidence(confidence_path, result.confidence)
    _report_run(ctx, result)
    for path in outputs:
        if path is not None:
            _echo(ctx, f"wrote {path}")


def _check_png_range(path, min_disp: int, max_disp: int) -> None:
    problem = io.png_range_problem(path, min_disp, max_disp)
    if problem is not None:
        raise click.ClickException(problem)


def _announce_compilation(ctx: click.Context) -> None:
    """One line before the first run compiles the kernels (20-40 s of silence else)."""
    from ._kernels import cache_is_cold

    if cache_is_cold():
        _echo(ctx, "compiling the kernels once (about 30 s; later runs start at once)",
              err=True)


def _check_writable_folder(path: Path) -> None:
    folder = _check_output_folder(path)
    if not _writable(folder):
        raise click.ClickException(f"{path}: output folder '{folder}' is not writable")


def _calibration(calib, focal, baseline, cx, cy, doffs) -> geometry.Calibration | None:
    """The camera from --calib, or from --focal and --baseline, or None."""
    by_hand = {"--focal": focal, "--baseline": baseline, "--cx": cx, "--cy": cy,
               "--doffs": doffs}
    given = [k for k, v in by_hand.items() if v is not None]
    if calib is not None:
        if given:
            raise click.UsageError(f"give --calib or {', '.join(given)}, not both")
        return geometry.read_calibration(calib)
    if not given:
        return None
    if focal is None or baseline is None:
        raise click.UsageError("--focal and --baseline go together")
    return geometry.Calibration(focal=focal, baseline=baseline, cx=cx, cy=cy,
                                doffs=doffs or 0.0)


def _estimate_range(left_image, right_image, name):
    try:
        return search_range.estimate_disparity_range(left_image, right_image)
    except ValueError as exc:
        raise click.ClickException(f"{name}: {exc}") from None


def _report_run(ctx: click.Context, result: pipeline.MatchResult) -> None:
    """Under --verbose: the estimated noise and the stage times."""
    if result.noise_sigma is not None:
        floor = result.config.noise.floor
        action = "adapted" if result.noise_sigma > floor else "no adaptation"
        _verbose(ctx, f"estimated noise: {result.noise_sigma:.2f} grey levels "
                      f"(floor {floor:g}: {action})")
    if result.photometric is not None:
        fit = result.photometric
        _verbose(ctx, f"exposure: matched colours differ by {fit.before:.1f} grey levels, "
                      f"{fit.residual:.1f} after the right view's colour map "
                      f"({fit.matches} pixels); colour term weight "
                      f"{result.config.cost.ad_weight:.2f}")
    if result.levels or result.stripes > 1:
        _verbose(ctx, f"full search {result.levels} pyramid level(s) down, in "
                      f"{result.stripes} stripe(s)")
    times = ", ".join(f"{k} {v:.3f}" for k, v in result.seconds.items())
    _verbose(ctx, f"seconds: {times}; total {sum(result.seconds.values()):.3f}")


@main.command("eval")
@click.option("--dataset", type=click.Choice(list(datasets.DATASETS)),
              default="middlebury2", show_default=True)
@data_root_option
@click.option("--method", "methods", multiple=True, metavar="NAME|PATH",
              help="A bundled config name, a YAML path, or a peer method "
                   f"({', '.join(PEER_METHODS)}); repeat for several rows. "
                   "Default: census, paper and default.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), default=None,
              help="Write the figures as JSON here.")
@click.option("--out-dir", type=click.Path(file_okay=False), default=None,
              help="Save each disparity (PFM, colour PNG) and an error image here.")
@click.option("--figure", "figure_path", type=click.Path(dir_okay=False), default=None,
              help="Write a picture of the results here (.png): a row per scene; the "
                   "left view, the ground truth, and each method's disparity and errors.")
@click.option("--threshold", type=float, default=None,
              help="Middlebury: a pixel is bad when its error exceeds this many pixels "
                   "(default 1.0, and 2.0 for Middlebury 2014). KITTI's D1 is fixed.")
@click.option("--max-disp", "range_mode", type=click.Choice(["official", "auto"]),
              default="official", show_default=True,
              help="Search each scene's official range, or the one estimated from the "
                   "pair as 'vsmatch run' does without --max-disp.")
@click.option("--ablation", is_flag=True,
              help="Instead of --method rows: the refinement chain and the exposure "
                   "correction of the config given by --method (default: 'default') built "
                   "up one stage at a time, then one switch changed at a time (scanline "
                   "directions, shrinking arm threshold, filling, direction factor kappa).")
@click.option("--noise", default=None, metavar="LEVELS",
              help="Also run with Gaussian noise of sigma = level x 255 added to each view, "
                   "e.g. 0.02,0.05,0.10,0.15 (EVALUATION.md).")
@click.option("--seeds", type=click.IntRange(min=1), default=3, show_default=True,
              help="Noise seeds per level; figures are the mean over them.")
@click.pass_context
@friendly_errors
def eval_command(ctx, dataset, data_root, methods, json_path, out_dir, figure_path,
                 threshold, range_mode, ablation, noise, seeds):
    """Score methods on a benchmark with ground truth.

    Middlebury: bad pixels (bad 1.0; bad 2.0 for Middlebury 2014) on nonocc and all
    (and disc); KITTI: D1 (2015) or out-3 (2012). Every measure goes in --json.

    \b
    Example:
      vsmatch eval --dataset middlebury2 --method census --method paper --json t1.json
      vsmatch eval --dataset middlebury2014-quarter --method default --method opencv-sgbm
    """
    from tqdm import tqdm

    if ablation:
        if len(methods) > 1:
            raise click.BadParameter("--ablation takes at most one --method",
                                     param_hint="'--method'")
        configs = evaluation.ablation_configs(load_config(methods[0] if methods else None))
    else:
        # Loading each config first fails before any work on a bad one.
        configs = {m: m if m in PEER_METHODS else load_config(m)
                   for m in (methods or ("census", "paper", "default"))}
    for path in (json_path, figure_path):
        if path is not None:
            _check_output_folder(Path(path))
    if figure_path is not None and Path(figure_path).suffix.lower() != ".png":
        raise click.BadParameter(f"'{figure_path}' must end in .png", param_hint="'--figure'")
    io.check_distinct_paths([], [json_path, figure_path])
    try:
        evaluation.scoring_for(dataset, threshold)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'--threshold'") from None
    levels = _parse_levels(noise)
    scenes = datasets.load_dataset(dataset, data_root)
    ranges = evaluation.scene_ranges(scenes, auto=range_mode == "auto")
    if range_mode == "auto":
        for scene in scenes:
            _verbose(ctx, f"{scene.name}: disparity range {ranges[scene.name][0]}.."
                          f"{ranges[scene.name][1]} (official {scene.min_disp}.."
                          f"{scene.max_disp})")
    quiet = ctx.find_root().obj.get("quiet")
    runs = len(configs) * len(scenes) * (1 + len(levels) * seeds)
    disparities = {} if figure_path is not None else None
    with tqdm(total=runs, disable=quiet, unit="run", leave=False) as bar:
        def done(method: str, scene: str) -> None:
            bar.set_postfix_str(f"{method}/{scene}")
            bar.update(1)
        report = evaluation.evaluate(scenes, configs, dataset=dataset, threshold=threshold,
                                     out_dir=out_dir, on_done=done, ranges=ranges,
                                     disparities=disparities)
        if levels:
            evaluation.evaluate_noise(scenes, configs, report, levels=levels, seeds=seeds,
                                      on_done=done)
    _echo(ctx, evaluation.format_tables(report))
    if levels:
        _echo(ctx, evaluation.format_noise_table(report))
    if json_path is not None:
        io.write_text_atomic(json_path, json.dumps(report, indent=2) + "\n")
        _echo(ctx, f"wrote {json_path}")
    if figure_path is not None:
        from .figure import results_figure

        io.imwrite_atomic(figure_path, results_figure(scenes, report, disparities))
        _echo(ctx, f"wrote {figure_path}")


def _parse_levels(text: str | None) -> list[float]:
    if not text:
        return []
    try:
        levels = [float(v) for v in text.split(",")]
    except ValueError:
        raise click.BadParameter(f"'{text}' is not a comma-separated list of numbers",
                                 param_hint="'--noise'") from None
    if any(not 0 < v <= 1 for v in levels):
        raise click.BadParameter(f"levels must be in (0, 1], got '{text}'",
                                 param_hint="'--noise'")
    return levels


def _check_output_folder(path: Path) -> Path:
    """The folder ``path`` goes in, which must exist."""
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise click.ClickException(f"{path}: output folder '{folder}' does not exist")
    return folder


@main.command("bench")
@data_root_option
@config_option
@click.option("--repeats", type=click.IntRange(min=1), default=5, show_default=True,
              help="Timed runs per pair; the median is reported.")
@click.option("--no-cold", is_flag=True, help="Skip the empty-cache start-up run "
              "(it compiles every kernel, about 15 s).")
@click.option("--no-size", is_flag=True, help="Skip the size series (Adirondack 1x, 2x, "
              "4x, and 4x twice as tall; a few minutes).")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), default=None,
              help="Write the measurements as JSON here.")
@click.pass_context
@friendly_errors
def bench_command(ctx, data_root, config, repeats, no_cold, no_size, json_path):
    """Time vsmatch against OpenCV StereoSGBM (block size 3) on the standard pairs and
    at size.

    Per-stage and total times on the twelve standard pairs (middlebury2 and Middlebury
    2014 at quarter size), SGBM HH timed in the same process on the same images, and
    their ratio; start-up with an empty and a warm compilation cache; the whole 'vsmatch
    run' command; peak memory; the size series: Adirondack upscaled 1x, 2x and 4x
    (2872x1984, 292 disparities), vsmatch against SGBM's 5-direction and HH modes, with
    time, peak memory and accuracy, and vsmatch on the 4x pair made twice as tall (its
    upside-down copy below it): how memory grows with the height.
    """
    from . import bench

    if json_path is not None:
        _check_output_folder(Path(json_path))
    load_config(config)
    report = bench.run_benchmark(data_root, config, repeats, cold=not no_cold,
                                 size=not no_size)
    _echo(ctx, bench.format_report(report))
    if json_path is not None:
        io.write_text_atomic(json_path, json.dumps(report, indent=2) + "\n")
        _echo(ctx, f"wrote {json_path}")


@main.command("batch")
@click.argument("source", type=click.Path())
@click.option("-o", "--out-dir", type=click.Path(file_okay=False), default="vsmatch-out",
              show_default=True, help="For a folder SOURCE: where the disparities go "
              "(created if missing). A CSV names each output itself.")
@click.option("--format", "fmt", type=click.Choice(["pfm", "png"]), default="pfm",
              show_default=True, help="Output format for a folder SOURCE.")
@click.option("--max-disp", type=MAX_DISP, default="auto", show_default=True,
              help="Largest disparity searched, for pairs that do not give their own "
                   "(CSV column 4); 'auto' estimates it from each pair.")
@config_option
@click.option("-j", "--jobs", type=click.IntRange(min=1), default=1, show_default=True,
              help="Pairs matched at once, each in its own process.")
@click.option("--scheduler", default=None, metavar="tcp://HOST:PORT|local:N",
              callback=lambda ctx, param, value: _scheduler_address(value),
              help="Run the pairs on a Dask cluster: a running scheduler's address, or "
                   "local:N to start N worker processes here (pip install "
                   "'vsmatch[cluster]'). Inputs and outputs must be at the same paths on "
                   "every worker.")
@click.option("--overwrite", is_flag=True, help="Match pairs whose output already exists "
              "(only earlier outputs are replaced: an output may never name an input).")
@click.option("--confidence", "with_confidence", is_flag=True,
              help="Also write each pair's confidence beside its disparity "
                   "(NAME_confidence.pfm, float32 in [0, 1]).")
@click.option("--min-confidence", type=CONFIDENCE_LEVEL, default=None, metavar="C",
              help="Mark pixels whose confidence is below C invalid in the disparities.")
@max_memory_option
@verbosity_options
@click.pass_context
@friendly_errors
def batch_command(ctx, source, out_dir, fmt, max_disp, config, jobs, scheduler, overwrite,
                  with_confidence, min_confidence, max_memory):
    """Match every pair listed in a CSV file or found in a folder.

    \b
    A CSV has rows left,right,output[,max_disp] (paths relative to the CSV's folder;
    an optional header row starting with 'left'; max_disp a number or 'auto'). A
    folder holds a recording (image_2/ + image_3/ as KITTI, image_02/data/ +
    image_03/data/ as KITTI raw, colored_0/ + colored_1/, or left/ + right/, frames of
    the same name; each disparity goes to OUT_DIR/FRAME.pfm), or one sub-folder per
    pair (imL/imR, im0/im1, view1/view5 or left/right images), or files NAME_left.png
    and NAME_right.png side by side (OUT_DIR/NAME.pfm).

    Pairs whose output exists are skipped unless --overwrite. A failed pair does not
    stop the others: the failures are listed at the end and the exit status is 1.

    \b
    Example:
      vsmatch batch pairs.csv --jobs 2
      vsmatch batch scenes/ -o disparities --format png --max-disp 100
      vsmatch batch drive/ -o disparities --scheduler tcp://scheduler-host:8786
    """
    from tqdm import tqdm

    cfg = _with_budget(load_config(config), max_memory)
    src = Path(source)
    unpaired = []
    if src.is_dir():
        jobs_list, unpaired = batch.find_pairs(src, out_dir, max_disp=max_disp,
                                               suffix=f".{fmt}")
    elif src.is_file():
        jobs_list = batch.read_pair_list(src, max_disp)
    else:
        raise click.ClickException(f"{src}: no such file or folder")
    if not jobs_list and not unpaired:
        raise click.ClickException(f"{src}: no stereo pairs found")
    batch.check_plan(jobs_list)  # before any work: no output over an input or another output
    if jobs_list and src.is_dir():
        Path(out_dir).mkdir(parents=True, exist_ok=True)
    todo = [j for j in jobs_list if overwrite or not j.output.exists()]
    skipped = len(jobs_list) - len(todo)
    quiet = ctx.find_root().obj.get("quiet")
    failures = []
    if todo:
        _announce_compilation(ctx)
        # The executor first: a cluster that cannot be had fails before any output.
        with make_executor(jobs, scheduler) as executor, \
                tqdm(total=len(todo), disable=quiet, unit="pair", leave=False) as bar:
            def done(job: batch.PairJob, outcome: batch.PairOutcome) -> None:
                bar.set_postfix_str(job.output.name)
                bar.update(1)
                if outcome.error is None and ctx.find_root().obj.get("verbose"):
                    # Through the bar, which would otherwise draw over the line.
                    bar.write(f"{job.describe()}: disparities {outcome.min_disp}.."
                              f"{outcome.max_disp}, {outcome.seconds:.2f} s", file=sys.stderr)
            failures = batch.run_batch(todo, cfg, executor=executor, on_done=done,
                                       with_confidence=with_confidence,
                                       min_confidence=min_confidence)
    total = len(jobs_list) + len(unpaired)
    failed = len(failures) + len(unpaired)
    _echo(ctx, f"matched {len(todo) - len(failures)} of {total} pairs"
               + (f", skipped {skipped} with existing output" if skipped else "")
               + (f", {failed} failed" if failed else ""))
    for path in unpaired:
        click.echo(f"failed: {path}: no frame of the same name in the other view", err=True)
    for job, error in failures:
        click.echo(f"failed: {job.left}: {error}", err=True)
    if failed:
        sys.exit(1)


@main.group("datasets")
def datasets_group():
    """List the benchmarks vsmatch knows, and download them."""


@datasets_group.command("list")
@data_root_option
@click.pass_context
@friendly_errors
def datasets_list(ctx, data_root):
    """Show each known dataset, where it is looked for and whether it is there."""
    roots = datasets.resolve_data_root(data_root)
    existing = [r for r in roots if r.is_dir()] or roots
    _echo(ctx, f"data root: {existing[0].resolve()} (--data-root or VSMATCH_DATA change it)")
    for name, spec in datasets.DATASETS.items():
        try:
            folder = datasets.dataset_folder(name, data_root)
            status = f"found in {folder}"
        except datasets.DatasetError:
            status = f"not found (expected {spec.folder}/ under the data root); get it: " \
                     f"{spec.source}"
        _echo(ctx, f"{name:<25}{status}")


@datasets_group.command("download")
@click.argument("dataset", type=click.Choice(["middlebury2014", "kitti2015", "kitti2012"]))
@click.option("--resolution", type=click.Choice(["Q", "H", "F"]), default="Q",
              show_default=True, help="Middlebury 2014 size: quarter, half or full.")
@click.option("--to", "to", type=click.Path(file_okay=False), required=True,
              help="The data root to put it in (DIR/middlebury2014-quarter/ ...).")
@click.option("--mirror", default=None, metavar="URL",
              help="Fetch the archives from this base URL instead of Middlebury's.")
@click.pass_context
@friendly_errors
def datasets_download(ctx, dataset, resolution, to, mirror):
    """Fetch a benchmark into a data root that 'vsmatch eval --data-root' reads.

    \b
    Example:
      vsmatch datasets download middlebury2014 --resolution Q --to data
      vsmatch eval --dataset middlebury2014-quarter --data-root data
    """
    if dataset != "middlebury2014":
        folder = Path(to) / datasets.DATASETS[dataset].folder
        raise click.ClickException(
            f"{dataset} cannot be downloaded for you: it {datasets.DATASETS[dataset].source}"
            .replace("DIR/", f"{Path(to)}/") + f" (vsmatch reads {folder}/training/)")
    from .datasets.download import download_middlebury2014

    quiet = ctx.find_root().obj.get("quiet")
    folder, fetched = download_middlebury2014(resolution, to, mirror=mirror,
                                              progress=not quiet)
    scenes = sorted(p.name for p in folder.iterdir() if p.is_dir())
    state = "downloaded" if fetched else "already complete"
    _echo(ctx, f"{folder}: {state}, {len(scenes)} training scenes")


@main.command()
@click.option("-o", "--out-dir", type=click.Path(file_okay=False), default="vsmatch-demo",
              show_default=True, help="Folder for the pair, the disparity and the error image.")
@config_option
@click.pass_context
@friendly_errors
def demo(ctx, out_dir, config):
    """Match a synthetic stereo pair made in code, with known disparity.

    Writes left.png, right.png, disparity.pfm, disparity_colour.png and error.png
    (bad pixels red), and prints the bad-pixel percentage. Nothing is downloaded.
    """
    pair = synthetic.make_pair()
    disp = pipeline.match(pair.left, pair.right, max_disp=pair.max_disp, config=config)
    folder = Path(out_dir)
    folder.mkdir(parents=True, exist_ok=True)
    io.imwrite_atomic(folder / "left.png", pair.left)
    io.imwrite_atomic(folder / "right.png", pair.right)
    io.write_disparity(folder / "disparity.pfm", disp)
    io.imwrite_atomic(folder / "disparity_colour.png", io.colour_disparity(disp, pair.max_disp))
    bad = evaluation.bad_pixel_map(disp, pair.disparity, 1.0)
    io.imwrite_atomic(folder / "error.png",
                      io.error_image(disp, bad, pair.nonocc, pair.max_disp))
    percent = evaluation.bad_percent(disp, pair.disparity, pair.nonocc, 1.0)
    _echo(ctx, f"synthetic pair {pair.left.shape[1]}x{pair.left.shape[0]}, disparities "
               f"0..{pair.max_disp}: {percent:.2f} % bad pixels (error > 1 px, non-occluded)")
    _echo(ctx, f"outputs in {folder}/")
