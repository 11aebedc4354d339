"""The ``vsmatch`` console script. Loading the commands takes a moment (Numba, OpenCV):
Ctrl-C or SIGTERM meanwhile is one line too, as everywhere else."""

from __future__ import annotations

import signal
import sys


#: The signals that stop a program besides Ctrl-C, each handled as SIGTERM is (its
#: temporaries removed, one line, exit 128 + its number), and their lines: a kill, a closed
#: terminal or SSH session (SIGHUP), Ctrl-backslash (SIGQUIT). Here, where the console
#: script needs them before the commands (and Numba, OpenCV) are loaded; ``cli.common``
#: handles them from there on.
TERMINATING = {getattr(signal, name): said for name, said in (
    ("SIGTERM", "terminated"), ("SIGHUP", "hung up (the terminal closed)"),
    ("SIGQUIT", "quit")) if hasattr(signal, name)}


def _terminated(signum, frame):
    raise KeyboardInterrupt(signum)


def main() -> None:
    previous = {number: signal.signal(number, _terminated) for number in TERMINATING}
    try:
        from . import load_group

        group = load_group()
    except KeyboardInterrupt as exc:
        number = exc.args[0] if exc.args and exc.args[0] in TERMINATING else None
        sys.stderr.write(f"vsmatch: {TERMINATING[number] if number else 'interrupted'}\n")
        sys.exit(128 + int(number) if number else 130)
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
    group()
