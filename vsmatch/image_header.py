"""An image's size read from its header, before anything is decoded.

A small file can decode to gigabytes (a 875 kB PNG of 30000 x 30000 pixels), so the size
is checked first. PNG, JPEG, BMP, PNM (PGM/PPM) and TIFF headers are read here; for
another format :func:`header_size` returns None and OpenCV's own pixel limit applies.
"""

from __future__ import annotations

import struct
from pathlib import Path

#: Bytes read from the start of a file; a JPEG's frame header may follow long metadata,
#: so JPEG markers are walked through the whole file instead.
HEAD_BYTES = 4096


def header_size(path: str | Path) -> tuple[int, int] | None:
    """``(width, height)`` from the header of ``path``, or None for a format not read
    here or a header that does not parse (OpenCV then reports the file)."""
    with open(path, "rb") as fh:
        head = fh.read(HEAD_BYTES)
        try:
            if head.startswith(b"\x89PNG\r\n\x1a\n") and head[12:16] == b"IHDR":
                return struct.unpack(">II", head[16:24])
            if head.startswith(b"BM") and len(head) >= 26:
                width, height = struct.unpack("<ii", head[18:26])
                return abs(width), abs(height)
            if head[:2] in (b"P2", b"P3", b"P5", b"P6"):
                return _pnm_size(head)
            if head[:4] in (b"II*\x00", b"MM\x00*"):
                return _tiff_size(fh, head[:2] == b"II")
            if head.startswith(b"\xff\xd8"):
                return _jpeg_size(fh)
        except (struct.error, ValueError, IndexError):
            return None
    return None


def _pnm_size(head: bytes) -> tuple[int, int] | None:
    words = []
    for line in head[2:].split(b"\n"):
        words += line.split(b"#")[0].split()
        if len(words) >= 2:
            return int(words[0]), int(words[1])
    return None


def _jpeg_size(fh) -> tuple[int, int] | None:
    fh.seek(2)
    while True:
        marker = fh.read(2)
        if len(marker) < 2 or marker[0] != 0xFF:
            return None
        kind = marker[1]
        if kind in (0xD8, 0x01) or 0xD0 <= kind <= 0xD7:  # markers without a length
            continue
        length = struct.unpack(">H", fh.read(2))[0]
        # SOF0..SOF15 hold the frame size, except DHT (C4), JPG (C8) and DAC (CC).
        if 0xC0 <= kind <= 0xCF and kind not in (0xC4, 0xC8, 0xCC):
            height, width = struct.unpack(">xHH", fh.read(5))
            return width, height
        fh.seek(length - 2, 1)


def _tiff_size(fh, little: bool) -> tuple[int, int] | None:
    order = "<" if little else ">"
    fh.seek(4)
    offset = struct.unpack(order + "I", fh.read(4))[0]
    fh.seek(offset)
    count = struct.unpack(order + "H", fh.read(2))[0]
    size = {}
    for _ in range(count):
        tag, kind, _n, value = struct.unpack(order + "HHI4s", fh.read(12))
        if tag in (256, 257):  # ImageWidth, ImageLength: SHORT or LONG
            size[tag] = struct.unpack(order + ("H" if kind == 3 else "I"),
                                      value[:2] if kind == 3 else value)[0]
    if 256 in size and 257 in size:
        return size[256], size[257]
    return None
