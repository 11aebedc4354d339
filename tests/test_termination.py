"""SIGTERM, a second SIGTERM and a closed pipe: the run ends in one line, outputs whole or
absent."""

import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import pytest
from cli_helpers import files_in, invoke, shifted_pair, smooth_pair, write_pair

from vsmatch.cli import common

SIGTERM_AT_FIRST_RENAME = """
import os, signal, sys
real = os.replace
def replace(src, dst):
    result = real(src, dst)
    if str(dst).endswith(".pfm") and not getattr(replace, "sent", False):
        replace.sent = True  # after the first output is in place, before the others
        os.kill(os.getpid(), signal.SIGTERM)
    return result
os.replace = replace
from vsmatch.cli import main
main(sys.argv[1:])
"""


def test_sigterm_removes_temporaries_and_exits_143(pair_files, tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time

    # A stale temporary from a killed run is removed by the next run of the same output.
    (tmp_path / ".d.abc12_9z.tmp.pfm").write_bytes(b"")  # tempfile's 8 random characters
    code = ("import os, signal, sys, vsmatch.io as io\n"
            "real = io.imwrite_atomic\n"
            "def slow(path, image):\n"
            "    def encode(tmp):\n"
            "        open(tmp, 'wb').close(); print('writing', flush=True)\n"
            "        import time; time.sleep(30)\n"
            "    io.write_atomic(path, encode)\n"
            "io.imwrite_atomic = slow\n"
            "from vsmatch.cli import main\n"
            "sys.argv = ['vsmatch'] + sys.argv[1:]\n"
            "main()\n")
    proc = subprocess.Popen([sys.executable, "-c", code, "run", str(pair_files[0]),
                             str(pair_files[1]), "-o", str(tmp_path / "d.pfm"),
                             "--max-disp", "8"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while time.time() < deadline and "writing" not in proc.stdout.readline():
        pass
    os.kill(proc.pid, signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    stale = tmp_path / ".d.abc12_9z.tmp.pfm"
    assert err.strip().splitlines() == [
        f"removed {stale}, left by an earlier run that was killed", "vsmatch: terminated"]
    assert files_in(tmp_path) == ["l.png", "r.png"]


def descendants(pid: int) -> list[int]:
    """A process's children, theirs and so on, from Linux's /proc (no psutil needed)."""
    found = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            children = (task / "children").read_text().split()
        except OSError:  # the task ended meanwhile
            continue
        for child in map(int, children):
            found += [child, *descendants(child)]
    return found


def running(pid: int) -> bool:
    """Alive and not a zombie waiting for its parent."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_sigterm_ends_a_parallel_batch_and_its_workers(tmp_path, rng):
    import os
    import signal
    import subprocess
    import sys
    import time

    for k in range(6):
        left, right = shifted_pair(rng, 20, height=400, width=600)
        cv2.imwrite(str(tmp_path / f"p{k}_left.png"), left)
        cv2.imwrite(str(tmp_path / f"p{k}_right.png"), right)
    proc = subprocess.Popen([sys.executable, "-m", "vsmatch", "batch", str(tmp_path), "-o",
                             str(tmp_path / "out"), "--jobs", "2", "--max-disp", "200",
                             "--config", "default"], stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while time.time() < deadline and len(descendants(proc.pid)) < 3:
        time.sleep(0.2)  # the resource tracker and two workers
    children = descendants(proc.pid)
    assert len(children) >= 3
    time.sleep(2)  # the workers busy matching
    os.kill(proc.pid, signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    deadline = time.time() + 15
    while time.time() < deadline and any(map(running, children)):
        time.sleep(0.2)
    assert not any(map(running, children)), [p for p in children if running(p)]
    leftovers = [p.name for p in (tmp_path / "out").iterdir() if ".tmp" in p.name]
    assert leftovers == []


def test_output_into_a_closed_pipe_is_quiet(tmp_path, monkeypatch):
    """`vsmatch ... | head`: no "Error: [Errno 32] Broken pipe", exit 141 as a shell
    reports SIGPIPE."""
    def closed(*args, **kwargs):
        raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr("vsmatch.cli.datasets.echo", closed)
    result = invoke("datasets", "list", "--data-root", tmp_path)
    assert result.exit_code == 141 and "Broken pipe" not in result.output


def test_sigterm_during_the_renames_leaves_every_output_or_none(tmp_path, rng):
    views = write_pair(tmp_path, rng)
    outputs = {"-o": "d.pfm", "--depth": "z.pfm", "--confidence": "c.pfm",
               "--preview": "p.png", "--cloud": "x.ply"}
    args = [str(v) for v in views] + ["--max-disp", "16", "--focal", "300", "--baseline", "60"]
    for option, name in outputs.items():
        args += [option, str(tmp_path / name)]
    proc = subprocess.run([sys.executable, "-c", SIGTERM_AT_FIRST_RENAME, "run", *args],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 143, proc.stderr
    written = [name for name in outputs.values() if (tmp_path / name).exists()]
    assert written in ([], list(outputs.values())), written
    assert not [p for p in tmp_path.iterdir() if ".tmp" in p.name]


def test_a_second_sigterm_is_ignored_while_the_first_unwinds(monkeypatch):
    monkeypatch.setattr(signal, "signal", lambda *a: calls.append(a))
    calls = []
    with pytest.raises(common.Terminated):
        common.on_sigterm(signal.SIGTERM, None)
    # Every signal handled as SIGTERM is (a closed terminal's SIGHUP, SIGQUIT) too.
    assert calls == [call for number in common.TERMINATING for call in (
        (number, common.ignore_signal), (number, signal.SIG_IGN))]
    assert signal.SIGTERM in common.TERMINATING and signal.SIGHUP in common.TERMINATING
    assert common.ignore_signal(signal.SIGTERM, None) is None  # a callable: no race OSError


def test_two_sigterms_in_a_row_give_one_line(tmp_path, rng):
    left, right = smooth_pair(rng, height=900, width=1400)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    proc = subprocess.Popen([sys.executable, "-m", "vsmatch", "-v", "run", tmp_path / "l.png",
                             tmp_path / "r.png", "-o", tmp_path / "d.pfm", "--max-disp", "96"],
                            stderr=subprocess.PIPE, text=True)
    lines = []
    for line in proc.stderr:  # until the matching starts
        lines.append(line)
        if line.startswith("searching disparities"):
            break
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    time.sleep(0.001)
    proc.send_signal(signal.SIGTERM)
    err = "".join(lines) + proc.communicate(timeout=120)[1]
    assert proc.returncode == 143, err
    assert "Traceback" not in err and "Exception ignored" not in err
    assert err.strip().splitlines()[-1] == "vsmatch: terminated"
    assert not (tmp_path / "d.pfm").exists()


def test_a_late_second_sigterm_neither_kills_nor_prints(tmp_path, rng):
    """The second SIGTERM 0-1.5 ms after the first, at several points of the match: exit
    143 with one line each time (a do-nothing Python handler alone let Python's shutdown
    restore the default action, and a late signal killed the process: 1 run in 3)."""
    left, right = smooth_pair(rng, height=400, width=600)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    for attempt in range(8):
        proc = subprocess.Popen([sys.executable, "-m", "vsmatch", "-v", "run",
                                 tmp_path / "l.png", tmp_path / "r.png", "-o",
                                 tmp_path / "d.pfm", "--max-disp", "48"],
                                stderr=subprocess.PIPE, text=True)
        for line in proc.stderr:
            if line.startswith("searching disparities"):
                break
        time.sleep(0.05 * (attempt % 4))
        proc.send_signal(signal.SIGTERM)
        time.sleep(0.0005 * (attempt % 4))
        proc.send_signal(signal.SIGTERM)
        err = proc.communicate(timeout=120)[1]
        assert proc.returncode == 143, (attempt, proc.returncode, err)
        assert "Traceback" not in err, err


def test_sigterm_while_compiling_ahead_ends_the_compiling_workers(pair_files, tmp_path):
    """A first run on an empty cache compiles in worker processes: SIGTERM ends the run in
    one line and its workers with it (they would compile on for half a minute)."""
    import os

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    proc = subprocess.Popen([sys.executable, "-m", "vsmatch", "run", str(pair_files[0]),
                             str(pair_files[1]), "-o", str(tmp_path / "d.pfm"),
                             "--max-disp", "8"], env=env, stderr=subprocess.PIPE, text=True)
    assert "compiling the kernels once" in proc.stderr.readline()
    deadline = time.time() + 60
    while time.time() < deadline and not descendants(proc.pid):
        time.sleep(0.1)
    workers = descendants(proc.pid)
    assert workers  # one a core; this process only waits on them
    time.sleep(0.5)  # compiling: a share takes several seconds (the largest kernel, ~4 s)
    os.kill(proc.pid, signal.SIGTERM)
    sent = time.time()
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and err.strip().splitlines() == ["vsmatch: terminated"], err
    assert time.time() - sent < 6  # not after the workers' shares (~15 s here)
    assert not any(map(running, workers)), [p for p in workers if running(p)]
    assert not (tmp_path / "d.pfm").exists()
