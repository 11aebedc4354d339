"""``vsmatch demo``: a synthetic pair made in code, matched and scored."""

from __future__ import annotations

from pathlib import Path

import click

from .. import compilation, evaluation, io, pipeline, preview, synthetic
from ..config import load_config
from .common import (announce_compilation, check_new_folder, config_option, echo, examples,
                     friendly_errors, verbosity_options)

from .main import main


#: What the demo writes into its folder; the last names the folder as the demo's.
DEMO_FILES = ("left.png", "right.png", "disparity.pfm", "disparity_colour.png", "error.png")
MARKER = "vsmatch-demo.txt"


@main.command(epilog=examples(
    "vsmatch demo",
    "vsmatch demo -o /tmp/demo"))
@click.option("-o", "--out-dir", type=click.Path(file_okay=False), default="vsmatch-demo",
              show_default=True, help="Folder for the pair, the disparity and the error image.")
@click.option("--overwrite", is_flag=True, help="Replace files of the demo's names in a "
              "folder that an earlier demo did not make.")
@config_option
@verbosity_options
@click.pass_context
@friendly_errors
def demo(ctx, out_dir, overwrite, config):
    """Match a synthetic stereo pair made in code, with known disparity.

    Writes left.png, right.png, disparity.pfm, disparity_colour.png and error.png
    (bad pixels red), and prints the bad-pixel percentage. Nothing is downloaded.
    """
    folder = Path(out_dir)
    check_new_folder(folder)
    if not overwrite and not (folder / MARKER).is_file():
        for name in DEMO_FILES:
            if (folder / name).exists():
                raise click.ClickException(
                    f"{folder / name}: exists and an earlier demo did not write it "
                    "(--overwrite replaces it, or give another -o)")
    pair = synthetic.make_pair()
    announce_compilation(ctx, config, bands=compilation.searches_bands(
        load_config(config), pair.left.shape, 0, pair.max_disp))
    disp = pipeline.match(pair.left, pair.right, max_disp=pair.max_disp, config=config)
    bad = evaluation.bad_pixel_map(disp, pair.disparity, 1.0)
    percent = evaluation.bad_percent(disp, pair.disparity, pair.nonocc, 1.0)
    summary = (f"synthetic pair {pair.left.shape[1]}x{pair.left.shape[0]}, disparities "
               f"0..{pair.max_disp}: {percent:.2f} % bad pixels (error > 1 px, non-occluded)")
    with io.output_folder(folder), io.all_or_none():
        io.imwrite_atomic(folder / "left.png", pair.left)
        io.imwrite_atomic(folder / "right.png", pair.right)
        io.write_disparity(folder / "disparity.pfm", disp)
        io.imwrite_atomic(folder / "disparity_colour.png",
                          preview.colour_disparity(disp, pair.max_disp))
        io.imwrite_atomic(folder / "error.png",
                          preview.error_image(disp, bad, pair.nonocc, pair.max_disp))
        io.write_text_atomic(folder / MARKER, f"Written by 'vsmatch demo': "
                             f"{', '.join(DEMO_FILES)}.\n{summary}\n")
    echo(ctx, summary)
    echo(ctx, f"outputs in {folder}")
