import json

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from vsmatch import __version__, io
from vsmatch.cli import main



def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_help_and_version():
    result = invoke("--help")
    assert result.exit_code == 0 and "run" in result.output and "eval" in result.output
    assert "max-disp" in invoke("run", "--help").output
    assert __version__ in invoke("--version").output


@pytest.mark.parametrize("suffix", [".pfm", ".png"])
def test_run_writes_the_disparity(pair_files, tmp_path, suffix):
    out = tmp_path / f"disp{suffix}"
    result = invoke("run", *pair_files, "-o", out, "--max-disp", 8, "--config", "paper")
    assert result.exit_code == 0, result.output
    disp = io.read_disparity(out)
    assert disp.shape == (32, 48)
    assert np.all(disp[5:-5, 12:-5] == 3)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["l.png", "r.png", out.name])


def test_run_with_a_config_file(pair_files, tmp_path):
    """The file's values are the ones matched with: its output is the library's with that
    config, to the byte, and not the default config's (a config silently ignored would pass
    an exit-code check)."""
    from vsmatch import pipeline
    from vsmatch.config import load_config

    cfg = tmp_path / "c.yaml"
    cfg.write_text("cost:\n  lambda_census: 2.0\narms:\n  l1: 3\n  l2: 5\n")
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8,
                    "--config", cfg)
    assert result.exit_code == 0, result.output
    left, right = (io.read_image(p) for p in pair_files)
    written = io.read_pfm(tmp_path / "d.pfm")
    expected = pipeline.run(left, right, max_disp=8, config=load_config(str(cfg))).disparity
    default = pipeline.run(left, right, max_disp=8).disparity
    assert written.tobytes() == expected.tobytes()
    assert written.tobytes() != default.tobytes()


@pytest.fixture
def bad_inputs(pair_files, tmp_path):
    """Broken inputs beside the good pair, in the working folder."""
    (tmp_path / "text.png").write_text("this is not an image")
    good = (tmp_path / "l.png").read_bytes()
    (tmp_path / "trunc.png").write_bytes(good[: len(good) // 2])
    cv2.imwrite(str(tmp_path / "small.png"), np.zeros((32, 40, 3), np.uint8))
    cv2.imwrite(str(tmp_path / "tiny_l.png"), np.zeros((5, 30, 3), np.uint8))
    cv2.imwrite(str(tmp_path / "tiny_r.png"), np.zeros((5, 30, 3), np.uint8))
    (tmp_path / "broken.yaml").write_text("arms: [1, 2\n")
    (tmp_path / "unknown.yaml").write_text("arms:\n  tau9: 3\n")
    (tmp_path / "range.yaml").write_text("arms:\n  tau1: 999\n")
    (tmp_path / "afile").write_text("")
    return tmp_path


@pytest.mark.parametrize("args,code,message", [
    (["MISSING.png", "r.png", "-o", "d.pfm"], 1, "MISSING.png: file not found"),
    (["text.png", "r.png", "-o", "d.pfm"], 1, "text.png: not a readable image"),
    (["trunc.png", "r.png", "-o", "d.pfm"], 1, "trunc.png: not a readable image"),
    (["l.png", "small.png", "-o", "d.pfm"], 1, "differ in size"),
    (["tiny_l.png", "tiny_r.png", "-o", "d.pfm", "--max-disp", "4"], 1,
     "smaller than the census window"),
    (["l.png", "r.png", "-o", "d.tif"], 2, "must end in .pfm"),
    (["l.png", "r.png", "-o", "d.pfm", "--max-disp", "0"], 2, "must be at least 1"),
    (["l.png", "r.png", "-o", "d.pfm", "--max-disp", "-3"], 2, "must be at least 1"),
    (["l.png", "r.png", "-o", "d.pfm", "--max-disp", "48"], 2, "less than the image width"),
    (["l.png", "r.png", "-o", "d.pfm", "--max-disp", "x"], 2,
     "'x' is neither a whole number nor 'auto'"),
    (["l.png", "r.png", "-o", "d.pfm", "--config", "broken.yaml"], 1, "not valid YAML"),
    (["l.png", "r.png", "-o", "d.pfm", "--config", "unknown.yaml"], 1,
     "unknown config key 'arms.tau9'"),
    (["l.png", "r.png", "-o", "d.pfm", "--config", "range.yaml"], 1,
     "arms.tau1 = 999.0 is out of range [0.0, 255.0]"),
    (["l.png", "r.png", "-o", "d.pfm", "--config", "nonsense"], 1, "neither a bundled"),
    (["l.png", "r.png", "-o", "nodir/d.pfm"], 1, "does not exist"),
    (["l.png", "r.png", "-o", "afile/d.pfm"], 1, "does not exist"),
])
def test_run_errors_are_one_line_without_output(bad_inputs, monkeypatch, args, code, message):
    monkeypatch.chdir(bad_inputs)
    before = set(bad_inputs.iterdir())
    result = invoke("run", *args)
    assert result.exit_code == code, result.output
    assert message in result.output
    assert "Traceback" not in result.output
    assert len(result.output.strip().splitlines()) == 1
    assert set(bad_inputs.iterdir()) == before  # nothing written, no temporary left


def test_unwritable_output_folder(pair_files, small_disk):
    """The real permission check: a read-only mount refuses even root (no check patched)."""
    disk = small_disk(64, read_only=True)
    result = invoke("run", *pair_files, "-o", disk / "d.pfm")
    assert result.exit_code == 1 and f"{disk}" in result.output
    assert "is not writable" in result.output


def test_truncated_image_error_is_one_line_in_a_real_process(bad_inputs):
    """libpng prints its own complaint unless OpenCV's logging is silenced."""
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "vsmatch", "run", "trunc.png", "r.png",
                           "-o", "d.pfm"], cwd=bad_inputs, capture_output=True, text=True)
    assert proc.returncode == 1
    assert proc.stderr.strip().splitlines() == ["Error: trunc.png: not a readable image "
                                                "(unknown format, or truncated)"]
    assert not (bad_inputs / "d.pfm").exists()


