"""Hostile and awkward input (issue 18): refused in one line, before the work, never
clipped, never a traceback, never a lost or half-written file."""

import os
import struct
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

import vsmatch
from vsmatch import batch, config, exposure, geometry, io, pipeline
from vsmatch.cli import main

from conftest import random_pair


def invoke(*args, env=None):
    return CliRunner().invoke(main, [str(a) for a in args], env=env)


def one_line_error(result, code=1):
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1, result.output
    return lines[0]


def files_in(folder):
    return sorted(p.name for p in folder.iterdir())


# --- 1. 16-bit PNG output ------------------------------------------------------------

def test_png_output_refuses_a_range_it_cannot_hold_before_matching(tmp_path, rng,
                                                                   monkeypatch):
    left, right = random_pair(rng, height=24, width=300, shift=3)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    monkeypatch.setattr(pipeline, "run", lambda *a, **k: pytest.fail("matched anyway"))
    for extra in (["--max-disp", 280], ["--min-disp", -16, "--max-disp", 8]):
        line = one_line_error(invoke("run", tmp_path / "l.png", tmp_path / "r.png",
                                     "-o", tmp_path / "d.png", *extra))
        assert "16-bit PNG" in line and ".pfm" in line
    assert files_in(tmp_path) == ["l.png", "r.png"]


def test_png_encoder_refuses_instead_of_clipping():
    with pytest.raises(ValueError, match="16-bit PNG"):
        io.disparity_to_png16(np.array([[300.0, 2.0]], np.float32))
    with pytest.raises(ValueError, match="16-bit PNG"):
        io.disparity_to_png16(np.array([[-3.0, 2.0]], np.float32))
    png = io.disparity_to_png16(np.array([[np.inf, 255.5]], np.float32))
    assert png.tolist() == [[0, 65408]]


def test_batch_png_refuses_a_pair_whose_range_it_cannot_hold(tmp_path, rng):
    for name, width in (("wide", 300), ("narrow", 48)):
        left, right = random_pair(rng, height=24, width=width, shift=3)
        cv2.imwrite(str(tmp_path / f"{name}_left.png"), left)
        cv2.imwrite(str(tmp_path / f"{name}_right.png"), right)
    (tmp_path / "p.csv").write_text("wide_left.png,wide_right.png,wide.png,280\n"
                                    "narrow_left.png,narrow_right.png,narrow.png,8\n")
    result = invoke("batch", tmp_path / "p.csv")
    assert result.exit_code == 1
    assert "16-bit PNG" in result.output and "failed: " in result.output
    assert (tmp_path / "narrow.png").exists() and not (tmp_path / "wide.png").exists()


# --- 2. batch plans --------------------------------------------------------------------

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


# --- 3. recordings ---------------------------------------------------------------------

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


# --- 4. OpenCV 5 ------------------------------------------------------------------------

def test_first_match_over_more_than_256_disparities(rng):
    """OpenCV 5's blur takes at most 128 channels; 4.x took 512."""
    left, right = random_pair(rng, height=40, width=420, shift=30)
    cfg = config.load_config("default")
    disp, matched = exposure.first_match(left, right, 300, cfg)
    assert disp.shape == (40, 420)
    assert np.mean(disp[matched] == 30) > 0.9 and matched[:, 340:].mean() > 0.5


# --- 5. placeholders in calibration files ---------------------------------------------

def test_ndisp_of_half_the_width_or_more_is_unknown(tmp_path, pair_files):
    calib = tmp_path / "calib.txt"
    calib.write_text("cam0=[100 0 24; 0 100 16; 0 0 1]\ndoffs=0\nbaseline=50\nndisp=48\n")
    assert geometry.read_calibration(calib).search_range_for(48) is None
    assert geometry.read_calibration(calib).search_range_for(200) == 48
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--calib", calib, "-v")
    # The range is then found from the pair (this tiny random pair has too few features).
    assert "taken as 'unknown'" in result.output
    assert "--max-disp" not in result.output.split("taken as")[0]


# --- 6. no traceback ------------------------------------------------------------------

