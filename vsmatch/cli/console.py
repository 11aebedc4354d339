"""The ``vsmatch`` console script. Loading the commands takes a moment (Numba, OpenCV):
Ctrl-C or SIGTERM meanwhile is one line too, as everywhere else."""

from __future__ import annotations

import signal
import sys


#: The signals besides Ctrl-C that stop the loading, their lines (as ``cli.common``'s).
_STOPPING = {getattr(signal, name): said for name, said in (
    ("SIGTERM", "terminated"), ("SIGHUP", "hung up (the terminal closed)"),
    ("SIGQUIT", "quit")) if hasattr(signal, name)}


def _terminated(signum, frame):
    raise KeyboardInterrupt(signum)


def main() -> None:
    previous = {number: signal.signal(number, _terminated) for number in _STOPPING}
    try:
        from . import load_group

        group = load_group()
    except KeyboardInterrupt as exc:
        number = exc.args[0] if exc.args and exc.args[0] in _STOPPING else None
        sys.stderr.write(f"vsmatch: {_STOPPING[number] if number else 'interrupted'}\n")
        sys.exit(128 + int(number) if number else 130)
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
    group()
