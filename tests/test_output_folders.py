"""Output folders: a command never replaces a file it did not write, and a command that
fails leaves no empty folder behind (demo, rectify, run --rectified, eval --out-dir)."""

import subprocess

import numpy as np
import pytest
from click.testing import CliRunner

from vsmatch.cli import main


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_demo_never_replaces_a_users_file(tmp_path):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "left.png").write_bytes(b"my own picture")
    result = invoke("demo", "-o", folder)
    assert result.exit_code == 1 and "left.png" in result.output, result.output
    assert "--overwrite" in result.output
    assert (folder / "left.png").read_bytes() == b"my own picture"
    assert sorted(p.name for p in folder.iterdir()) == ["left.png"]


def test_demo_runs_again_over_its_own_folder(tmp_path):
    folder = tmp_path / "demo"
    assert invoke("demo", "-o", folder).exit_code == 0
    first = (folder / "disparity.pfm").read_bytes()
    result = invoke("demo", "-o", folder)
    assert result.exit_code == 0, result.output
    assert (folder / "disparity.pfm").read_bytes() == first
    assert (folder / "vsmatch-demo.txt").is_file()


def test_demo_on_a_full_disk_leaves_no_folder(small_disk):
    disk = small_disk(16)
    result = invoke("demo", "-o", disk / "out")
    assert result.exit_code == 1 and "could not be written" in result.output, result.output
    assert len(result.output.strip().splitlines()) == 1, result.output
    assert list(disk.iterdir()) == []


def test_rectify_on_a_full_disk_leaves_no_folder(small_disk, tmp_path):
    from cli_helpers import write_opencv_rig, write_pair

    left, right = write_pair(tmp_path, np.random.default_rng(0))
    calib = write_opencv_rig(tmp_path / "rig.yaml")
    disk = small_disk(16)
    result = invoke("rectify", left, right, "--calib", calib, "--to", disk / "rect")
    assert result.exit_code == 1 and "could not be written" in result.output, result.output
    assert list(disk.iterdir()) == []


@pytest.mark.data
def test_eval_on_a_full_disk_leaves_no_folder(small_disk, data_dir):
    disk = small_disk(16)
    result = invoke("-q", "eval", "--dataset", "middlebury2", "--data-root", data_dir, "--method",
                    "census", "--out-dir", disk / "runs")
    assert result.exit_code == 1 and "could not be written" in result.output, result.output
    assert len(result.output.strip().splitlines()) == 1, result.output
    assert list(disk.iterdir()) == []


SIGTERM_AFTER_FIRST_SCENE = """
import os, signal, sys
from vsmatch import evaluation
real = evaluation.save_scene_outputs
def save(*args, **kwargs):
    real(*args, **kwargs)
    os.kill(os.getpid(), signal.SIGTERM)  # after the first scene's files are in place
evaluation.save_scene_outputs = save
from vsmatch.cli import main
main(sys.argv[1:])
"""


