"""The ``vsmatch`` group: global options, and the SIGTERM handler."""

from __future__ import annotations

import signal
import sys
import threading

import click

from .. import __version__
from .common import (STOPS, TERMINATING, OneLineErrors, examples, on_sigint, on_sigterm,
                     quiet_unraisable_stops)


@click.group(cls=OneLineErrors, context_settings={"help_option_names": ["-h", "--help"]},
             epilog=examples("vsmatch demo",
                             "vsmatch run left.png right.png -o disp.pfm --preview disp.png",
                             "vsmatch run --help"))
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
        STOPS.clear()  # a command run before in this process (tests) is over
        for number in TERMINATING:  # SIGTERM, and what a closing terminal sends
            signal.signal(number, on_sigterm)
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            signal.signal(signal.SIGINT, on_sigint)
        if not getattr(sys.unraisablehook, "quiet_stops", False):
            sys.unraisablehook = quiet_unraisable_stops(sys.unraisablehook)


def _silence_opencv() -> None:
    """Keep OpenCV's decoders (libpng, ...) from printing beside our one-line errors."""
    import cv2

    try:
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    except AttributeError:  # an OpenCV build without the logging module
        pass
