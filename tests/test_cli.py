import json

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from vsmatch import __version__, io
from vsmatch.cli import main

from conftest import random_pair


@pytest.fixture
def pair_files(tmp_path, rng):
    left, right = random_pair(rng, height=32, width=48, shift=3)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    return tmp_path / "l.png", tmp_path / "r.png"


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
    cfg = tmp_path / "c.yaml"
    cfg.write_text("aggregation:\n  iterations: 2\n")
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8,
                    "--config", cfg)
    assert result.exit_code == 0, result.output


@pytest.mark.parametrize("args,code,message", [
    (["MISSING", "r.png", "-o", "d.pfm"], 1, "file not found"),
    (["l.png", "r.png", "-o", "d.tif"], 2, "must end in .pfm"),
    (["l.png", "r.png", "-o", "d.pfm", "--max-disp", "0"], 2, "must be at least 1"),
    (["l.png", "r.png", "-o", "d.pfm", "--max-disp", "48"], 2, "less than the image width"),
    (["l.png", "r.png", "-o", "nodir/d.pfm"], 1, "does not exist"),
    (["l.png", "r.png", "-o", "d.pfm", "--config", "nonsense"], 1, "neither a bundled"),
])
def test_run_errors_are_one_line_without_output(pair_files, tmp_path, monkeypatch,
                                                args, code, message):
    monkeypatch.chdir(tmp_path)
    result = invoke("run", *args)
    assert result.exit_code == code, result.output
    assert message in result.output
    assert "Traceback" not in result.output
    assert not (tmp_path / "d.pfm").exists() and not (tmp_path / "d.tif").exists()


def test_demo_writes_its_outputs(tmp_path):
    result = invoke("demo", "-o", tmp_path / "demo")
    assert result.exit_code == 0, result.output
    assert "% bad pixels" in result.output
    names = {p.name for p in (tmp_path / "demo").iterdir()}
    assert names == {"left.png", "right.png", "disparity.pfm", "disparity_colour.png",
                     "error.png"}


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
    report = json.loads(out.read_text())
    assert report["dataset"] == "middlebury2" and report["threshold"] == 1.0
    census = report["methods"]["census"]
    assert list(census["scenes"]) == ["tsukuba", "venus", "teddy", "cones"]
    assert set(census["scenes"]["cones"]) == {"nonocc", "all", "disc", "seconds"}
    assert set(census["avg"]) == {"nonocc", "all", "disc"}
    assert (tmp_path / "imgs" / "census" / "teddy_error.png").exists()


def test_ablation_refuses_several_methods(tmp_path):
    result = invoke("eval", "--ablation", "--method", "paper", "--method", "census",
                    "--data-root", tmp_path)
    assert result.exit_code == 2 and "at most one" in result.output
