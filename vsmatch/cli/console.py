"""The ``vsmatch`` console script. Loading the commands takes a moment (Numba, OpenCV):
Ctrl-C or SIGTERM meanwhile is one line too, as everywhere else."""

from __future__ import annotations

import signal
import sys


def _terminated(signum, frame):
    raise KeyboardInterrupt("terminated")


def main() -> None:
    previous = signal.signal(signal.SIGTERM, _terminated)
    try:
        from . import load_group

        group = load_group()
    except KeyboardInterrupt as exc:
        terminated = str(exc) == "terminated"
        sys.stderr.write(f"vsmatch: {'terminated' if terminated else 'interrupted'}\n")
        sys.exit(143 if terminated else 130)
    finally:
        signal.signal(signal.SIGTERM, previous)
    group()
