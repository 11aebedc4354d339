"""Hostile configs, calibrations and options: one line naming the file and key."""

import time

import pytest
import yaml
from cli_helpers import HEIGHT, WIDTH, invoke, kalibr_rig, one_line_error, ros_pair

from vsmatch import config, geometry, rig
from vsmatch.geometry import CalibrationError

ALIAS_BOMB = """cam0:
  camera_model: pinhole
  intrinsics: [300, 300, 80, 48]
  distortion_model: radtan
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [160, 96]
cam1:
  camera_model: pinhole
  intrinsics: [300, 300, 80, 48]
  distortion_model: radtan
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [160, 96]
  a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1]
  b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a]
  c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b]
  d: &d [*c, *c, *c, *c, *c, *c, *c, *c, *c]
  e: &e [*d, *d, *d, *d, *d, *d, *d, *d, *d]
  f: &f [*e, *e, *e, *e, *e, *e, *e, *e, *e]
  g: &g [*f, *f, *f, *f, *f, *f, *f, *f, *f]
  h: &h [*g, *g, *g, *g, *g, *g, *g, *g, *g]
  T_cn_cnm1: [*h, *h, *h, *h]
"""


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


def test_an_impossible_memory_budget_is_a_usage_error_naming_the_option(pair_files, tmp_path):
    line = one_line_error(invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp",
                                 8, "--max-memory", 99999999999), code=2)
    assert "--max-memory" in line and "memory.max_mb" not in line


def test_yaml_alias_bombs_in_calibrations_are_refused_at_once(tmp_path):
    (tmp_path / "camchain.yaml").write_text(ALIAS_BOMB)
    start = time.perf_counter()
    with pytest.raises(CalibrationError, match="more YAML nodes than a calibration holds"):
        rig.read_rig([tmp_path / "camchain.yaml"])
    assert time.perf_counter() - start < 5  # was 42 s and 7.7 GB
    left, right = ros_pair(tmp_path)
    bomb = ALIAS_BOMB[ALIAS_BOMB.index("  a: &a"):].replace("  T_cn_cnm1", "  z")
    right.write_text(right.read_text() + "bomb:\n" + bomb)
    with pytest.raises(CalibrationError, match="more YAML nodes"):
        rig.read_rig([left, right])


def test_a_few_plain_aliases_are_still_read(tmp_path):
    """PyYAML writes a list shared by both cameras once, with an alias."""
    text = yaml.safe_dump(kalibr_rig())
    assert "*id001" in text
    (tmp_path / "camchain.yaml").write_text(text)
    assert rig.read_rig([tmp_path / "camchain.yaml"]).size == (WIDTH, HEIGHT)