def test_unexpected_errors_are_one_line_and_debug_shows_them(pair_files, tmp_path,
                                                            monkeypatch):
    def broken(*args, **kwargs):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(pipeline, "run", broken)
    args = ["run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8]
    line = one_line_error(invoke(*args))
    assert "vsmatch run: unexpected ZeroDivisionError: boom" in line
    assert isinstance(invoke("--debug", *args).exception, ZeroDivisionError)
    assert isinstance(invoke(*args, env={"VSMATCH_DEBUG": "1"}).exception, ZeroDivisionError)
    assert files_in(tmp_path) == ["l.png", "r.png"]


@pytest.mark.parametrize("height, width", [(4, 20000), (2, 100000), (60, 1)])
def test_a_very_thin_pair_without_a_range_is_one_line(tmp_path, rng, height, width):
    """What is wrong is the views' size, whatever the range: said before any range is
    looked for (not "give --max-disp")."""
    left, right = random_pair(rng, height=height, width=width, shift=0)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    line = one_line_error(invoke("run", tmp_path / "l.png", tmp_path / "r.png", "-o",
                                 tmp_path / "d.pfm"))
    assert "smaller than the census window" in line and "--max-disp" not in line


@pytest.mark.parametrize("text,message", [
    ("[" * 100000 + "]" * 100000, "larger than"),
    ("[" * 5000 + "]" * 5000, "nested too deeply"),
    ("pyramid: {max_row_cells: .inf}", "pyramid.max_row_cells = inf must be a finite"),
    ("arms: {tau1: .nan}", "arms.tau1 = nan must be a finite"),
    ("fill: {max_search: .nan}", "fill.max_search = nan must be a finite"),
])
def test_hostile_configs_are_one_line_naming_file_and_key(pair_files, tmp_path, text,
                                                          message):
    cfg = tmp_path / "c.yaml"
    cfg.write_text(text)
    line = one_line_error(invoke("run", *pair_files, "-o", tmp_path / "d.pfm",
                                 "--max-disp", 8, "--config", cfg))
    assert message in line and "c.yaml" in line


def test_yaml_alias_bomb_is_quoted_short(tmp_path):
    """Nine nested anchors: 9**9 strings if the value were ever walked or printed."""
    levels = ["&a [" + ", ".join(["xxxxxxxx"] * 9) + "]"]
    for k in "bcdefghi":
        previous = chr(ord(k) - 1)
        levels.append(f"&{k} [" + ", ".join([f"*{previous}"] * 9) + "]")
    cfg = tmp_path / "bomb.yaml"
    cfg.write_text("arms:\n  tau1: [" + ", ".join(levels) + "]\n")
    with pytest.raises(config.ConfigError) as caught:
        config.load_config(cfg)
    assert "arms.tau1 = a list must be a number" in str(caught.value)
    assert len(str(caught.value)) < 200


def test_calibration_with_non_finite_numbers_names_file_and_key(tmp_path):
    good = "cam0=[100 0 24; 0 100 16; 0 0 1]\nbaseline=50\nndisp=16\n"
    for key, text in (("doffs", good + "doffs=nan\n"),
                      ("cam0", good.replace("24;", "nan;") + "doffs=0\n"),
                      ("baseline", good.replace("baseline=50", "baseline=inf"))):
        calib = tmp_path / "calib.txt"
        calib.write_text(text)
        with pytest.raises(geometry.CalibrationError) as caught:
            geometry.read_calibration(calib)
        assert str(calib) in str(caught.value) and key in str(caught.value)


@pytest.mark.parametrize("option", ["--max-depth", "--cx", "--focal", "--doffs"])
def test_non_finite_options_are_usage_errors(pair_files, tmp_path, option):
    args = ["run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8, "--focal", 100,
            "--baseline", 1]
    line = one_line_error(invoke(*args, option, "nan"), code=2)
    assert option in line and "finite" in line


# --- 7. decompression bombs ------------------------------------------------------------

def png_header_only(width, height):
    """A valid PNG signature and IHDR claiming a huge size, with a tiny body."""
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    chunk = struct.pack(">I", len(ihdr)) + b"IHDR" + ihdr
    chunk += struct.pack(">I", zlib.crc32(b"IHDR" + ihdr) & 0xFFFFFFFF)
    body = zlib.compress(b"\0" * 1000)
    idat = struct.pack(">I", len(body)) + b"IDAT" + body
    idat += struct.pack(">I", zlib.crc32(b"IDAT" + body) & 0xFFFFFFFF)
    return b"\x89PNG\r\n\x1a\n" + chunk + idat


def test_huge_image_headers_are_refused_before_decoding(tmp_path, monkeypatch):
    (tmp_path / "bomb.png").write_bytes(png_header_only(60000, 60000))
    monkeypatch.setattr(io.cv2, "imdecode", lambda *a: pytest.fail("decoded"))
    with pytest.raises(io.ImageError, match="3600 megapixels, over the limit"):
        io.read_image(tmp_path / "bomb.png")
    (tmp_path / "big.png").write_bytes(png_header_only(8000, 6000))
    with pytest.raises(io.ImageError, match="--max-memory"):
        io.read_image(tmp_path / "big.png", max_mb=1024)


@pytest.mark.parametrize("ext", [".png", ".jpg", ".bmp", ".ppm", ".pgm", ".tif"])
def test_header_sizes_match_what_opencv_decodes(tmp_path, rng, ext):
    from vsmatch.image_header import header_size

    image = rng.integers(0, 256, (37, 53, 1 if ext == ".pgm" else 3), dtype=np.uint8)
    path = tmp_path / f"i{ext}"
    assert cv2.imwrite(str(path), image)
    assert header_size(path) == (53, 37)


def test_huge_image_from_the_command_line(tmp_path, pair_files):
    (tmp_path / "bomb.png").write_bytes(png_header_only(60000, 60000))
    line = one_line_error(invoke("run", tmp_path / "bomb.png", pair_files[1], "-o",
                                 tmp_path / "d.pfm", "--max-disp", 8))
    assert "bomb.png" in line and "megapixels" in line


# --- 14, 16. signals and all-or-none outputs --------------------------------------------

def test_a_failing_cloud_leaves_no_disparity_and_names_the_file(pair_files, tmp_path,
                                                                 monkeypatch):
    import errno

    def disk_full(self, path):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("plyfile.PlyData.write", disk_full)
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8,
                    "--focal", 100, "--baseline", 1, "--depth", tmp_path / "z.pfm",
                    "--cloud", tmp_path / "c.ply")
    line = one_line_error(result)
    assert "c.ply" in line and "No space left" in line
    assert files_in(tmp_path) == ["l.png", "r.png"]


