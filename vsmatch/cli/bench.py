"""``vsmatch bench``: time vsmatch against OpenCV StereoSGBM."""

from __future__ import annotations

import json
from pathlib import Path

import click

from .. import io
from ..config import load_config
from .common import (check_output_folder, config_option, data_root_option, echo,
                     friendly_errors, verbosity_options)

from .main import main


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
@verbosity_options
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
    from .. import bench

    if json_path is not None:
        check_output_folder(Path(json_path))
    load_config(config)
    report = bench.run_benchmark(data_root, config, repeats, cold=not no_cold,
                                 size=not no_size)
    echo(ctx, bench.format_report(report))
    if json_path is not None:
        io.write_text_atomic(json_path, json.dumps(report, indent=2) + "\n")
        echo(ctx, f"wrote {json_path}")