@pytest.mark.parametrize("convert", [
    lambda a: cv2.cvtColor(a, cv2.COLOR_BGR2GRAY),
    lambda a: a.astype(np.uint16) * 257,
    lambda a: cv2.cvtColor(a, cv2.COLOR_BGR2BGRA),
])
def test_grey_16bit_and_rgba_pairs_are_matched(pair_files, tmp_path, convert):
    for path in pair_files:
        cv2.imwrite(str(path), convert(cv2.imread(str(path))))
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8,
                    "--config", "paper")
    assert result.exit_code == 0, result.output
    assert np.all(io.read_disparity(tmp_path / "d.pfm")[5:-5, 12:-5] == 3)


def test_interrupt_exits_130_without_output(pair_files, tmp_path, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("vsmatch.pipeline.run", interrupted)
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8)
    assert result.exit_code == 130 and "interrupted" in result.output
    assert not (tmp_path / "d.pfm").exists()


def test_interrupt_while_writing_leaves_no_file(pair_files, tmp_path, monkeypatch):
    real_imencode = cv2.imencode

    def encode_then_interrupt(ext, image):
        real_imencode(ext, image)  # the temporary exists by now
        raise KeyboardInterrupt

    monkeypatch.setattr("vsmatch.io.cv2.imencode", encode_then_interrupt)
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8)
    assert result.exit_code == 130
    assert sorted(p.name for p in tmp_path.iterdir()) == ["l.png", "r.png"]


def test_quiet_and_verbose(pair_files, tmp_path):
    quiet = invoke("--quiet", "run", *pair_files, "-o", tmp_path / "q.pfm", "--max-disp", 8)
    assert quiet.exit_code == 0 and quiet.output == ""
    loud = invoke("--verbose", "run", *pair_files, "-o", tmp_path / "v.pfm", "--max-disp", 8)
    assert loud.exit_code == 0
    assert "estimated noise" in loud.output and "seconds:" in loud.output