def test_sigterm_removes_temporaries_and_exits_143(pair_files, tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time

    # A stale temporary from a killed run is removed by the next run of the same output.
    (tmp_path / ".d.abc123.tmp.pfm").write_bytes(b"")
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
    assert err.strip() == "vsmatch: terminated"
    assert files_in(tmp_path) == ["l.png", "r.png"]


# --- 17, 19. the command line ----------------------------------------------------------

def test_verbose_and_quiet_after_the_command(pair_files, tmp_path):
    loud = invoke("run", *pair_files, "-o", tmp_path / "v.pfm", "--max-disp", 8, "-v")
    assert loud.exit_code == 0 and "seconds:" in loud.output
    quiet = invoke("run", *pair_files, "-o", tmp_path / "q.pfm", "--max-disp", 8, "-q")
    assert quiet.exit_code == 0 and quiet.output == ""


def test_batch_verbose_prints_each_pairs_range_and_time(tmp_path, rng):
    left, right = random_pair(rng, height=24, width=48, shift=3)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    (tmp_path / "p.csv").write_text("l.png,r.png,d.pfm,8\n")
    result = invoke("-v", "batch", tmp_path / "p.csv")
    assert result.exit_code == 0, result.output
    assert "line 1: disparities 0..8, " in result.output and " s" in result.output


def test_preview_is_written_with_the_disparity(pair_files, tmp_path):
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8,
                    "--preview", tmp_path / "d_colour.png")
    assert result.exit_code == 0, result.output
    preview = cv2.imread(str(tmp_path / "d_colour.png"))
    assert preview.shape[0] == 32 and preview.shape[1] > 48 and preview[:, :48].std() > 0


