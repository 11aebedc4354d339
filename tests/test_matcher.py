"""StereoMatcher (issue 20): made once, used for many frames, the same bytes as match()."""

import cv2
import numpy as np

import vsmatch
from vsmatch import rig, search_range


def textured(rng, shift, height=80, width=160):
    base = rng.integers(0, 256, (height // 4 + 1, (width + shift) // 4 + 2, 3), np.uint8)
    wide = cv2.resize(base, (base.shape[1] * 4, base.shape[0] * 4),
                      interpolation=cv2.INTER_CUBIC)[:height]
    # Left pixel x shows what right pixel x - shift shows.
    return (np.ascontiguousarray(wide[:, :width]),
            np.ascontiguousarray(wide[:, shift:shift + width]))


def test_compute_gives_what_match_gives(rng):
    left, right = textured(rng, 6)
    stereo = vsmatch.StereoMatcher(max_disp=16, config="paper")
    for _ in range(2):
        np.testing.assert_array_equal(stereo.compute(left, right),
                                      vsmatch.match(left, right, max_disp=16, config="paper"))
    assert stereo.frames == 2
    full = stereo.result(left, right)
    assert full.confidence.shape == left.shape[:2] and full.search_range == (0, 16)


def test_the_found_range_is_kept_until_the_scene_comes_closer(rng, monkeypatch):
    calls = []
    real = search_range.estimate_disparity_range

    def counting(left, right, *args, **kwargs):
        calls.append(1)
        return real(left, right, *args, **kwargs)

    monkeypatch.setattr(search_range, "estimate_disparity_range", counting)
    stereo = vsmatch.StereoMatcher()
    far = textured(rng, 6)
    for _ in range(3):
        stereo.compute(*far)
    assert len(calls) == 1 and stereo.range[1] >= 6
    first_top = stereo.range[1]
    near = textured(rng, first_top + 10, width=240)
    stereo.compute(*near)  # the top crowds: found again on the next frame
    stereo.compute(*near)
    assert len(calls) == 2 and stereo.range[1] >= first_top + 10


def test_a_raw_rig_is_rectified_with_maps_made_once(rng, monkeypatch, tmp_path):
    size = (160, 80)
    K = np.array([[150.0, 0, 80], [0, 150.0, 40], [0, 0, 1]])
    fs = cv2.FileStorage(str(tmp_path / "stereo.yaml"), cv2.FILE_STORAGE_WRITE)
    for key, value in (("K1", K), ("K2", K), ("D1", np.zeros((1, 5))), ("D2", np.zeros((1, 5))),
                       ("R", np.eye(3)), ("T", np.array([[-1.0], [0], [0]]))):
        fs.write(key, value)
    fs.release()
    made = []
    real = rig.Rectifier.__init__

    def counting(self, *args, **kwargs):
        made.append(1)
        real(self, *args, **kwargs)

    monkeypatch.setattr(rig.Rectifier, "__init__", counting)
    stereo = vsmatch.StereoMatcher(max_disp=16, calib=tmp_path / "stereo.yaml",
                                   config="paper")
    left, right = textured(rng, 6, height=size[1], width=size[0])
    for _ in range(3):
        disp = stereo.compute(left, right)
    assert len(made) == 1 and stereo.camera.baseline == 1.0
    assert np.mean(np.abs(disp[10:-10, 30:-10] - 6) < 1) > 0.8