def test_demo_writes_its_outputs(tmp_path):
    result = invoke("demo", "-o", tmp_path / "demo")
    assert result.exit_code == 0, result.output
    assert "% bad pixels" in result.output
    names = {p.name for p in (tmp_path / "demo").iterdir()}
    assert names == {"left.png", "right.png", "disparity.pfm", "disparity_colour.png",
                     "error.png", "vsmatch-demo.txt"}


def test_eval_missing_dataset_says_where_it_looked(tmp_path):
    result = invoke("eval", "--data-root", tmp_path)
    assert result.exit_code == 1
    assert "not found" in result.output and str(tmp_path) in result.output


@pytest.mark.data
def test_eval_json_has_the_documented_shape(data_dir, tmp_path):
    out = tmp_path / "t.json"
    result = invoke("--quiet", "eval", "--data-root", data_dir, "--method", "census",
                    "--json", out, "--out-dir", tmp_path / "imgs")
    assert result.exit_code == 0, result.output
    # --quiet quiets the notes, not the results: the table is the command's output.
    assert "nonocc bad1.0 (%)" in result.output and "\ncensus " in result.output
    assert "wrote" not in result.output
    report = json.loads(out.read_text())
    assert report["dataset"] == "middlebury2" and report["threshold"] == 1.0
    assert report["metric"] == "bad1.0"
    census = report["methods"]["census"]
    assert list(census["scenes"]) == ["tsukuba", "venus", "teddy", "cones"]
    cones = census["scenes"]["cones"]
    assert set(cones) == {"nonocc", "all", "disc", "seconds", "metrics", "range",
                          "confidence"}
    assert set(cones["confidence"]) == {"auc", "optimum", "dense", "r"}
    assert 0 <= cones["confidence"]["r"] < 1
    assert (tmp_path / "imgs" / "census" / "cones_confidence.pfm").exists()
    assert cones["range"] == [0, 59]
    assert cones["metrics"]["nonocc"]["bad1.0"] == cones["nonocc"]
    assert {"bad0.5", "bad2.0", "bad4.0", "avgerr", "rms", "A90", "invalid"} <= set(
        cones["metrics"]["all"])
    assert set(census["avg"]) == {"nonocc", "all", "disc", "metrics", "confidence"}
    assert (tmp_path / "imgs" / "census" / "teddy_error.png").exists()


def test_ablation_refuses_several_methods(tmp_path):
    result = invoke("eval", "--ablation", "--method", "paper", "--method", "census",
                    "--data-root", tmp_path)
    assert result.exit_code == 2 and "at most one" in result.output


@pytest.mark.parametrize("where", ["left", "output", "batch", "video"])
def test_a_symbolic_link_that_loops_is_one_line(tmp_path, monkeypatch, rng, where):
    from conftest import random_pair
    import cv2

    monkeypatch.chdir(tmp_path)
    (tmp_path / "loop").symlink_to("loop")
    left, right = random_pair(rng, height=32, width=48, shift=3)
    cv2.imwrite("l.png", left)
    cv2.imwrite("r.png", right)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "d.pfm").symlink_to("../loop")
    args = {"left": ["run", "loop", "r.png", "-o", "d.pfm", "--max-disp", "8"],
            "output": ["run", "l.png", "r.png", "-o", "out/d.pfm", "--max-disp", "8"],
            "batch": ["batch", "pairs.csv"],
            "video": ["video", "loop", "-o", "v.avi", "--side-by-side"]}[where]
    (tmp_path / "pairs.csv").write_text("loop,r.png,o.pfm,8\n")
    result = invoke(*args)
    assert result.exit_code == 1, result.output
    assert "symbolic link that loops" in result.output and "unexpected" not in result.output
    assert len(result.output.strip().splitlines()) == 1, result.output


def test_a_camera_index_past_what_opencv_takes_is_one_line(tmp_path):
    result = invoke("video", "99999999999999999999", "1", "-o", tmp_path / "v.avi")
    assert result.exit_code == 1 and "no camera has this index" in result.output
    assert "Overload" not in result.output
