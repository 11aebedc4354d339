"""``vsmatch eval``: score methods on a benchmark with ground truth."""

from __future__ import annotations

import json
from pathlib import Path

import click

from .. import datasets, evaluation, io
from ..config import load_config
from ..peers import PEER_METHODS
from .common import (POSITIVE, add_note, check_new_folder, check_outputs, check_outside,
                     data_root_option, echo, examples, friendly_errors, verbose,
                     verbosity_options)

from .main import main


@main.command("eval", epilog=examples(
    "vsmatch eval --dataset middlebury2 --method paper --method default",
    "vsmatch eval --dataset middlebury2014-quarter --method default --method opencv-sgbm",
    "vsmatch eval --dataset middlebury2 --noise 0.02,0.05,0.10,0.15 --seeds 3"))
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
              help="Save each disparity (PFM, colour PNG) and an error image here, a "
                   "folder a method (named after it; numbered where two names meet).")
@click.option("--overwrite", is_flag=True,
              help="Write into method folders of --out-dir that already hold files.")
@click.option("--figure", "figure_path", type=click.Path(dir_okay=False), default=None,
              help="Write a picture of the results here (.png): a row per scene; the "
                   "left view, the ground truth, and each method's disparity and errors.")
@click.option("--threshold", type=POSITIVE, default=None,
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
@verbosity_options
@click.pass_context
@friendly_errors
def eval_command(ctx, dataset, data_root, methods, json_path, out_dir, overwrite, figure_path,
                 threshold, range_mode, ablation, noise, seeds):
    """Score methods on a benchmark with ground truth.

    Middlebury: bad pixels (bad 1.0; bad 2.0 for Middlebury 2014) on nonocc and all
    (and disc); KITTI: D1 (2015) or out-3 (2012). Every measure goes in --json.
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
    if figure_path is not None and Path(figure_path).suffix.lower() != ".png":
        raise click.BadParameter(f"'{figure_path}' must end in .png", param_hint="'--figure'")
    check_outputs([], [json_path, figure_path])
    try:
        evaluation.scoring_for(dataset, threshold)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'--threshold'") from None
    levels = _parse_levels(noise)
    # Nothing is written into the data set that is read.
    check_outside(datasets.dataset_folder(dataset, data_root),
                  [json_path, figure_path, out_dir], "data set")
    if out_dir is not None:
        check_new_folder(Path(out_dir))  # a read-only one is said before the matching
        _check_method_folders(ctx, Path(out_dir), list(configs), data_root, overwrite)
    scenes = datasets.load_dataset(dataset, data_root)
    ranges = evaluation.scene_ranges(scenes, auto=range_mode == "auto")
    if range_mode == "auto":
        for scene in scenes:
            verbose(ctx, f"{scene.name}: disparity range {ranges[scene.name][0]}.."
                          f"{ranges[scene.name][1]} (official {scene.min_disp}.."
                          f"{scene.max_disp})")
    quiet = ctx.find_root().obj.get("quiet")
    runs = len(configs) * len(scenes) * (1 + len(levels) * seeds)
    disparities = {} if figure_path is not None else None
    # A bar in a terminal only (None): a log file gets no carriage returns.
    with tqdm(total=runs, disable=True if quiet else None, unit="run", leave=False) as bar, \
            io.output_folder(out_dir):
        def done(method: str, scene: str) -> None:
            bar.set_postfix_str(f"{method}/{scene}")
            bar.update(1)
        try:
            report = evaluation.evaluate(scenes, configs, dataset=dataset,
                                         threshold=threshold, out_dir=out_dir, on_done=done,
                                         ranges=ranges, disparities=disparities)
        except (KeyboardInterrupt, Exception) as exc:
            # What is written stays (each file whole): say so, rather than leave a
            # half-filled folder without a word.
            if out_dir is not None and any(p.is_file() for p in Path(out_dir).rglob("*")):
                add_note(exc, f"--out-dir {out_dir} holds only the runs that finished "
                              "(each file whole)")
            raise
        if levels:
            evaluation.evaluate_noise(scenes, configs, report, levels=levels, seeds=seeds,
                                      on_done=done)
    # The results are the command's output: printed under --quiet too (which quiets the
    # progress and the notes).
    click.echo(evaluation.format_tables(report))
    if levels:
        click.echo(evaluation.format_noise_table(report))
    if json_path is not None:
        io.write_text_atomic(json_path, json.dumps(report, indent=2) + "\n")
        echo(ctx, f"wrote {json_path}")
    if figure_path is not None:
        from ..figure import results_figure

        io.imwrite_atomic(figure_path, results_figure(scenes, report, disparities))
        echo(ctx, f"wrote {figure_path}")


def _check_method_folders(ctx, out_dir: Path, methods: list[str], data_root,
                          overwrite: bool) -> None:
    """Before any work: no method's folder inside a data set of the data root (a method
    named after one would write into it), and none that holds files unless
    ``overwrite``; each method's folder said where names met."""
    folders = evaluation.method_folders(methods)
    for name in datasets.DATASETS:
        try:
            data = io.resolved(datasets.dataset_folder(name, data_root))
        except datasets.DatasetError:
            continue
        for method, folder in folders.items():
            if io.resolved(out_dir / folder).is_relative_to(data):
                raise click.ClickException(f"--out-dir {out_dir}: method {method}'s folder "
                                           f"{out_dir / folder} lies in the data set {name} "
                                           "(read, never written); give another --out-dir")
    for method, folder in folders.items():
        path = out_dir / folder
        if path.is_dir() and any(path.iterdir()) and not overwrite:
            raise click.ClickException(f"--out-dir {out_dir}: {path} (method {method}) "
                                       "already holds files; --overwrite writes over them, "
                                       "or give another --out-dir")
        if folder != evaluation.safe_name(method):
            echo(ctx, f"method {method}: its outputs in {path} (another method's name "
                      "takes the plain folder)")


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