@pytest.mark.data
def test_sigterm_during_eval_says_what_the_out_dir_holds(tmp_path, data_dir):
    import sys

    proc = subprocess.run([sys.executable, "-c", SIGTERM_AFTER_FIRST_SCENE, "eval",
                           "--dataset", "middlebury2", "--data-root", str(data_dir),
                           "--method", "census", "--out-dir", str(tmp_path / "runs")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 143, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.strip() and "run/s" not in line
             and "|" not in line]
    assert len(lines) == 1 and "only the runs that finished" in lines[0], proc.stderr
    written = [p.name for p in (tmp_path / "runs" / "census").iterdir()
               if p.suffix == ".pfm" and "_confidence" not in p.name]
    assert len(written) == 1, written  # the first scene's, whole


def test_ctrl_c_while_the_command_loads_is_one_line(tmp_path):
    """Numba and OpenCV take a moment to load: Ctrl-C then printed Python's traceback."""
    import os
    import sys

    # The signal is sent from inside the loading (no race with a fixed sleep): the
    # console script's own import of the commands is where Ctrl-C lands.
    code = ("import os, signal, sys\n"
            "import vsmatch.cli as cli\n"
            "from vsmatch.cli import console\n"
            "real = cli.load_group\n"
            "def load_group():\n"
            "    os.kill(os.getpid(), getattr(signal, os.environ['STOP']))\n"
            "    return real()\n"
            "cli.load_group = load_group\n"
            "sys.argv = ['vsmatch', 'run', 'l.png', 'r.png', '-o', sys.argv[1]]\n"
            "console.main()\n")
    for stop, code_expected, line in (("SIGINT", 130, "vsmatch: interrupted"),
                                      ("SIGTERM", 143, "vsmatch: terminated"),
                                      ("SIGHUP", 129, "vsmatch: hung up (the terminal closed)")):
        proc = subprocess.run([sys.executable, "-c", code, str(tmp_path / "d.pfm")],
                              capture_output=True, text=True, timeout=120,
                              env={**os.environ, "STOP": stop})
        assert proc.returncode == code_expected, proc.stderr
        assert "Traceback" not in proc.stderr
        assert proc.stderr.strip().splitlines() == [line], proc.stderr


def test_loading_the_command_does_not_load_numba_or_opencv():
    import sys

    code = ("import sys, vsmatch.cli.console, vsmatch; "
            "print('numba' in sys.modules or 'cv2' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.stdout.strip() == "False", out.stderr


def test_eval_gives_each_method_its_own_folder_and_replaces_nothing(tmp_path, data_dir):
    """Two methods of one file name shared one folder, the second replacing the first; a
    folder holding a user's files was written over; a method named after a data set wrote
    into it. Each method now gets a folder of its own, said where names meet; a folder with
    files is refused without --overwrite; a data set's folder never."""
    import shutil

    root = tmp_path / "data"
    shutil.copytree(data_dir / "middlebury2", root / "middlebury2")
    for folder, base in (("a", "fast"), ("b", "paper")):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "fast.yaml").write_text(f"base: {base}\n")
    out = tmp_path / "out"
    result = invoke("eval", "--data-root", root, "--method", tmp_path / "a" / "fast.yaml",
                    "--method", tmp_path / "b" / "fast.yaml", "--method", "fast",
                    "--out-dir", out)
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == ["fast", "fast_2", "fast_3"]
    assert "fast.yaml: its outputs in" in result.output and "fast_2" in result.output
    bases = [(out / f / "config.yaml").read_text() for f in ("fast", "fast_2", "fast_3")]
    # Each folder holds its own method's config: b's (paper) was written over a's before.
    assert bases[1] != bases[0] and bases[0] == bases[2]
    # A folder that holds files: refused before any work, nothing touched.
    before = (out / "fast" / "tsukuba.pfm").read_bytes()
    result = invoke("eval", "--data-root", root, "--method", "paper", "--method", "fast",
                    "--out-dir", out)
    assert result.exit_code == 1 and "already holds files" in result.output
    assert "--overwrite" in result.output and not (out / "paper").exists()
    assert (out / "fast" / "tsukuba.pfm").read_bytes() == before
    assert invoke("eval", "--data-root", root, "--method", "fast", "--out-dir", out,
                  "--overwrite").exit_code == 0
    # A method named after a data set, its folder in the data root: refused.
    (tmp_path / "middlebury2.yaml").write_text("base: fast\n")
    result = invoke("eval", "--data-root", root, "--dataset", "middlebury2", "--method",
                    tmp_path / "middlebury2.yaml", "--out-dir", root)
    assert result.exit_code == 1, result.output
    assert "lies in the data set middlebury2" in result.output
    assert not (root / "middlebury2" / "tsukuba.pfm").exists()
    assert sorted(p.name for p in (root / "middlebury2").iterdir()) == sorted(
        p.name for p in (data_dir / "middlebury2").iterdir())


@pytest.mark.parametrize("command", [["demo", "-o"], ["eval", "--method", "fast", "--out-dir"],
                                     ["batch", "PAIRS", "-o"]])
def test_a_link_to_nothing_as_an_output_folder_is_one_line(tmp_path, data_dir, command):
    """A dangling link as an output folder read '[Errno 17] File exists'; now it is named,
    with where it leads, before any work."""
    (tmp_path / "out").symlink_to(tmp_path / "nowhere")
    if "PAIRS" in command:
        import shutil

        cones = data_dir / "middlebury2" / "cones"
        (tmp_path / "src").mkdir()
        for name, side in (("imL.png", "left"), ("imR.png", "right")):
            shutil.copy(cones / name, tmp_path / "src" / f"cones_{side}.png")
        command = [c if c != "PAIRS" else tmp_path / "src" for c in command]
    result = invoke(*command, tmp_path / "out", "--data-root", data_dir) if \
        command[0] == "eval" else invoke(*command, tmp_path / "out")
    assert result.exit_code == 1, result.output
    line = result.output.strip().splitlines()[-1]
    assert f"a link to {tmp_path / 'nowhere'}, which does not exist" in line
    assert "Errno" not in result.output and not (tmp_path / "nowhere").exists()


def test_eval_on_a_read_only_mount_is_refused_before_the_matching(small_disk, data_dir,
                                                                  monkeypatch):
    """It read '[Errno 30] Read-only file system' after every scene was matched."""
    from vsmatch import evaluation

    disk = small_disk(64, read_only=True)
    monkeypatch.setattr(evaluation, "evaluate", lambda *a, **k: pytest.fail("matched"))
    result = invoke("eval", "--dataset", "middlebury2", "--data-root", data_dir, "--method",
                    "census", "--out-dir", disk / "runs")
    assert result.exit_code == 1, result.output
    assert f"folder '{disk}' is not writable" in result.output
    assert "Errno" not in result.output
