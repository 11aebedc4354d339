import numpy as np
import pytest
import yaml

from vsmatch.config import (Config, ConfigError, bundled_config_names, config_from_dict,
                            load_config)


def test_bundled_configs_load():
    assert {"census", "paper", "default"} <= set(bundled_config_names())
    for name in bundled_config_names():
        assert isinstance(load_config(name), Config)
    assert load_config(None) == load_config("default")


def test_census_config_is_the_bare_baseline():
    cfg = load_config("census")
    assert (cfg.cost.census_width, cfg.cost.census_height) == (9, 7)
    assert cfg.cost.lambda_gradient is None and cfg.aggregation.iterations == 0
    assert not cfg.consistency.enabled


def test_yaml_file_merges_over_defaults(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("arms:\n  kappa: 0.5\n  l2: 40\n")
    cfg = load_config(path)
    assert cfg.arms.kappa == 0.5 and cfg.arms.l2 == 40
    assert cfg.arms.tau1 == Config().arms.tau1


@pytest.mark.parametrize("data,message", [
    ({"cost": {"lambda_censsus": 3}}, r"unknown config key 'cost.lambda_censsus'"),
    ({"costs": {}}, r"unknown config key 'costs'"),
    ({"arms": {"tau1": -1}}, r"arms.tau1 = -1.0 is out of range \[0.0, 255.0\]"),
    ({"arms": {"l1": 2.5}}, r"arms.l1 = 2.5 must be a whole number"),
    ({"arms": {"l1": 30, "l2": 20}}, r"l1 < l2"),
    ({"fill": {"directions": 5}}, r"fill.directions = 5 is not one of 2, 8, 16"),
    ({"consistency": {"enabled": "yes"}}, r"must be true or false"),
    ({"cost": {"lambda_census": "x"}}, r"must be a number"),
    ({"cost": {"census_width": 8}}, r"must be odd"),
    ({"cost": {"census_width": 11}}, r"at most 64 neighbours"),
    ({"bands": {"census_width": 8}}, r"bands.census_width and bands.census_height must be odd"),
    ({"bands": {"census_width": 11}}, r"bands.census_width x bands.census_height .* at most 64"),
    ({"cost": 3}, r"section 'cost' must be a mapping"),
])
def test_bad_values_are_refused_naming_the_key(data, message):
    with pytest.raises(ConfigError, match=message):
        config_from_dict(data)


def test_null_switches_an_optional_term_off():
    assert config_from_dict({"cost": {"lambda_gradient": None}}).cost.lambda_gradient is None
    with pytest.raises(ConfigError, match="must not be empty"):
        config_from_dict({"arms": {"tau1": None}})


def test_broken_yaml_and_missing_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("arms: [1, 2\n")
    with pytest.raises(ConfigError, match="not valid YAML at line"):
        load_config(bad)
    with pytest.raises(ConfigError, match="neither a bundled config"):
        load_config(tmp_path / "missing.yaml")


def test_error_messages_are_one_line(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("arms:\n  tau9: 1\n")
    with pytest.raises(ConfigError) as info:
        load_config(bad)
    assert "\n" not in str(info.value) and str(bad) in str(info.value)


def test_ablation_switches_one_stage_per_row():
    from vsmatch.evaluation import ablation_configs

    base = config_from_dict({"scanline": {"enabled": True, "p1": 0.7},
                             "voting": {"enabled": True}, "fill": {"directions": 2},
                             "discontinuity": {"enabled": True},
                             "subpixel": {"enabled": True, "median": True},
                             "arms": {"kappa": 0.0}, "photometric": {"enabled": True},
                             "planes": {"enabled": True}})
    rows = list(ablation_configs(base).items())
    assert len(rows) == 12
    first = rows[0][1]
    assert not (first.scanline.enabled or first.voting.enabled or first.subpixel.enabled
                or first.photometric.enabled or first.planes.enabled)
    assert rows[1][1].scanline == base.scanline  # the base's own stage values
    assert rows[7][1] == base  # every stage on again
    assert rows[8][1].scanline.directions == 8 and "8 directions" in rows[8][0]
    assert rows[9][1].arms.shrink and "shrinking arm threshold on" in rows[9][0]
    assert rows[10][1].fill.directions == 16 and "16 directions" in rows[10][0]
    assert rows[11][1].arms.kappa == 0.5 and "kappa = 0.5" in rows[11][0]
    changed = [sum(a != b for a, b in zip(rows[i][1].to_dict().values(),
                                          rows[i + 1][1].to_dict().values()))
               for i in range(7)]
    assert changed == [1, 1, 1, 1, 1, 1, 1]
    for label, cfg in rows[8:]:  # one value away from the base
        assert sum(a != b for a, b in zip(cfg.to_dict().values(),
                                          base.to_dict().values())) == 1, label


def test_a_file_can_start_from_a_bundled_config(tmp_path):
    mine = tmp_path / "mine.yaml"
    mine.write_text("base: default\narms: {l2: 30}\nplanes: {enabled: false}\n")
    cfg = load_config(mine)
    default = load_config("default")
    assert cfg.arms.l2 == 30 and not cfg.planes.enabled
    assert cfg.cost == default.cost and cfg.photometric == default.photometric
    assert load_config(tmp_path / "mine.yaml").arms.tau1 == default.arms.tau1
    mine.write_text("base: nope\n")
    with pytest.raises(ConfigError, match="base must name a bundled config"):
        load_config(mine)


@pytest.mark.parametrize("text, key", [
    ("arms:\n  tau1: 10\narms:\n  tau2: 5\n", "arms"),
    ("base: default\nbase: fast\n", "base"),
    ("cost:\n  lambda_ad: 10\n  lambda_ad: 20\n", "lambda_ad")])
def test_a_key_given_twice_is_refused(tmp_path, text, key):
    """PyYAML keeps the last of two equal keys: one of the user's values would be
    dropped without a word."""
    path = tmp_path / "twice.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=f"'{key}' is given twice"):
        load_config(str(path))


def test_a_calibration_key_given_twice_is_refused(tmp_path):
    from vsmatch import rig
    from vsmatch.geometry import CalibrationError

    cam = ("  camera_model: pinhole\n  intrinsics: [300, 300, 80, 48]\n"
           "  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n"
           "  resolution: [160, 96]\n")
    path = tmp_path / "camchain.yaml"
    path.write_text("cam0:\n" + cam + "cam1:\n" + cam + "  T_cn_cnm1: [[1, 0, 0, -0.06], "
                    "[0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\ncam0:\n" + cam)
    with pytest.raises(CalibrationError, match="'cam0' is given twice"):
        rig.read_rig([path])


def test_a_huge_whole_number_is_out_of_range(tmp_path):
    path = tmp_path / "huge.yaml"
    path.write_text("arms:\n  l2: 123456789012345678901234567890\n")
    with pytest.raises(ConfigError, match=r"arms.l2 = .* is out of range"):
        load_config(str(path))


def test_a_budget_too_small_for_the_overlap_names_the_overlap(rng):
    from vsmatch import pipeline

    cfg = config_from_dict({"memory": {"overlap": 4096, "max_mb": 16}},
                           base=load_config("default"))
    tall = rng.integers(0, 256, (2000, 96, 3), dtype=np.uint8)
    # 2000 rows of 96 pixels x 17 disparities: 37 MB in one piece, less than two overlaps.
    with pytest.raises(ValueError, match="memory.overlap = 4096 .* at least 37 MB"):
        pipeline.check_pair(tall, tall.copy(), 16, cfg)
    # Views whose rows all fit the budget need no stripes, whatever the overlap.
    left = rng.integers(0, 256, (64, 96, 3), dtype=np.uint8)
    pipeline.check_pair(left, left.copy(), 16, cfg)
    assert np.isfinite(pipeline.run(left, left.copy(), max_disp=16, config=cfg).disparity).all()


def test_scheduling_sits_under_schedule_and_the_old_layout_is_still_read(tmp_path):
    new = tmp_path / "new.yaml"
    new.write_text("bands:\n  support: 3\n  scanline: true\n"
                   "schedule:\n  pyramid:\n    min_levels: 1\n  memory:\n    max_mb: 64\n")
    old = tmp_path / "old.yaml"
    old.write_text("pyramid:\n  min_levels: 1\n  support: 3\n  scanline: true\n"
                   "memory:\n  max_mb: 64\n")
    cfg = load_config(str(new))
    assert cfg == load_config(str(old))
    assert (cfg.bands.support, cfg.bands.scanline, cfg.pyramid.min_levels,
            cfg.memory.max_mb) == (3, True, 1, 64)
    # What eval writes beside its results reads back the same.
    written = tmp_path / "written.yaml"
    written.write_text(yaml.safe_dump(cfg.to_file_dict(), sort_keys=False))
    assert load_config(str(written)) == cfg
    assert set(cfg.to_file_dict()["schedule"]) == {"pyramid", "memory"}


@pytest.mark.parametrize("data, message", [
    ({"schedule": {"cost": {"lambda_ad": 3}}}, "unknown config key 'schedule.cost'"),
    ({"schedule": {"memory": {"max_mb": 64}}, "memory": {"overlap": 8}},
     "config section 'memory' is given twice"),
    ({"pyramid": {"support": 3}, "bands": {"support": 4}},
     "config value pyramid.support is given twice"),
    ({"schedule": [1]}, "config section 'schedule' must be a mapping"),
])
def test_a_schedule_that_cannot_be_read_is_one_line(data, message):
    with pytest.raises(ConfigError, match=message):
        config_from_dict(data)


def test_every_key_is_set_by_a_bundled_config():
    """A parameter no bundled config sets is an option nobody chose; the exceptions are
    named here with why."""
    import dataclasses
    from importlib import resources

    pending = {"cost.census_band", "noise.band_per_sigma"}  # the dead band: issue 35 decides
    given = set()
    for name in bundled_config_names():
        data = yaml.safe_load((resources.files("vsmatch") / "configs" / f"{name}.yaml")
                              .read_text())
        data.pop("base", None)
        data.update(data.pop("schedule", None) or {})
        given |= {f"{section}.{key}" for section, values in data.items() for key in values}
    every = {f"{s.name}.{k.name}" for s in dataclasses.fields(Config)
             for k in dataclasses.fields(s.default_factory())}
    assert every - given == pending


def test_with_changes_sets_keys_from_section_key_value_text():
    from vsmatch.config import with_changes

    cfg = with_changes("accurate", ["surfaces.bridge=128", "surfaces.contrast=null",
                                    "cost.lambda_ad=40.5"])
    assert cfg.surfaces.bridge == 128 and cfg.surfaces.contrast is None
    assert cfg.cost.lambda_ad == 40.5
    assert cfg.surfaces.refit == load_config("accurate").surfaces.refit  # the rest kept
    with pytest.raises(ConfigError):
        with_changes("default", ["surfaces.bridge=-1"])  # checked as a config file is


def test_a_mapping_is_taken_as_a_config_file_would_be(rng):
    """config= may be a mapping laid out as a YAML config (a base included); its mistakes
    are named as a file's are, and it is never taken for a file name."""
    import vsmatch

    cfg = load_config({"base": "fast", "arms": {"l1": 5}})
    assert cfg.arms.l1 == 5 and cfg.pyramid.min_levels == load_config("fast").pyramid.min_levels
    assert load_config({"arms": {"l1": 5}}).arms.l2 == Config().arms.l2  # the built-in values
    with pytest.raises(ConfigError, match="the config mapping: unknown config key 'arms.l9'"):
        load_config({"arms": {"l9": 5}})
    left = rng.integers(0, 256, (40, 64, 3), dtype=np.uint8)
    with pytest.raises(ConfigError, match="the config mapping: base must name"):
        vsmatch.match(left, left, max_disp=8, config={"base": "nope"})
