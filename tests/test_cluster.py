"""vsmatch batch on a Dask cluster (a LocalCluster here, never another machine), recordings
as paired folders, and the failures of workers and schedulers."""

import os
import signal
import subprocess
import sys
import time

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from vsmatch import batch, io
from vsmatch.cli import main

from conftest import no_way_to
from test_range import textured_pair


@pytest.fixture(scope="module")
def distributed():
    try:
        import distributed
    except ImportError:
        no_way_to("import Dask's distributed (pip install 'vsmatch[cluster]')")
    return distributed


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def write_recording(folder, count, size=(240, 360), layout=("image_2", "image_3")):
    rng = np.random.default_rng(7)
    left_dir, right_dir = folder / layout[0], folder / layout[1]
    left_dir.mkdir(parents=True)
    right_dir.mkdir(parents=True)
    for k in range(count):
        left, right = textured_pair(rng, 4 + k % 9, height=size[0], width=size[1])
        cv2.imwrite(str(left_dir / f"{k:06d}_10.png"), left)
        cv2.imwrite(str(right_dir / f"{k:06d}_10.png"), right)
    return folder


def outputs(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.mark.parametrize("layout", [("image_2", "image_3"), ("image_02/data", "image_03/data"),
                                    ("colored_0", "colored_1"), ("left", "right")])
def test_recordings_are_found_as_paired_folders(tmp_path, layout):
    write_recording(tmp_path / "drive", 3, size=(40, 60), layout=layout)
    (tmp_path / "drive" / layout[0] / "000009_10.png").write_bytes(b"")  # no right frame
    (tmp_path / "drive" / layout[0] / "notes.txt").write_text("not a frame")
    jobs, unpaired = batch.find_pairs(tmp_path / "drive", tmp_path / "out", max_disp=None,
                                      suffix=".png")
    assert [j.output.name for j in jobs] == ["000000_10.png", "000001_10.png", "000002_10.png"]
    assert [p.name for p in unpaired] == ["000009_10.png"]
    assert all(j.right.parent.name in layout[1] and j.left.name == j.right.name for j in jobs)


def test_a_killed_task_leaves_no_temporary_file(tmp_path):
    out = tmp_path / "a.pfm"
    stale = tmp_path / ".a.k2j4x_9q.tmp.pfm"  # what mkstemp names a write of a.pfm
    other = tmp_path / ".a.b.k2j4x_9q.tmp.pfm"  # a write of a.b.pfm: not ours
    stale.write_bytes(b"half")
    other.write_bytes(b"half")
    io.remove_stale_temporaries(out)
    assert not stale.exists() and other.exists()


def test_local_cluster_gives_the_same_bytes_as_one_job(distributed, tmp_path):
    src = write_recording(tmp_path / "drive", 6)
    serial = invoke("-q", "batch", src, "-o", tmp_path / "serial", "--max-disp", 24)
    assert serial.exit_code == 0, serial.output
    environ = dict(os.environ)
    result = invoke("-q", "batch", src, "-o", tmp_path / "dask", "--max-disp", 24,
                    "--scheduler", "local:2")
    assert result.exit_code == 0, result.output
    assert dict(os.environ) == environ  # Dask's worker settings do not leak into ours
    assert outputs(tmp_path / "dask") == outputs(tmp_path / "serial")
    assert len(outputs(tmp_path / "dask")) == 6


def test_a_worker_killed_mid_batch_loses_nothing(distributed, tmp_path):
    src = write_recording(tmp_path / "drive", 10, size=(360, 540))
    reference = invoke("-q", "batch", src, "-o", tmp_path / "serial", "--max-disp", 40)
    assert reference.exit_code == 0, reference.output
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        pids = client.run(os.getpid)
        out = tmp_path / "dask"
        proc = subprocess.Popen([sys.executable, "-m", "vsmatch", "batch", str(src),
                                 "-o", str(out), "--max-disp", "40", "--scheduler",
                                 cluster.scheduler_address],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 120
        while not (out.is_dir() and any(out.glob("*.pfm"))) and time.monotonic() < deadline:
            time.sleep(0.05)
        busy = [address for address, keys in client.processing().items() if keys]
        assert busy, "no worker had a task when the first output appeared"
        victim = pids[busy[0]]
        os.kill(victim, signal.SIGKILL)  # in the middle of the batch, holding tasks
        stdout, stderr = proc.communicate(timeout=300)
        assert proc.returncode == 0, stderr
        assert "matched 10 of 10 pairs" in stdout
        assert victim not in client.run(os.getpid).values()  # it did die
    assert outputs(out) == outputs(tmp_path / "serial")  # every output whole, no temporary


def test_an_unreachable_scheduler_is_one_line(distributed, tmp_path):
    import socket

    import dask

    src = write_recording(tmp_path / "drive", 1, size=(40, 60))
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with dask.config.set({"distributed.comm.timeouts.connect": "2s"}):
        result = invoke("batch", src, "-o", tmp_path / "out", "--max-disp", 8,
                        "--scheduler", f"tcp://127.0.0.1:{port}")
    assert result.exit_code == 1, result.output
    lines = [line for line in result.output.strip().splitlines() if "Error" in line]
    assert len(lines) == 1 and "cannot reach the Dask scheduler" in lines[0]
    assert "Traceback" not in result.output
    assert not (tmp_path / "out").exists()  # not even an empty output folder


def test_missing_dask_says_how_to_install(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails as if absent
    src = write_recording(tmp_path / "drive", 1, size=(40, 60))
    result = invoke("batch", src, "-o", tmp_path / "out", "--max-disp", 8,
                    "--scheduler", "local:2")
    assert result.exit_code == 1
    assert "pip install 'vsmatch[cluster]'" in result.output
    assert len(result.output.strip().splitlines()) == 1


@pytest.mark.parametrize("value", ["local:0", "local:x", "garbage", "tcp://host"])
def test_bad_scheduler_addresses_are_usage_errors_naming_the_option(tmp_path, value):
    src = write_recording(tmp_path / "drive", 1, size=(40, 60))
    result = invoke("batch", src, "-o", tmp_path / "out", "--max-disp", 8, "--scheduler", value)
    assert result.exit_code == 2 and "expected" in result.output
    assert "--scheduler" in result.output and len(result.output.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def fails_on_three(item):
    if item == 3:
        raise RuntimeError("no three")
    return item * 10


@pytest.mark.parametrize("how", [dict(jobs=2), dict(scheduler="local:1"), dict(jobs=1)])
def test_an_unexpected_task_error_fails_that_item_only(distributed, how):
    from vsmatch.executors import make_executor

    with make_executor(**how) as executor:
        results = dict(executor.map_unordered(fails_on_three, range(5)))
    assert results[2] == 20 and results[4] == 40
    assert "RuntimeError" in results[3] and "no three" in results[3]


# --- clusters that hang or die: bounded waits, one line ---------------------------------------

def free_port():
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for_port(port, seconds=120):
    """Until a server listens on ``port`` (a scheduler started in a process of its own):
    waited for, not guessed with a fixed sleep that a busy machine outlasts."""
    import socket

    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    pytest.fail(f"nothing listened on port {port} within {seconds} s")


def test_a_scheduler_that_never_answers_is_given_up(distributed, tmp_path):
    """A port that accepts and never answers held Dask's client forever."""
    import socket
    import threading

    import dask

    src = write_recording(tmp_path / "drive", 1, size=(40, 60))
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    held = []
    threading.Thread(target=lambda: held.extend(server.accept() for _ in range(4)),
                     daemon=True).start()
    results = []

    def run():
        with dask.config.set({"distributed.comm.timeouts.connect": "2s"}):
            results.append(invoke("batch", src, "-o", tmp_path / "out", "--max-disp", 8,
                                  "--scheduler",
                                  f"tcp://127.0.0.1:{server.getsockname()[1]}"))

    batch = threading.Thread(target=run, daemon=True)
    try:
        batch.start()
        batch.join(timeout=300)  # given up at all, not within a machine-dependent time
    finally:
        server.close()
    assert not batch.is_alive(), "the batch still waits for a scheduler that never answers"
    [result] = results
    assert result.exit_code == 1, result.output
    lines = [line for line in result.output.strip().splitlines() if line.strip()]
    assert len(lines) == 1 and "cannot reach the Dask scheduler" in lines[0], result.output


def test_a_scheduler_without_workers_is_one_line(distributed, tmp_path):
    import dask

    src = write_recording(tmp_path / "drive", 1, size=(40, 60))
    with distributed.LocalCluster(n_workers=0, dashboard_address=":0") as cluster, \
            dask.config.set({"distributed.comm.timeouts.connect": "2s"}):
        result = invoke("batch", src, "-o", tmp_path / "out", "--max-disp", 8,
                        "--scheduler", cluster.scheduler_address)
    assert result.exit_code == 1, result.output
    lines = [line for line in result.output.strip().splitlines() if line.strip()]
    assert len(lines) == 1 and "has no worker" in lines[0], result.output


def finished_outputs(folder):
    """The outputs in place (not the hidden temporaries being written)."""
    return [p for p in folder.glob("*.pfm") if not p.name.startswith(".")] \
        if folder.is_dir() else []


def start_worker(address):
    return subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address,
                             "--no-nanny", "--nthreads", "1", "--no-dashboard"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def test_the_only_worker_dying_ends_the_batch_in_one_line(distributed, tmp_path):
    """No worker left (and none restarting it): the batch stops after the patience,
    with the outputs written so far whole, instead of waiting forever."""
    import dask

    src = write_recording(tmp_path / "drive", 8, size=(240, 360))
    out = tmp_path / "dask"
    with distributed.LocalCluster(n_workers=0, dashboard_address=":0") as cluster, \
            dask.config.set({"distributed.comm.timeouts.connect": "5s"}):
        worker = start_worker(cluster.scheduler_address)
        try:
            proc = subprocess.Popen(
                [sys.executable, "-m", "vsmatch", "batch", str(src), "-o", str(out),
                 "--max-disp", "40", "--scheduler", cluster.scheduler_address],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                env={**os.environ, "DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "5s"})
            deadline = time.monotonic() + 120
            while not finished_outputs(out) and time.monotonic() < deadline:
                time.sleep(0.05)
            worker.kill()
            stdout, stderr = proc.communicate(timeout=120)
        finally:
            worker.kill()
    assert proc.returncode == 1, stderr
    # One line of ours (the progress bar aside), and none of Dask's log.
    lines = [line for line in stderr.splitlines() if line.startswith("Error")]
    assert " - distributed." not in stderr and "Traceback" not in stderr, stderr
    assert len(lines) == 1 and "no worker" in lines[0], stderr
    written = finished_outputs(out)
    assert 1 <= len(written) < 8
    for path in written:
        assert np.isfinite(io.read_pfm(path)).any()
    assert not [p for p in out.iterdir() if ".tmp" in p.name]


def test_a_killed_scheduler_is_one_line_without_dasks_traceback(distributed, tmp_path):
    src = write_recording(tmp_path / "drive", 8, size=(240, 360))
    out = tmp_path / "dask"
    port = free_port()
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler",
                                  "--host", "127.0.0.1", "--port", str(port),
                                  "--no-dashboard"],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    address = f"tcp://127.0.0.1:{port}"
    worker = None
    try:
        wait_for_port(port)
        worker = start_worker(address)
        proc = subprocess.Popen(
            [sys.executable, "-m", "vsmatch", "batch", str(src), "-o", str(out),
             "--max-disp", "40", "--scheduler", address],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            env={**os.environ, "DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "5s"})
        deadline = time.monotonic() + 120
        while not (out.is_dir() and any(out.glob("*.pfm"))) and time.monotonic() < deadline:
            time.sleep(0.05)
        scheduler.kill()
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        scheduler.kill()
        if worker is not None:
            worker.kill()
    assert proc.returncode == 1, stderr
    # One line of ours (the progress bar aside), and none of Dask's log.
    lines = [line for line in stderr.splitlines() if line.startswith("Error")]
    assert " - distributed." not in stderr and "Traceback" not in stderr, stderr
    assert len(lines) == 1 and "Dask" in lines[0], stderr
    assert "Traceback" not in stderr


@pytest.mark.parametrize("value, message", [
    ("ucx://127.0.0.1:8786", "ucx:// is not supported"),
    ("tcp://127.0.0.1:99999", "not in 1..65535"),
])
def test_addresses_this_machine_cannot_use_are_refused_at_once(tmp_path, value, message):
    src = write_recording(tmp_path / "drive", 1, size=(40, 60))
    start = time.monotonic()
    result = invoke("batch", src, "-o", tmp_path / "out", "--scheduler", value)
    assert result.exit_code == 2 and message in result.output, result.output
    assert time.monotonic() - start < 5
