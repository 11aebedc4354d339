"""A batch's plan is checked whole before any work: clashing or linked outputs, odd CSVs,
missing rows."""

import cv2
import pytest
from cli_helpers import invoke, one_line_error
from conftest import random_pair

from vsmatch import batch, io


def test_batch_refuses_an_output_over_another_rows_input_before_any_work(tmp_path, rng):
    for stem in ("A", "B"):
        left, right = random_pair(rng, height=24, width=48, shift=3)
        cv2.imwrite(str(tmp_path / f"{stem}_L.png"), left)
        cv2.imwrite(str(tmp_path / f"{stem}_R.png"), right)
    (tmp_path / "p.csv").write_text("B_L.png,B_R.png,A_L.png,8\nA_L.png,A_R.png,out_A.png,8\n")
    before = (tmp_path / "A_L.png").read_bytes()
    line = one_line_error(invoke("batch", tmp_path / "p.csv", "--overwrite"))
    assert "line 1" in line and "line 2" in line and "A_L.png" in line
    assert (tmp_path / "A_L.png").read_bytes() == before
    assert not (tmp_path / "out_A.png").exists()


def test_batch_refuses_an_output_that_links_to_an_input(tmp_path, rng):
    left, right = random_pair(rng, height=24, width=48, shift=3)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    (tmp_path / "link.png").symlink_to(tmp_path / "l.png")
    (tmp_path / "p.csv").write_text("l.png,r.png,link.png,8\n")
    assert "would overwrite the input" in one_line_error(
        invoke("batch", tmp_path / "p.csv", "--overwrite"))


def test_batch_refuses_two_rows_with_one_output(tmp_path):
    (tmp_path / "p.csv").write_text("a.png,b.png,out.pfm,8\nc.png,d.png,./out.pfm,8\n")
    line = one_line_error(invoke("batch", tmp_path / "p.csv"))
    assert "line 2" in line and "line 1" in line and "both write" in line


def test_batch_reads_a_csv_with_a_byte_order_mark(tmp_path, rng):
    left, right = random_pair(rng, height=24, width=48, shift=3)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    (tmp_path / "p.csv").write_bytes("\ufeffleft,right,output,max_disp\nl.png,r.png,d.pfm,8\n"
                                     .encode("utf-8"))
    result = invoke("batch", tmp_path / "p.csv")
    assert result.exit_code == 0, result.output
    assert (tmp_path / "d.pfm").exists()


def test_unpaired_frames_are_listed_and_fail(tmp_path, rng):
    for side in ("left", "right"):
        (tmp_path / "rec" / side).mkdir(parents=True)
    for frame in ("001", "002", "003"):
        left, right = random_pair(rng, height=24, width=48, shift=3)
        cv2.imwrite(str(tmp_path / "rec" / "left" / f"{frame}.png"), left)
        if frame != "002":
            cv2.imwrite(str(tmp_path / "rec" / "right" / f"{frame}.png"), right)
    result = invoke("batch", tmp_path / "rec", "-o", tmp_path / "out", "--max-disp", 8)
    assert result.exit_code == 1
    assert "matched 2 of 3 pairs, 1 failed" in result.output
    assert "002.png: no frame of the same name in the other view" in result.output


def test_batch_verbose_prints_each_pairs_range_and_time(tmp_path, rng):
    left, right = random_pair(rng, height=24, width=48, shift=3)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    (tmp_path / "p.csv").write_text("l.png,r.png,d.pfm,8\n")
    result = invoke("-v", "batch", tmp_path / "p.csv")
    assert result.exit_code == 0, result.output
    assert "line 1: disparities 0..8, " in result.output and " s" in result.output


def test_plan_check_compares_by_identity():
    a = batch.PairJob(io.Path("a.png"), io.Path("b.png"), io.Path("x/../o.pfm"), 8, "row 1")
    b = batch.PairJob(io.Path("c.png"), io.Path("d.png"), io.Path("o.pfm"), 8, "row 2")
    with pytest.raises(batch.BatchError, match="row 2 and row 1 both write"):
        batch.check_plan([a, b])
    batch.check_plan([a])


def test_batch_plan_check_is_linear(tmp_path, monkeypatch):
    rows = 300
    jobs = [batch.PairJob(tmp_path / f"l{k}.png", tmp_path / f"r{k}.png",
                          tmp_path / f"d{k}.pfm", 8, f"line {k}") for k in range(rows)]
    calls = []
    monkeypatch.setattr(batch.io, "same_file", lambda a, b: calls.append(1) or False)
    original = batch._file_key
    monkeypatch.setattr(batch, "_file_key", lambda p: calls.append(1) or original(p))
    batch.check_plan(jobs)
    assert len(calls) <= 3 * rows  # quadratic: 90 000


def test_ten_thousand_missing_rows_are_checked_in_seconds(tmp_path):
    lines = [f"l{k}.png,r{k}.png,d{k}.pfm,8" for k in range(10_000)]
    (tmp_path / "p.csv").write_text("\n".join(lines) + "\n")
    lines[9_999] = "l9999.png,r9999.png,l0.png,8"
    (tmp_path / "bad.csv").write_text("\n".join(lines) + "\n")
    line = one_line_error(invoke("batch", tmp_path / "bad.csv"))
    assert "line 10000" in line and "would overwrite the input" in line


def test_a_nul_in_a_csv_cell_names_the_line(tmp_path):
    (tmp_path / "p.csv").write_text("a.png,b.png,c.pfm\na\0.png,b.png,d.pfm\n")
    line = one_line_error(invoke("batch", tmp_path / "p.csv"))
    assert "line 2" in line and "NUL" in line
