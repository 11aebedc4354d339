"""The photometric stage: learning the right view's colour map from matched pixels."""

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from vsmatch import photometric, pipeline
from vsmatch.cli import main
from vsmatch.config import ConfigError, PhotometricConfig, config_from_dict, load_config
from vsmatch.datasets import load_dataset
from vsmatch.evaluation import score_scene, scoring_for
from vsmatch.synthetic import make_pair


def _exposed(values: np.ndarray) -> np.ndarray:
    """A brighter exposure that saturates: what MotorcycleE's right view looks like."""
    return np.clip(1.6 * values.astype(np.float32) + 10, 0, 255).astype(np.uint8)


def test_the_map_undoes_an_exposure_change_learnt_at_matched_pixels(rng):
    left = rng.integers(0, 150, size=(60, 80, 3), dtype=np.uint8)
    shift = 5
    right = np.zeros_like(left)
    right[:, :-shift] = left[:, shift:]  # left pixel x is right pixel x - 5
    right = _exposed(right)
    disp = np.full(left.shape[:2], shift, np.float32)
    matched = np.zeros(left.shape[:2], bool)
    matched[:, shift:] = True
    correction = photometric.learn(left, right, disp, matched)
    assert correction.before > 40 and correction.residual <= 1.0
    grey = np.arange(150)
    back = correction.table[_exposed(grey), 0].astype(int)
    assert np.abs(back - grey).max() <= 2
    mapped = photometric.apply(right, correction)
    assert np.abs(mapped[:, :-shift].astype(int) - left[:, shift:]).mean() < 1.0


def test_levels_the_matches_do_not_hold_keep_their_steps(rng):
    """Matches that hold right levels 20-129 only (a bright thin object unmatched): the
    map learns the exposure's offset there and carries it on in steps of one, rather than
    putting every level above onto the left's brightest (which flattened wires' texture)."""
    left = rng.integers(20, 130, size=(60, 80), dtype=np.uint8)
    right = (left + 10).astype(np.uint8)  # right pixel x is left pixel x, 10 levels up
    correction = photometric.learn(left, right, np.zeros((60, 80), np.float32),
                                   np.ones((60, 80), bool))
    table = correction.table[:, 0].astype(int)
    assert np.abs(table[30:140] - (np.arange(30, 140) - 10)).max() <= 1  # learnt
    np.testing.assert_array_equal(table[140:], np.arange(140, 256) - 10)  # one to one
    np.testing.assert_array_equal(table[:30], np.maximum(np.arange(30) - 10, 0))


def test_unrelated_views_leave_a_large_residual(rng):
    left = rng.integers(0, 256, size=(60, 80, 3), dtype=np.uint8)
    right = rng.integers(0, 256, size=(60, 80, 3), dtype=np.uint8)
    correction = photometric.learn(left, right, np.zeros((60, 80), np.float32),
                                   np.ones((60, 80), bool))
    assert correction.residual > 40  # quantiles agree; pixels do not


def test_too_few_matches_learn_nothing(rng):
    image = rng.integers(0, 256, size=(20, 20), dtype=np.uint8)
    assert photometric.learn(image, image, np.zeros((20, 20), np.float32),
                             np.ones((20, 20), bool)) is None  # 400 < MIN_MATCHES


def test_colour_weight_fades_linearly():
    cfg = PhotometricConfig(fade_from=5, fade_to=10)
    assert [photometric.colour_weight(r, cfg) for r in (0, 5, 7.5, 10, 40)] == \
        [1.0, 1.0, 0.5, 0.0, 0.0]


def test_fade_bounds_are_checked():
    with pytest.raises(ConfigError, match="fade_from < fade_to"):
        config_from_dict({"photometric": {"fade_from": 6, "fade_to": 6}})


