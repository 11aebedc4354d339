import cv2
import numpy as np
import pytest

from vsmatch import io


def test_pfm_round_trip_keeps_values_and_invalid(tmp_path, rng):
    disp = rng.random((13, 17), dtype=np.float32) * 60
    disp[3, 4] = np.inf
    path = tmp_path / "d.pfm"
    io.write_disparity(path, disp)
    back = io.read_disparity(path)
    np.testing.assert_array_equal(back, disp)
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left


def test_pfm_is_middlebury_convention(tmp_path):
    # Bottom row first, negative scale = little endian (Middlebury's PFM files).
    disp = np.arange(6, dtype=np.float32).reshape(2, 3)
    path = tmp_path / "d.pfm"
    io.write_disparity(path, disp)
    raw = path.read_bytes()
    header_end = raw.index(b"\n", raw.index(b"\n", raw.index(b"\n") + 1) + 1) + 1
    magic, width, height, scale = raw[:header_end].split()
    assert (magic, int(width), int(height), float(scale)) == (b"Pf", 3, 2, -1.0)
    data = np.frombuffer(raw[header_end:], dtype="<f4").reshape(2, 3)
    np.testing.assert_array_equal(data[::-1], disp)


def test_png16_round_trip_kitti_convention(tmp_path):
    disp = np.array([[0.0, 1.5, 63.25], [np.inf, 0.001, 200.0]], np.float32)
    path = tmp_path / "d.png"
    io.write_disparity(path, disp)
    raw = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert raw.dtype == np.uint16
    # A valid disparity below 1/256 is stored as 1, since 0 means invalid.
    assert raw.tolist() == [[1, 384, 16192], [0, 1, 51200]]
    back = io.read_disparity(path)
    assert np.isinf(back[1, 0])  # 0 means invalid
    assert back[0, 1] == 1.5 and back[1, 2] == 200.0


def test_unknown_disparity_format_is_refused(tmp_path):
    with pytest.raises(ValueError, match="unknown disparity format"):
        io.write_disparity(tmp_path / "d.tif", np.zeros((2, 2), np.float32))


@pytest.mark.parametrize("make", [
    lambda a: cv2.cvtColor(a, cv2.COLOR_BGR2GRAY),
    lambda a: a.astype(np.uint16) * 257,
    lambda a: cv2.cvtColor(a, cv2.COLOR_BGR2BGRA),
])
def test_grey_16bit_and_rgba_inputs_become_bgr8(tmp_path, rng, make):
    base = rng.integers(0, 256, size=(6, 7, 3), dtype=np.uint8)
    path = tmp_path / "in.png"
    cv2.imwrite(str(path), make(base))
    image = io.read_image(path)
    assert image.shape == (6, 7, 3) and image.dtype == np.uint8


def test_16bit_input_keeps_the_top_byte(tmp_path, rng):
    base = rng.integers(0, 256, size=(6, 7, 3), dtype=np.uint8)
    cv2.imwrite(str(tmp_path / "a.png"), base.astype(np.uint16) * 257)
    np.testing.assert_array_equal(io.read_image(tmp_path / "a.png"), base)


def test_unreadable_inputs_give_one_line_errors(tmp_path):
    with pytest.raises(io.ImageError, match="file not found"):
        io.read_image(tmp_path / "nope.png")
    (tmp_path / "text.png").write_text("not an image")
    with pytest.raises(io.ImageError, match="not a readable image"):
        io.read_image(tmp_path / "text.png")


def test_failed_write_leaves_no_file(tmp_path):
    def broken(tmp):
        with open(tmp, "wb") as fh:
            fh.write(b"partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        io.write_atomic(tmp_path / "out.pfm", broken)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.data
def test_twelve_bit_views_in_16_bit_pngs_match_as_the_8_bit_ones(data_dir, tmp_path):
    """A machine-vision camera's 12-bit values (0..4095) in 16-bit PNGs keep their 8 most
    significant bits in use (not the top byte, 0..15): the same disparities as the 8-bit
    pair, and the range is still found from the pair."""
    from click.testing import CliRunner
    from vsmatch.cli import main

    for name in ("imL", "imR"):
        view = cv2.imread(str(data_dir / "middlebury2" / "tsukuba" / f"{name}.png"))
        cv2.imwrite(str(tmp_path / f"{name}8.png"), view)
        cv2.imwrite(str(tmp_path / f"{name}12.png"), view.astype(np.uint16) * 16 + 7)
    outputs = {}
    for bits in (8, 12):
        out = tmp_path / f"d{bits}.pfm"
        result = CliRunner().invoke(main, ["run", str(tmp_path / f"imL{bits}.png"),
                                           str(tmp_path / f"imR{bits}.png"), "-o", str(out),
                                           "--config", "fast"])
        assert result.exit_code == 0, result.output
        outputs[bits] = out.read_bytes()
    assert outputs[8] == outputs[12]


def test_the_same_file_as_both_views_is_refused(tmp_path, rng):
    view = rng.integers(0, 256, (32, 48, 3), dtype=np.uint8)
    cv2.imwrite(str(tmp_path / "v.png"), view)
    with pytest.raises(io.ImageError, match="the same file"):
        io.read_pair(tmp_path / "v.png", tmp_path / "v.png")


@pytest.mark.parametrize("mount", [True, False], ids=["tmpfs", "file-size-limit"])
def test_a_full_disk_is_an_error_for_every_format(small_disk, rng, mount):
    """Some OpenCV encoders (PFM in 4.x) said they had written a file that a full disk cut
    short: the bytes are written by Python, whose write raises. Also where no tmpfs can be
    mounted (the fixture's file-size limit)."""
    disk = small_disk(16, mount=mount)
    images = {"d.pfm": rng.random((256, 256)).astype(np.float32),  # 256 kB
              "d.png": rng.integers(0, 65535, (256, 256), dtype=np.uint16)}
    for name, image in images.items():
        with pytest.raises(OSError, match="could not be written"):
            io.imwrite_atomic(disk / name, image)
        assert not list(disk.iterdir())
