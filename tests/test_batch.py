import os
import subprocess
import sys

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from vsmatch import batch, io
from vsmatch.cli import main

from conftest import random_pair


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def write_pair(folder, rng, left_name, right_name, shift=3, size=(32, 48)):
    folder.mkdir(parents=True, exist_ok=True)
    left, right = random_pair(rng, height=size[0], width=size[1], shift=shift)
    cv2.imwrite(str(folder / left_name), left)
    cv2.imwrite(str(folder / right_name), right)


@pytest.fixture
def pair_list(tmp_path, rng):
    write_pair(tmp_path / "a", rng, "l.png", "r.png", shift=2)
    write_pair(tmp_path / "b", rng, "l.png", "r.png", shift=4)
    (tmp_path / "out").mkdir()
    csv = tmp_path / "pairs.csv"
    csv.write_text("left,right,output,max_disp\n"
                   "a/l.png,a/r.png,out/a.pfm,8\n"
                   "missing/l.png,missing/r.png,out/m.pfm,8\n"
                   "b/l.png,b/r.png,out/b.png,8\n")
    return csv


def test_csv_batch_carries_on_past_a_failure(pair_list, tmp_path):
    result = invoke("batch", pair_list)
    assert result.exit_code == 1
    assert "matched 2 of 3 pairs, 1 failed" in result.output
    assert "failed: " in result.output and "missing/l.png: file not found" in result.output
    assert "\r" not in result.output  # no progress bar's carriage returns in a log
    assert np.all(np.abs(io.read_disparity(tmp_path / "out/a.pfm")[5:-5, 12:-5] - 2) < 0.5)
    assert np.all(np.abs(io.read_disparity(tmp_path / "out/b.png")[5:-5, 12:-5] - 4) < 0.5)
    assert not (tmp_path / "out/m.pfm").exists()


def test_existing_outputs_are_skipped_unless_overwrite(pair_list, tmp_path):
    invoke("batch", pair_list)
    stamp = (tmp_path / "out/a.pfm").stat().st_mtime_ns
    again = invoke("batch", pair_list)
    assert "skipped 2 with existing output (--overwrite matches them again)" in again.output
    assert (tmp_path / "out/a.pfm").stat().st_mtime_ns == stamp
    forced = invoke("batch", pair_list, "--overwrite")
    assert "matched 2 of 3" in forced.output and "skipped" not in forced.output


def test_folder_batch_finds_scene_folders_and_side_by_side_files(tmp_path, rng):
    src = tmp_path / "scenes"
    write_pair(src / "alpha", rng, "imL.png", "imR.png")
    write_pair(src / "beta", rng, "im0.png", "im1.png")
    write_pair(src, rng, "gamma_left.png", "gamma_right.png")
    (src / "notes.txt").write_text("ignored")
    result = invoke("batch", src, "-o", tmp_path / "disp", "--format", "png",
                    "--max-disp", 8, "--config", "paper")
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in (tmp_path / "disp").iterdir()) == [
        "alpha.png", "beta.png", "gamma.png"]


def test_parallel_jobs_give_the_same_bytes(pair_list, tmp_path):
    invoke("batch", pair_list)
    serial = (tmp_path / "out/a.pfm").read_bytes()
    result = invoke("batch", pair_list, "--jobs", 2, "--overwrite")
    assert result.exit_code == 1 and "matched 2 of 3" in result.output
    assert (tmp_path / "out/a.pfm").read_bytes() == serial


@pytest.mark.parametrize("text,message", [
    ("a.png,b.png\n", "line 1: expected left,right,output"),
    ("a.png,b.png,c.pfm,many\n", "max_disp 'many' is not a whole number or 'auto'"),
    ("a.png,b.png,c.pfm,0\n", "max_disp 0 must be at least 1"),
])
def test_bad_pair_lists_are_refused(tmp_path, text, message):
    csv = tmp_path / "bad.csv"
    csv.write_text(text)
    with pytest.raises(batch.BatchError, match=message):
        batch.read_pair_list(csv, 64)
    result = invoke("batch", csv)
    assert result.exit_code == 1 and message in result.output


def test_empty_and_missing_sources(tmp_path):
    (tmp_path / "empty").mkdir()
    assert "no stereo pairs found" in invoke("batch", tmp_path / "empty",
                                             "-o", tmp_path / "o").output
    assert "no such file or folder" in invoke("batch", tmp_path / "nope").output


