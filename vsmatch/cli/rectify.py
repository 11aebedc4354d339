"""``vsmatch rectify``: a raw rig's pair rectified, with the rectified rig's calib.txt."""

from __future__ import annotations

from pathlib import Path

import click

from .. import io, rig
from .common import (ALPHA, check_outputs, echo, examples, friendly_errors, verbose,
                     verbosity_options)

from .main import main
from .run import rectified_outputs, write_rectified


@main.command(epilog=examples(
    "vsmatch rectify raw_l.png raw_r.png --calib stereo.yaml --to rect/",
    "vsmatch rectify l.png r.png --calib left.yaml --calib right.yaml --to rect/"))
@click.argument("left", type=click.Path(dir_okay=False))
@click.argument("right", type=click.Path(dir_okay=False))
@click.option("--calib", type=click.Path(dir_okay=False), multiple=True, required=True,
              help="The raw rig: an OpenCV stereoCalibrate YAML/XML, a Kalibr "
                   "camchain.yaml, or a ROS camera_info or EuRoC sensor.yaml pair (--calib "
                   "left.yaml --calib right.yaml).")
@click.option("--to", "folder", type=click.Path(file_okay=False), required=True,
              help="Folder for im0.png, im1.png and calib.txt (created if missing).")
@click.option("--alpha", type=ALPHA, default=0.0, show_default=True,
              help="OpenCV's rectification alpha: 0 keeps only valid pixels, 1 every "
                   "source pixel.")
@verbosity_options
@click.pass_context
@friendly_errors
def rectify(ctx, left, right, calib, folder, alpha):
    """Rectify a raw stereo pair: im0.png, im1.png and a Middlebury-style calib.txt of
    the rectified rig, which 'vsmatch run --calib' reads.
    """
    check_outputs([left, right, *calib], [], folders=rectified_outputs(folder))
    raw_rig = rig.read_rig(calib)
    left_image, right_image = io.read_pair(left, right)
    rectifier = rig.Rectifier(raw_rig, left_image.shape[1::-1], alpha)
    left_image, right_image = rectifier.rectify(left_image, right_image)
    camera = rectifier.calibration()
    verbose(ctx, f"rectified: f {camera.focal:.1f} px, baseline {camera.baseline:g}, "
                 f"principal point ({camera.cx:.1f}, {camera.cy:.1f})")
    with io.output_folder(folder):
        write_rectified(folder, left_image, right_image, camera, None)
    echo(ctx, f"wrote {Path(folder) / 'im0.png'}, im1.png, calib.txt")
