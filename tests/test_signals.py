"""Signals that Python could lose: a SIGTERM or Ctrl-C whose exception is raised inside a
ctypes callback (Numba's compiler calls back into Python while it compiles) is reported as
unraisable and dropped; the run must still stop, in one line, with no output."""

import subprocess
import sys

import cv2
import pytest

from conftest import random_pair

STOP_IN_A_CALLBACK = """
import ctypes, os, signal, sys, time
from vsmatch import pipeline
real = pipeline.run
def run(*args, **kwargs):
    def inside():  # as Numba's LLVM callbacks run: Python code called from C
        os.kill(os.getpid(), getattr(signal, os.environ["STOP_SIGNAL"]))
        time.sleep(0.2)
    ctypes.CFUNCTYPE(None)(inside)()
    sys.stderr.write("the callback's exception was lost\\n")
    return real(*args, **kwargs)
pipeline.run = run
from vsmatch.cli import main
main(sys.argv[1:])
"""


@pytest.mark.parametrize("name, code, line", [("SIGTERM", 143, "vsmatch: terminated"),
                                              ("SIGINT", 130, "vsmatch: interrupted")])
def test_a_signal_lost_in_a_callback_still_stops_the_run(tmp_path, rng, name, code, line):
    import os

    left, right = random_pair(rng, height=40, width=60, shift=3)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    proc = subprocess.run([sys.executable, "-c", STOP_IN_A_CALLBACK, "run",
                           str(tmp_path / "l.png"), str(tmp_path / "r.png"), "-o",
                           str(tmp_path / "d.pfm"), "--max-disp", "8"],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "STOP_SIGNAL": name})
    lines = proc.stderr.strip().splitlines()
    assert lines[0] == "the callback's exception was lost", proc.stderr  # the case at hand
    assert proc.returncode == code, proc.stderr
    assert lines[1:] == [line], proc.stderr  # no "Exception ignored", no traceback
    assert not (tmp_path / "d.pfm").exists()
