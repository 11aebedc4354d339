"""``vsmatch bench``: time vsmatch against OpenCV StereoSGBM."""

from __future__ import annotations

import json

import click

from .. import datasets, io
from ..config import bundled_config_names, load_config
from .common import (check_outputs, check_outside, data_root_option, echo, examples,
                     friendly_errors, verbosity_options)

from .main import main


@main.command("bench", epilog=examples(
    "vsmatch bench",
    "vsmatch bench --config default --config fast --json bench.json --plot pareto.png",
    "vsmatch bench --threads 1,2 --no-cold --no-size"))
@data_root_option
@click.option("--config", "configs", multiple=True, metavar="NAME|PATH",
              help="A config to time (repeatable): a bundled one "
                   f"({', '.join(bundled_config_names())}) or a YAML file. "
                   "Default: fast and default.")
@click.option("--rounds", "--repeats", "rounds", type=click.IntRange(min=1), default=5,
              show_default=True, help="Alternating rounds per pair; the fastest of each "
                                      "method is kept.")
@click.option("--no-cold", is_flag=True, help="Skip the empty-cache start-up run "
              "(it compiles every kernel the config calls, 50-60 s on 2 cores).")
@click.option("--no-size", is_flag=True, help="Skip the size series (Adirondack, a KITTI "
              "frame, 1.5 megapixels, 4x and 4x twice as tall; several minutes).")
@click.option("--threads", "threads", default=None, metavar="N[,N...]",
              help="Time the standard pairs at each of these thread counts (Numba's and "
                   "OpenCV's both, taken in turn within every round), with each config's "
                   "speed-up and each stage's: e.g. 1,2 or 1,2,16. Default: the threads as "
                   "set (NUMBA_NUM_THREADS, all cores).")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), default=None,
              help="Write the measurements as JSON here.")
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), default=None,
              help="Draw time against error on the twelve pairs, each config and SGBM "
                   "mode a point (PNG).")
@verbosity_options
@click.pass_context
@friendly_errors
def bench_command(ctx, data_root, configs, rounds, no_cold, no_size, threads, json_path,
                  plot_path):
    """Time vsmatch's configs against OpenCV StereoSGBM (block size 3) on the standard
    pairs and at size.

    On the standard pairs (middlebury2 and Middlebury 2014 at quarter size): each
    config and SGBM's 5-direction, HH and 3-way modes in one process, alternating, the
    fastest of the rounds; their ratios to SGBM HH and 5-direction, each one's error on
    the pairs, and each config's stage times. Then, for the first config: start-up with
    an empty and a warm compilation cache, the whole 'vsmatch run' command and peak
    memory; and the size series: Adirondack (718x496), a KITTI frame (1242x375, 192
    disparities), Adirondack at 1.5 megapixels and at 4x (2872x1984, 292 disparities),
    each config against SGBM's 5-direction and HH modes with time, peak memory and
    accuracy, and the 4x pair made twice as tall: how memory grows with the height.
    """
    from .. import bench

    check_outputs([], [json_path, plot_path])
    counts = None if threads is None else thread_counts(threads, bench.max_threads())
    for name in {*bench.STANDARD_DATASETS, *(entry[1] for entry in bench.SIZE_SERIES)}:
        try:
            folder = datasets.dataset_folder(name, data_root)
        except datasets.DatasetError:
            continue  # one that is not there is not read (or fails on its own later)
        check_outside(folder, [json_path, plot_path], "data set")
    if plot_path is not None and not plot_path.lower().endswith(".png"):
        raise click.BadParameter("the plot is written as PNG: name a .png file",
                                 param_hint="--plot")
    configs = configs or bench.BENCH_CONFIGS
    for config in configs:
        load_config(config)
    from tqdm import tqdm

    quiet = ctx.find_root().obj.get("quiet")
    # Several minutes in all: a bar in a terminal (None: none in a log file).
    with tqdm(disable=True if quiet else None, unit="step", leave=False) as bar:
        def done(name: str) -> None:
            bar.set_postfix_str(name)
            bar.update(1)

        def total(count: int) -> None:
            bar.total = count
            bar.refresh()

        report = bench.run_benchmark(data_root, configs, rounds, cold=not no_cold,
                                     size=not no_size, threads=counts, on_done=done,
                                     on_total=total)
    echo(ctx, bench.format_report(report))
    if json_path is not None:
        io.write_text_atomic(json_path, json.dumps(report, indent=2) + "\n")
        echo(ctx, f"wrote {json_path}")
    if plot_path is not None:
        io.imwrite_atomic(plot_path, bench.tradeoff_figure(report))
        echo(ctx, f"wrote {plot_path}")


def thread_counts(text: str, most: int) -> list[int]:
    """``--threads``' comma-separated counts, each between 1 and ``most``, in order, once."""
    counts = []
    for part in text.split(","):
        try:
            count = int(part)
        except ValueError:
            raise click.BadParameter(f"{part.strip()!r} is not a thread count: give whole "
                                     f"numbers separated by commas, e.g. 1,2",
                                     param_hint="--threads") from None
        if not 1 <= count <= most:
            raise click.BadParameter(
                f"{count} threads: this process can use 1 to {most} (NUMBA_NUM_THREADS; "
                f"the machine's cores unless set)", param_hint="--threads")
        if count not in counts:
            counts.append(count)
    return counts
