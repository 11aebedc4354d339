"""``vsmatch datasets``: the benchmarks vsmatch knows, and their download."""

from __future__ import annotations

from pathlib import Path

import click

from .. import datasets
from .common import data_root_option, echo, examples, friendly_errors, verbosity_options

from .main import main


@main.group("datasets", epilog=examples(
    "vsmatch datasets list",
    "vsmatch datasets download middlebury2014 --resolution Q --to data"))
def datasets_group():
    """List the benchmarks vsmatch knows, and download them."""


@datasets_group.command("list", epilog=examples(
    "vsmatch datasets list",
    "vsmatch datasets list --data-root data"))
@data_root_option
@verbosity_options
@click.pass_context
@friendly_errors
def datasets_list(ctx, data_root):
    """Show each known dataset, where it is looked for and whether it is there."""
    roots = datasets.resolve_data_root(data_root)
    existing = [r for r in roots if r.is_dir()] or roots
    echo(ctx, f"data root: {existing[0].resolve()} (--data-root or VSMATCH_DATA change it)")
    for name, spec in datasets.DATASETS.items():
        try:
            folder = datasets.dataset_folder(name, data_root)
            status = f"found in {folder}"
        except datasets.DatasetError:
            status = f"not found (expected {spec.folder}/ under the data root); get it: " \
                     f"{spec.source}"
        echo(ctx, f"{name:<25}{status}")


@datasets_group.command("download", epilog=examples(
    "vsmatch datasets download middlebury2014 --resolution Q --to data",
    "vsmatch datasets download middlebury2014 --to data --mirror https://example.org/mev3/"))
@click.argument("dataset", type=click.Choice(["middlebury2014", "kitti2015", "kitti2012"]))
@click.option("--resolution", type=click.Choice(["Q", "H", "F"]), default="Q",
              show_default=True, help="Middlebury 2014 size: quarter, half or full.")
@click.option("--to", "to", type=click.Path(file_okay=False), required=True,
              help="The data root to put it in (DIR/middlebury2014-quarter/ ...).")
@click.option("--mirror", default=None, metavar="URL|FOLDER",
              help="Fetch the archives from this base URL instead of Middlebury's, or copy "
                   "them from this folder (or file:// URL).")
@verbosity_options
@click.pass_context
@friendly_errors
def datasets_download(ctx, dataset, resolution, to, mirror):
    """Fetch a benchmark into a data root that 'vsmatch eval --data-root' reads.
    """
    if dataset != "middlebury2014":
        folder = Path(to) / datasets.DATASETS[dataset].folder
        raise click.ClickException(
            f"{dataset} cannot be downloaded for you: it {datasets.DATASETS[dataset].source}"
            .replace("DIR/", f"{Path(to)}/") + f" (vsmatch reads {folder}/training/)")
    from ..datasets.download import download_middlebury2014

    quiet = ctx.find_root().obj.get("quiet")
    folder, fetched = download_middlebury2014(resolution, to, mirror=mirror,
                                              progress=not quiet)
    scenes = sorted(p.name for p in folder.iterdir() if p.is_dir())
    state = "downloaded" if fetched else "already complete"
    echo(ctx, f"{folder}: {state}, {len(scenes)} training scenes")