def test_plan_check_compares_by_identity():
    a = batch.PairJob(io.Path("a.png"), io.Path("b.png"), io.Path("x/../o.pfm"), 8, "row 1")
    b = batch.PairJob(io.Path("c.png"), io.Path("d.png"), io.Path("o.pfm"), 8, "row 2")
    with pytest.raises(batch.BatchError, match="row 2 and row 1 both write"):
        batch.check_plan([a, b])
    batch.check_plan([a])


# --- 11, 12, 13. the range, swapped and unrectified views --------------------------------

def smooth_texture(rng, height, width):
    """A smooth random texture (SIFT finds corners in it)."""
    base = rng.integers(0, 256, size=(height // 4 + 1, width // 4 + 1, 3), dtype=np.uint8)
    return cv2.resize(base, (width // 4 * 4 + 4, height // 4 * 4 + 4),
                      interpolation=cv2.INTER_CUBIC)[:height, :width]


def shifted_pair(rng, dx, dy=0, height=120, width=240):
    """Left pixel (x, y) shows what right pixel (x - dx, y - dy) shows."""
    wide = smooth_texture(rng, height + 2 * abs(dy), width + 2 * abs(dx))
    x0, y0 = abs(dx), abs(dy)
    left = wide[y0:y0 + height, x0:x0 + width]
    right = wide[y0 + dy:y0 + dy + height, x0 + dx:x0 + dx + width]
    return np.ascontiguousarray(left), np.ascontiguousarray(right)


def verged_pair(rng):
    """Disparities -12 in the top half, +10 in the bottom half (a verged rig's mix)."""
    top, bottom = shifted_pair(rng, -12, height=80), shifted_pair(rng, 10, height=80)
    return np.vstack([top[0], bottom[0]]), np.vstack([top[1], bottom[1]])


def test_the_found_range_goes_below_zero_with_the_pair(rng):
    from vsmatch.search_range import estimate_disparity_range

    found = estimate_disparity_range(*verged_pair(rng))
    assert found.min_disp <= -12 and found.max_disp >= 10
    left, right = shifted_pair(rng, 12)
    assert estimate_disparity_range(left, right).min_disp == 0


def test_a_negative_found_range_is_searched(tmp_path, rng):
    left, right = verged_pair(rng)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    result = invoke("run", tmp_path / "l.png", tmp_path / "r.png", "-o", tmp_path / "d.pfm",
                    "-v")
    assert result.exit_code == 0, result.output
    disp = io.read_disparity(tmp_path / "d.pfm")
    assert np.mean(np.abs(disp[10:70, 30:-30] + 12) < 1) > 0.9
    assert np.mean(np.abs(disp[90:-10, 30:-30] - 10) < 1) > 0.9


def test_swapped_views_are_refused_without_a_range_and_named_with_one(tmp_path, rng):
    left, right = shifted_pair(rng, 12)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    swapped = ["run", tmp_path / "r.png", tmp_path / "l.png", "-o", tmp_path / "d.pfm"]
    assert "views look swapped" in one_line_error(invoke(*swapped))
    assert not (tmp_path / "d.pfm").exists()
    given = invoke(*swapped, "--max-disp", 20)
    assert given.exit_code == 0 and "warning: " in given.output and "swapped" in given.output


def test_unrectified_views_are_refused_without_a_range_and_named_with_one(tmp_path, rng):
    left, right = shifted_pair(rng, 8, dy=4)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    args = ["run", tmp_path / "l.png", tmp_path / "r.png", "-o", tmp_path / "d.pfm"]
    line = one_line_error(invoke(*args))
    assert "rows disagree by 4.0 px" in line and "not rectified" in line
    given = invoke(*args, "--max-disp", 20)
    assert given.exit_code == 0 and "warning: " in given.output and "rectif" in given.output


def test_sigterm_ends_a_parallel_batch_and_its_workers(tmp_path, rng):
    import os
    import signal
    import subprocess
    import sys
    import time

    psutil = pytest.importorskip("psutil")
    for k in range(6):
        left, right = shifted_pair(rng, 20, height=400, width=600)
        cv2.imwrite(str(tmp_path / f"p{k}_left.png"), left)
        cv2.imwrite(str(tmp_path / f"p{k}_right.png"), right)
    proc = subprocess.Popen([sys.executable, "-m", "vsmatch", "batch", str(tmp_path), "-o",
                             str(tmp_path / "out"), "--jobs", "2", "--max-disp", "200",
                             "--config", "default"], stderr=subprocess.PIPE, text=True)
    parent = psutil.Process(proc.pid)
    deadline = time.time() + 120
    while time.time() < deadline and len(parent.children(recursive=True)) < 3:
        time.sleep(0.2)  # the resource tracker and two workers
    children = parent.children(recursive=True)
    assert len(children) >= 3
    time.sleep(2)  # the workers busy matching
    os.kill(proc.pid, signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    gone, alive = psutil.wait_procs(children, timeout=15)
    assert not alive, [p.cmdline() for p in alive]
    leftovers = [p.name for p in (tmp_path / "out").iterdir() if ".tmp" in p.name]
    assert leftovers == []


def test_match_finds_the_range_when_max_disp_is_none(rng):
    left, right = verged_pair(rng)
    result = vsmatch.run(left, right, max_disp=None, config="paper")
    low, high = result.search_range
    assert low <= -12 and high >= 10
    disp = vsmatch.match(left, right, max_disp=None, config="paper")
    np.testing.assert_array_equal(disp, result.disparity)
    np.testing.assert_array_equal(
        disp, vsmatch.match(left, right, min_disp=low, max_disp=high, config="paper"))
    left, right = shifted_pair(rng, 12)
    with pytest.raises(ValueError, match="swapped"):
        vsmatch.match(right, left, max_disp=None)


# --- 18. the first run's compilation -----------------------------------------------------

def test_a_cold_kernel_cache_is_announced(pair_files, tmp_path, monkeypatch):
    from vsmatch import _kernels

    monkeypatch.setattr(_kernels, "cache_is_cold", lambda: True)
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8)
    assert result.exit_code == 0 and "compiling the kernels once" in result.output
    monkeypatch.undo()
    assert "compiling" not in invoke("run", *pair_files, "-o", tmp_path / "e.pfm",
                                     "--max-disp", 8).output


def test_cache_is_cold_looks_where_numba_caches(tmp_path):
    """Numba caches under NUMBA_CACHE_DIR (or ~/.cache/numba for a read-only install):
    the check asks Numba where, and finds a kernel cached there."""
    import subprocess
    import sys
    script = ("from vsmatch._kernels import cache_is_cold\n"
              "from vsmatch._kernels.aggregate import sum_along_arms\n"
              "print(cache_is_cold(), sum_along_arms._cache.cache_path)\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}

    def ask():
        out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                             text=True, check=True).stdout.split()
        return out[0] == "True", Path(out[1])

    cold, folder = ask()
    assert cold and folder.is_relative_to(tmp_path / "numba")
    tag = f"py{sys.version_info.major}{sys.version_info.minor}"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"aggregate.sum_over_arms-24.{tag}.nbi").write_bytes(b"")
    assert ask()[0] is False


def test_an_impossible_memory_budget_is_a_usage_error_naming_the_option(pair_files, tmp_path):
    line = one_line_error(invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp",
                                 8, "--max-memory", 99999999999), code=2)
    assert "--max-memory" in line and "memory.max_mb" not in line


def test_a_placeholder_ndisp_of_100000_does_not_blame_max_disp(tmp_path, pair_files):
    calib = tmp_path / "calib.txt"
    calib.write_text("cam0=[100 0 24; 0 100 16; 0 0 1]\ndoffs=0\nbaseline=50\nndisp=100000\n")
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--calib", calib, "-v")
    assert "ndisp=100000 is half the image width or more" in result.output
    assert "must be less than the image width" not in result.output


def test_output_into_a_closed_pipe_is_quiet(tmp_path, monkeypatch):
    """`vsmatch ... | head`: no "Error: [Errno 32] Broken pipe", exit 141 as a shell
    reports SIGPIPE."""
    def closed(*args, **kwargs):
        raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr("vsmatch.cli.datasets.echo", closed)
    result = invoke("datasets", "list", "--data-root", tmp_path)
    assert result.exit_code == 141 and "Broken pipe" not in result.output
