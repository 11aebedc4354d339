"""``vsmatch batch``: many pairs from a CSV list or a folder."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from .. import batch
from ..config import DEFAULT_CONFIG_NAME, load_config
from ..executors import make_executor
from .common import (CONFIDENCE_LEVEL, MAX_DISP, announce_compilation, config_option, echo,
                     examples, friendly_errors, given, max_memory_option, scheduler_address,
                     verbosity_options, with_budget)

from .main import main


@main.command("batch", epilog=examples(
    "vsmatch batch pairs.csv --jobs 2",
    "vsmatch batch scenes/ -o disparities --format png --max-disp 100",
    "vsmatch batch drive/ -o disparities --scheduler local:2"))
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
              callback=lambda ctx, param, value: scheduler_address(value),
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
    """
    from tqdm import tqdm

    if scheduler is not None and given(ctx, "jobs"):
        raise click.UsageError("--jobs is for this machine's processes; a --scheduler "
                               "cluster runs as many pairs at once as it has workers")
    cfg = with_budget(load_config(config), max_memory)
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
    # Before any work: no output over an input, the pair list or another output, every
    # output a .pfm or .png in a folder that can be written, and no file that an earlier
    # run did not write replaced without --overwrite.
    batch.check_plan(jobs_list, with_confidence=with_confidence,
                     sources=() if src.is_dir() else (src,))
    missing_folders = batch.check_output_files(jobs_list)
    todo = [j for j in jobs_list if overwrite or not j.output.exists()]
    if not overwrite:
        for job in todo:
            for path in batch.job_outputs(job, with_confidence)[1:]:
                if path.exists():
                    raise click.ClickException(
                        f"{job.describe()}: {path} exists but {job.output} does not: it is "
                        "not this batch's output (--overwrite replaces it)")
    skipped = len(jobs_list) - len(todo)
    quiet = ctx.find_root().obj.get("quiet")
    failures = []
    if todo:
        # A pair without a range finds it with the default config's match first.
        finding = any(job.max_disp is None for job in todo)
        announce_compilation(ctx, config, also=(DEFAULT_CONFIG_NAME,) if finding else ())
        # The executor first: a cluster that cannot be had fails before any output.
        with make_executor(jobs, scheduler) as executor, \
                tqdm(total=len(todo), disable=True if quiet else None, unit="pair",
                     leave=False) as bar:  # a bar in a terminal only (None): a log gets none
            # The output folders once the executor is had: a cluster that cannot be
            # reached leaves none behind.
            for folder in missing_folders:
                folder.mkdir(parents=True, exist_ok=True)
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
    echo(ctx, f"matched {len(todo) - len(failures)} of {total} pairs"
               + (f", skipped {skipped} with existing output (--overwrite matches them "
                  "again)" if skipped else "")
               + (f", {failed} failed" if failed else ""))
    for path in unpaired:
        click.echo(f"failed: {path}: no frame of the same name in the other view", err=True)
    for job, error in failures:
        click.echo(f"failed: {job.left}: {error}", err=True)
    if failed:
        sys.exit(1)
