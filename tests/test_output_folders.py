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


@pytest.fixture
def small_disk(tmp_path):
    disk = tmp_path / "disk"
    disk.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=16k", "tmpfs", str(disk)],
                      capture_output=True).returncode != 0:
        pytest.skip("cannot mount a small tmpfs here")
    yield disk
    subprocess.run(["umount", str(disk)], capture_output=True)


def test_demo_on_a_full_disk_leaves_no_folder(small_disk):
    result = invoke("demo", "-o", small_disk / "out")
    assert result.exit_code == 1 and "could not be written" in result.output, result.output
    assert len(result.output.strip().splitlines()) == 1, result.output
    assert list(small_disk.iterdir()) == []


def test_rectify_on_a_full_disk_leaves_no_folder(small_disk, tmp_path):
    from test_never_silent_2 import write_opencv_rig, write_pair

    left, right = write_pair(tmp_path, np.random.default_rng(0))
    calib = write_opencv_rig(tmp_path / "rig.yaml")
    result = invoke("rectify", left, right, "--calib", calib, "--to", small_disk / "rect")
    assert result.exit_code == 1 and "could not be written" in result.output, result.output
    assert list(small_disk.iterdir()) == []