@pytest.mark.data
def test_same_bytes_with_one_and_two_threads(data_dir, tmp_path):
    scene = data_dir / "middlebury2" / "cones"
    outputs = []
    for threads in ("1", "2"):
        out = tmp_path / f"t{threads}.pfm"
        env = {**os.environ, "NUMBA_NUM_THREADS": threads}
        proc = subprocess.run([sys.executable, "-m", "vsmatch", "--quiet", "run",
                               scene / "imL.png", scene / "imR.png", "-o", out,
                               "--max-disp", "59"], env=env, capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
        outputs.append(out.read_bytes())
    assert outputs[0] == outputs[1]


def test_csv_ranges_may_be_auto_or_left_to_the_default(tmp_path):
    csv = tmp_path / "p.csv"
    csv.write_text("a.png,b.png,c.pfm,auto\na.png,b.png,d.pfm,12\na.png,b.png,e.pfm\n")
    jobs = batch.read_pair_list(csv, None)
    assert [j.max_disp for j in jobs] == [None, 12, None]
    assert batch.read_pair_list(csv, 30)[2].max_disp == 30


def test_batch_estimates_each_range_by_default(tmp_path):
    from test_range import textured_pair

    rng = np.random.default_rng(3)
    for name, shift in (("near", 14), ("far", 5)):
        left, right = textured_pair(rng, shift, height=120, width=240)
        (tmp_path / "scenes" / name).mkdir(parents=True)
        cv2.imwrite(str(tmp_path / "scenes" / name / "left.png"), left)
        cv2.imwrite(str(tmp_path / "scenes" / name / "right.png"), right)
    result = invoke("batch", tmp_path / "scenes", "-o", tmp_path / "out")
    assert result.exit_code == 0, result.output
    for name, shift in (("near", 14), ("far", 5)):
        disp = io.read_disparity(tmp_path / "out" / f"{name}.pfm")
        assert np.mean(np.abs(disp[10:-10, 40:-10] - shift) < 0.5) > 0.9


def test_an_output_over_an_input_fails_that_pair(tmp_path, rng):
    write_pair(tmp_path, rng, "l.png", "r.png")
    csv = tmp_path / "p.csv"
    csv.write_text("l.png,r.png,l.png,8\n")
    before = (tmp_path / "l.png").read_bytes()
    result = invoke("batch", csv, "--overwrite")
    assert result.exit_code == 1 and "would overwrite the input" in result.output
    assert (tmp_path / "l.png").read_bytes() == before


def test_confidence_files_are_part_of_the_plan(tmp_path, rng):
    """A row's confidence file (NAME_confidence.pfm) is an output like its disparity:
    another row may not write it, and a user's own file of that name is not replaced
    without --overwrite."""
    write_pair(tmp_path, rng, "l.png", "r.png")
    clash = tmp_path / "clash.csv"
    clash.write_text("l.png,r.png,a_confidence.pfm,8\nl.png,r.png,a.pfm,8\n")
    result = invoke("batch", clash, "--confidence")
    assert result.exit_code == 1 and "both write" in result.output, result.output
    assert not (tmp_path / "a.pfm").exists() and not (tmp_path / "a_confidence.pfm").exists()

    own = tmp_path / "own.csv"
    own.write_text("l.png,r.png,b.pfm,8\n")
    (tmp_path / "b_confidence.pfm").write_bytes(b"mine")
    result = invoke("batch", own, "--confidence")
    assert result.exit_code == 1 and "--overwrite" in result.output, result.output
    assert (tmp_path / "b_confidence.pfm").read_bytes() == b"mine"
    assert not (tmp_path / "b.pfm").exists()
    assert invoke("batch", own, "--confidence", "--overwrite").exit_code == 0
    assert io.read_pfm(tmp_path / "b_confidence.pfm").shape == (32, 48)


def test_folder_batch_sub_folders_that_clash_with_a_confidence_file(tmp_path, rng):
    write_pair(tmp_path / "scenes" / "a", rng, "im0.png", "im1.png")
    write_pair(tmp_path / "scenes" / "a_confidence", rng, "im0.png", "im1.png")
    result = invoke("batch", tmp_path / "scenes", "-o", tmp_path / "out", "--max-disp", 8,
                    "--confidence")
    assert result.exit_code == 1 and "both write" in result.output, result.output
    assert not (tmp_path / "out").exists()


def test_the_pair_list_is_never_an_output(tmp_path, rng):
    write_pair(tmp_path, rng, "l.png", "r.png")
    csv = tmp_path / "pairs.csv"
    csv.write_text("l.png,r.png,pairs.csv,8\n")
    before = csv.read_bytes()
    result = invoke("batch", csv)
    assert result.exit_code == 1 and "would overwrite the pair list" in result.output
    assert csv.read_bytes() == before


def test_csv_outputs_are_checked_before_any_pair_runs(tmp_path, rng, small_disk):
    """A missing output folder is made; a read-only one, or an output that is not .pfm or
    .png, is refused before any pair is matched (so no pair is matched in vain)."""
    write_pair(tmp_path, rng, "l.png", "r.png")
    csv = tmp_path / "pairs.csv"
    csv.write_text("l.png,r.png,first.pfm,8\nl.png,r.png,new/deeper/d.pfm,8\n")
    result = invoke("batch", csv)
    assert result.exit_code == 0, result.output
    assert (tmp_path / "new/deeper/d.pfm").exists()

    csv.write_text("l.png,r.png,second.pfm,8\nl.png,r.png,d.jpg,8\n")
    result = invoke("batch", csv)
    assert result.exit_code == 1 and "line 2" in result.output and ".pfm" in result.output
    assert not (tmp_path / "second.pfm").exists()

    # The real permission check: a read-only mount refuses even root.
    locked = small_disk(64, read_only=True)
    csv.write_text(f"l.png,r.png,second.pfm,8\nl.png,r.png,{locked}/d.pfm,8\n")
    result = invoke("batch", csv)
    assert result.exit_code == 1 and "not writable" in result.output, result.output
    assert not (tmp_path / "second.pfm").exists()


def test_jobs_beside_a_scheduler_is_refused(tmp_path, rng):
    write_pair(tmp_path, rng, "l.png", "r.png")
    csv = tmp_path / "pairs.csv"
    csv.write_text("l.png,r.png,a.pfm,8\n")
    result = invoke("batch", csv, "--jobs", 2, "--scheduler", "local:1")
    assert result.exit_code == 2 and "--jobs" in result.output