def test_the_pipeline_learns_an_exposure_change_and_keeps_the_colour_term():
    pair = make_pair(width=240, height=180)
    same = pipeline.run(pair.left, pair.right, max_disp=pair.max_disp)
    assert same.photometric.before < 3 and same.colour_weight == 1.0
    brighter = pipeline.run(pair.left, _exposed(pair.right // 2 + 40), max_disp=pair.max_disp)
    assert brighter.photometric.before > 20 and brighter.photometric.residual < 3
    assert brighter.colour_weight == 1.0
    bad = {name: float(np.mean(np.abs(r.disparity - pair.disparity)[pair.nonocc] > 1))
           for name, r in (("same", same), ("brighter", brighter))}
    assert bad["brighter"] < bad["same"] + 0.02, bad


@pytest.mark.data
@pytest.mark.parametrize("name, with_stage, without", [
    ("MotorcycleE", 3.3, 3.5), ("ArtL", 6.6, 7.3), ("Piano", 10.5, 13.0), ("PianoL", 20.4, 23.5)])
def test_exposure_and_lighting_scenes_gain(data_dir, name, with_stage, without):
    """Middlebury 2014 quarter size, bad 2.0 nonocc, measured with and without the stage
    (``python scripts/exposure.py``): MotorcycleE 2.90 / 3.77, ArtL 6.30 / 7.62, Piano
    9.61 / 13.79, PianoL 19.42 / 23.94 (its lighting change: the colour term off)."""
    scene = next(s for s in load_dataset("middlebury2014-quarter", data_dir) if s.name == name)
    scoring = scoring_for("middlebury2014-quarter")
    off = config_from_dict({"photometric": {"enabled": False}}, base=load_config("default"))
    figures = {}
    for label, cfg in (("on", "default"), ("off", off)):
        disp = pipeline.match(scene.left, scene.right, max_disp=scene.max_disp, config=cfg)
        figures[label] = score_scene(disp, scene, scoring)["nonocc"]
    assert figures["on"] <= with_stage and figures["off"] > without, figures
    if name == "PianoL":  # the light moved: no colour map explains it
        fit = pipeline.run(scene.left, scene.right, max_disp=scene.max_disp)
        assert fit.photometric.excess > 10 and fit.colour_weight == 0.0


def test_verbose_run_reports_the_exposure_map(tmp_path):
    pair = make_pair(width=240, height=180)
    cv2.imwrite(str(tmp_path / "l.png"), pair.left)
    cv2.imwrite(str(tmp_path / "r.png"), _exposed(pair.right // 2 + 40))
    result = CliRunner().invoke(main, ["--verbose", "run", str(tmp_path / "l.png"),
                                       str(tmp_path / "r.png"), "-o", str(tmp_path / "d.pfm"),
                                       "--max-disp", str(pair.max_disp)])
    assert result.exit_code == 0, result.output
    line = next(t for t in result.output.splitlines() if t.startswith("exposure:"))
    assert "after the right view's colour map" in line and "colour term weight 1.00" in line


def test_grey_views_get_a_one_channel_map():
    pair = make_pair(width=240, height=180)
    left = cv2.cvtColor(pair.left, cv2.COLOR_BGR2GRAY)
    right = _exposed(cv2.cvtColor(pair.right, cv2.COLOR_BGR2GRAY) // 2 + 40)
    result = pipeline.run(left, right, max_disp=pair.max_disp)
    assert result.photometric.table.shape == (256, 1)
    assert result.photometric.before > 20 and result.photometric.residual < 3


@pytest.mark.parametrize("shape, box", [((31, 45, 7), 9), ((4, 6, 3), 9), ((1, 12, 2), 5),
                                        ((20, 17, 5), 8), ((3, 3, 2), 1)])
def test_the_box_blur_is_opencvs_blur(rng, shape, box):
    """The quick first match (and the confidence's texture) average with a parallel kernel
    in place of cv2.blur (which runs on one core): the same values, windows wider than the
    image and even ones included."""
    from vsmatch.images import box_blur

    volume = (rng.random(shape, dtype=np.float32) * 3).astype(np.float32)
    out = box_blur(volume, box)
    assert out.tobytes() == cv2.blur(volume.copy(), (box, box)).tobytes()


def test_matched_colours_and_the_corrected_right_view_as_numpy_takes_them(rng):
    """The kernels that gather the matched pixels' colours and map the right view give
    what the NumPy expressions give."""
    left = rng.integers(0, 256, (23, 31, 3), dtype=np.uint8)
    right = rng.integers(0, 256, (23, 31, 3), dtype=np.uint8)
    disp = (rng.random((23, 31)) * 12).astype(np.float32)
    matched = rng.random((23, 31)) < 0.6
    ys, xr, at_left, at_right = photometric._matched_colours(left, right, disp, matched)
    yy, xx = np.nonzero(matched)
    rr = xx - np.rint(disp[yy, xx]).astype(np.int64)
    inside = rr >= 0
    yy, xx, rr = yy[inside], xx[inside], rr[inside]
    assert (ys == yy).all() and (xr == rr).all()
    assert (at_left == left[yy, xx]).all() and (at_right == right[yy, rr]).all()
    table = rng.integers(0, 256, (256, 3), dtype=np.uint8)
    field = (rng.normal(0, 6, (12, 16, 3))).astype(np.float32)
    correction = photometric.Correction(table=table, residual=0.0, before=0.0, matches=1,
                                        noise=0.0, field=field)
    mapped = np.stack([table[right[:, :, c], c] for c in range(3)], axis=-1)
    big = cv2.resize(field, (31, 23), interpolation=cv2.INTER_LINEAR)
    expected = np.clip(np.rint(mapped + big), 0, 255).astype(np.uint8)
    assert (photometric.apply(right, correction) == expected).all()
