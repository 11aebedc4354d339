"""Image files: huge headers refused before decoding, grey beside colour named."""

import struct
import subprocess
import sys
import zlib

import cv2
import numpy as np
import pytest
from cli_helpers import invoke, one_line_error
from conftest import random_pair

from vsmatch import io, pipeline


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
    # A small limit names a small size as it is, not as "0 megapixels".
    (tmp_path / "small.png").write_bytes(png_header_only(450, 375))
    with pytest.raises(io.ImageError, match="is 0.17 megapixels, over the limit of 0.01"):
        io.read_image(tmp_path / "small.png", max_megapixels=0.01)


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


def test_grey_with_colour_is_named_as_such(rng):
    left, right = random_pair(rng, height=40, width=64)
    with pytest.raises(ValueError, match="grey .* colour"):
        pipeline.match(cv2.cvtColor(left, cv2.COLOR_BGR2GRAY), right, max_disp=8)


def test_a_text_file_named_mp4_is_one_line_on_the_real_stderr(tmp_path):
    (tmp_path / "l.mp4").write_text("not a video\n")
    (tmp_path / "r.mp4").write_text("not a video\n")
    proc = subprocess.run([sys.executable, "-m", "vsmatch", "video", tmp_path / "l.mp4",
                           tmp_path / "r.mp4", "-o", tmp_path / "d.avi"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1
    assert proc.stderr.strip().splitlines() == [f"Error: {tmp_path / 'l.mp4'}: cannot open "
                                                "this video"]
