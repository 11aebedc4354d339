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


@pytest.mark.parametrize("name, code, line", [
    ("SIGTERM", 143, "vsmatch: terminated"), ("SIGINT", 130, "vsmatch: interrupted"),
    ("SIGHUP", 129, "vsmatch: hung up (the terminal closed)"), ("SIGQUIT", 131, "vsmatch: quit")])
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


def write_two_videos(folder, rng, frames=3):
    left, right = random_pair(rng, height=48, width=80, shift=4)
    paths = []
    for name, view in (("l", left), ("r", right)):
        writer = cv2.VideoWriter(str(folder / f"{name}.avi"), cv2.VideoWriter_fourcc(*"MJPG"),
                                 10, (80, 48))
        for _ in range(frames):
            writer.write(view)
        writer.release()
        paths.append(folder / f"{name}.avi")
    return paths


@pytest.mark.parametrize("name, code", [("SIGHUP", 129), ("SIGQUIT", 131)])
def test_a_closed_terminal_stops_a_video_leaving_no_temporaries(tmp_path, rng, name, code):
    """SIGHUP (a closed terminal or SSH session) and SIGQUIT mid-video left the staged
    frames folder and the video's temporary; they are handled as SIGTERM is."""
    import os

    left, right = write_two_videos(tmp_path, rng)
    proc = subprocess.run([sys.executable, "-c", STOP_IN_A_CALLBACK, "video", str(left),
                           str(right), "-o", str(tmp_path / "d.avi"), "--frames",
                           str(tmp_path / "fr"), "--max-disp", "8"],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "STOP_SIGNAL": name})
    assert proc.returncode == code, proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["l.avi", "r.avi"], proc.stderr


def test_what_a_killed_video_left_is_removed_by_the_next_run(tmp_path, rng):
    """After a SIGKILL nothing can clean up: the next run of the same outputs removes the
    temporaries of the earlier one (the video's and the staged frames folder), and nothing
    else."""
    from click.testing import CliRunner

    from vsmatch.cli import main

    left, right = write_two_videos(tmp_path, rng)
    (tmp_path / ".d.k3j4h2g1.tmp.avi").write_bytes(b"half a video")
    (tmp_path / ".fr.a8b7c6d5.tmp").mkdir()
    (tmp_path / ".fr.a8b7c6d5.tmp" / "000000.pfm").write_bytes(b"half a frame")
    (tmp_path / ".d.mine.tmp.avi").write_bytes(b"a user's file of another pattern")
    result = CliRunner().invoke(main, ["video", str(left), str(right), "-o",
                                       str(tmp_path / "d.avi"), "--frames",
                                       str(tmp_path / "fr"), "--max-disp", "8"])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        ".d.mine.tmp.avi", "d.avi", "fr", "l.avi", "r.avi"]
    # Each is named as it goes.
    for name in (".d.k3j4h2g1.tmp.avi", ".fr.a8b7c6d5.tmp"):
        assert f"removed {tmp_path / name}, left by an earlier run that was killed" \
            in result.output


def test_after_a_stop_a_finalizers_failure_is_not_reported():
    """A signal that lands inside a finalizer's teardown (llvmlite's ObjectRef, half
    closed) fails again as Python shuts down: after a stop, that is not reported; before
    one, an unraisable exception still is."""
    from types import SimpleNamespace

    from vsmatch.cli import common

    seen = []
    hook = common.quiet_unraisable_stops(seen.append)
    failure = SimpleNamespace(exc_type=AttributeError, exc_value=AttributeError("x"),
                              exc_traceback=None, err_msg=None, object=None)
    saved = list(common.STOPS)
    try:
        common.STOPS.clear()
        hook(failure)
        assert seen == [failure]
        common.STOPS.append(15)
        hook(failure)
        assert seen == [failure]
        hook(SimpleNamespace(exc_type=KeyboardInterrupt, exc_value=None, exc_traceback=None,
                             err_msg=None, object=None))
        assert seen == [failure]
    finally:
        common.STOPS[:] = saved

