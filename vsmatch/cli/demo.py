"""``vsmatch demo``: a synthetic pair made in code, matched and scored."""

from __future__ import annotations

from pathlib import Path

import click

from .. import evaluation, io, pipeline, synthetic
from .common import (announce_compilation, config_option, echo, examples, friendly_errors,
                     verbosity_options)

from .main import main


@main.command(epilog=examples(
    "vsmatch demo",
    "vsmatch demo -o /tmp/demo"))
@click.option("-o", "--out-dir", type=click.Path(file_okay=False), default="vsmatch-demo",
              show_default=True, help="Folder for the pair, the disparity and the error image.")
@config_option
@verbosity_options
@click.pass_context
@friendly_errors
def demo(ctx, out_dir, config):
    """Match a synthetic stereo pair made in code, with known disparity.

    Writes left.png, right.png, disparity.pfm, disparity_colour.png and error.png
    (bad pixels red), and prints the bad-pixel percentage. Nothing is downloaded.
    """
    pair = synthetic.make_pair()
    announce_compilation(ctx)
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
    echo(ctx, f"synthetic pair {pair.left.shape[1]}x{pair.left.shape[0]}, disparities "
               f"0..{pair.max_disp}: {percent:.2f} % bad pixels (error > 1 px, non-occluded)")
    echo(ctx, f"outputs in {folder}/")
