"""Calibration files, depth and point clouds from a left-view disparity.

The camera model is the rectified pair's: depth ``Z = f B / (d + doffs)`` in the
baseline's unit, and a pixel (x, y) of the left view at depth Z is the point
``((x - cx) Z / f, (y - cy) Z / fy, Z)`` in the left camera's frame (x right, y down,
z forward), as OpenCV's ``reprojectImageTo3D`` gives.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np


#: The largest float32.
FLOAT32_MAX = float(np.finfo(np.float32).max)
#: The smallest normal float32, and the largest disparity a depth is taken of (a view's
#: width; 2**20 px is beyond any camera's): f B / that must stay a normal float32.
FLOAT32_TINY = float(np.finfo(np.float32).tiny)
MAX_DISPARITY = 2.0**20


class CalibrationError(ValueError):
    """A calibration that cannot be read or used; the message is one line."""


@dataclass(frozen=True)
class Calibration:
    """What depth and 3D points need from a rectified stereo pair's calibration."""

    focal: float  # f, pixels (horizontal)
    baseline: float  # B, in the unit depth comes out in (Middlebury mm, KITTI m)
    cx: float | None = None  # principal point of the left view; None: the image centre
    cy: float | None = None
    doffs: float = 0.0  # x-difference of the principal points (right minus left), pixels
    focal_y: float | None = None  # fy, when it differs from f
    ndisp: int | None = None  # Middlebury's search range 0 .. ndisp - 1, when given
    size: tuple[int, int] | None = None  # (width, height) of the views, when given
    # The search's bottom (vsmatch's ``dmin`` in calib.txt: a verged rig's range starts
    # below 0); the range is min_disp .. min_disp + ndisp - 1.
    min_disp: int = 0

    def __post_init__(self):
        for name in ("focal", "baseline", "cx", "cy", "doffs", "focal_y"):
            value = getattr(self, name)
            if value is None and name in ("focal", "baseline", "doffs"):
                raise CalibrationError(f"{name} must be a number, got None")
            if value is not None and (isinstance(value, bool) or not isinstance(
                    value, (int, float, np.integer, np.floating))):
                raise CalibrationError(f"{name} must be a number, got {value!r}"[:120])
            if value is not None and not np.isfinite(value):
                raise CalibrationError(f"{name} must be a finite number, got {value}")
        for name in ("ndisp", "min_disp"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(
                    value, (int, np.integer))):
                raise CalibrationError(f"{name} must be a whole number, got {value!r}"[:120])
        if not self.focal > 0:
            raise CalibrationError(f"focal length must be positive, got {self.focal}")
        if self.focal_y is not None and not self.focal_y > 0:
            raise CalibrationError(f"the vertical focal length must be positive, got "
                                   f"{self.focal_y:g}")
        if not self.baseline > 0:
            raise CalibrationError(f"baseline must be positive, got {self.baseline}")
        if self.ndisp is not None and self.ndisp < 1:
            raise CalibrationError(f"ndisp must be at least 1, got {self.ndisp}")

    def search_range_for(self, width: int) -> int | None:
        """``ndisp``, unless it is a placeholder: some benchmarks write the image width (or
        any number of half the width or more) for "unknown"; real ranges reach a quarter
        of the width at most (Middlebury 2014's largest, Jadeplant's, is 0.24)."""
        if self.ndisp is None or self.ndisp >= width / 2:
            return None
        return self.ndisp

    def search_range(self, width: int) -> tuple[int, int] | None:
        """``(min_disp, min_disp + ndisp - 1)``, or None where ndisp is not given or is a
        placeholder (:meth:`search_range_for`)."""
        ndisp = self.search_range_for(width)
        return None if ndisp is None else (self.min_disp, self.min_disp + ndisp - 1)

    def lowest_disparity(self) -> int:
        """The smallest whole disparity a real point can have: a point at infinity has
        ``d = -doffs``, and below it points would lie behind the cameras."""
        return math.floor(-self.doffs)

    def depth_problem(self) -> str | None:
        """Why depths of this camera do not fit float32, or None: the nearest depth
        f B / (d + doffs) at a disparity step of 1/256 px must stay finite."""
        if self.focal * self.baseline * 256 > FLOAT32_MAX:
            return (f"focal length x baseline = {self.focal * self.baseline:.3g} makes "
                    "depths too large for float32; give the baseline in a larger unit")
        # The farthest right pixel of the widest view float32 reads: depths not 0.
        if self.focal * self.baseline / MAX_DISPARITY < FLOAT32_TINY:
            return (f"focal length x baseline = {self.focal * self.baseline:.3g} makes "
                    "depths too small for float32 (they would read 0); check the focal "
                    "length, or give the baseline in a smaller unit")
        return None

    def size_problem(self, shape: tuple[int, ...]) -> str | None:
        """Why views of ``shape`` (H, W, ...) do not fit this calibration, or None: another
        size than the calibration's, the left principal point outside the views, or the
        right one (``cx + doffs``) more than a view's width away (no rectified rig has
        them so: depths and clouds would be upside down, sheared or empty)."""
        height, width = shape[:2]
        if self.size is not None and tuple(self.size) != (width, height):
            return (f"the calibration is for {self.size[0]}x{self.size[1]} views (width, "
                    f"height), these are {width}x{height}")
        cx, cy = self.principal_point(shape)
        if not (0 <= cx < width and 0 <= cy < height):
            return (f"the principal point ({cx:g}, {cy:g}) lies outside the {width}x{height} "
                    "views")
        if abs(self.doffs) >= width:
            return (f"doffs = {self.doffs:g} puts the right view's principal point more than "
                    f"the views' width ({width}) away from the left one's")
        return None

    def principal_point(self, shape: tuple[int, ...]) -> tuple[float, float]:
        height, width = shape[:2]
        return (self.cx if self.cx is not None else (width - 1) / 2.0,
                self.cy if self.cy is not None else (height - 1) / 2.0)


def read_calibration(path: str | Path) -> Calibration:
    """A Middlebury 2014 ``calib.txt`` or a KITTI ``calib_cam_to_cam.txt``.

    Middlebury: ``f``, ``cx``, ``cy`` from ``cam0``, ``doffs``, ``baseline`` (mm),
    ``ndisp``. KITTI: ``f``, ``cx``, ``cy`` from ``P_rect_02``, the baseline (m) from
    the x-translations of ``P_rect_02`` and ``P_rect_03``, ``doffs`` from their cx.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")  # a BOM (Windows editors) dropped
    except FileNotFoundError:
        raise CalibrationError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CalibrationError(f"{path}: cannot read the calibration ({exc})") from None
    fields = {}
    for line in text.splitlines():
        key, sep, value = line.partition("=") if "=" in line else line.partition(":")
        if sep:
            fields[key.strip()] = value.strip()
    try:
        if "cam0" in fields:
            return _middlebury(fields)
        if "P_rect_02" in fields and "P_rect_03" in fields:
            return _kitti(fields)
    except (KeyError, ValueError) as exc:
        raise CalibrationError(f"{path}: malformed calibration ({_describe(exc)})") from None
    except CalibrationError as exc:
        raise CalibrationError(f"{path}: {exc}") from None
    raise CalibrationError(f"{path}: not a Middlebury calib.txt (cam0=...) or a KITTI "
                           "calib_cam_to_cam.txt (P_rect_02, P_rect_03), nor a raw rig "
                           "(OpenCV stereoCalibrate YAML, XML or JSON: K1, D1, K2, D2, R, "
                           "T; Kalibr camchain; ROS camera_info or EuRoC sensor.yaml, left "
                           "and right)")


def _describe(exc: Exception) -> str:
    return f"missing {exc}" if isinstance(exc, KeyError) else str(exc)


def _numbers(fields: dict[str, str], key: str) -> np.ndarray:
    """The finite numbers of ``fields[key]``; ValueError naming the key otherwise."""
    values = [v for v in re.split(r"[\s;,\[\]]+", fields[key]) if v]
    try:
        numbers = np.array([float(v) for v in values], dtype=np.float64)
    except ValueError:
        raise ValueError(f"{key} is not a list of numbers") from None
    if not np.all(np.isfinite(numbers)):
        raise ValueError(f"{key} holds a number that is not finite")
    return numbers


def _number(fields: dict[str, str], key: str) -> float:
    numbers = _numbers(fields, key)
    if numbers.size != 1:
        raise ValueError(f"{key} must be one number")
    return float(numbers[0])


def _middlebury(fields: dict[str, str]) -> Calibration:
    cam0 = _numbers(fields, "cam0")
    if cam0.size != 9:
        raise ValueError("cam0 must be a 3x3 matrix")
    if cam0[3] != 0 or not np.allclose(cam0[6:], (0, 0, 1)):
        raise ValueError("cam0 is not a camera matrix [f 0 cx; 0 fy cy; 0 0 1]")
    if "cam1" in fields:
        _check_rectified(cam0, _numbers(fields, "cam1"))
    ndisp = _integer(fields, "ndisp") if "ndisp" in fields else None
    doffs = _number(fields, "doffs") if "doffs" in fields else 0.0
    min_disp = _integer(fields, "dmin") if "dmin" in fields else 0
    size = None
    if "width" in fields and "height" in fields:
        size = (_whole(fields, "width"), _whole(fields, "height"))
    return Calibration(focal=cam0[0], baseline=_number(fields, "baseline"), cx=cam0[2],
                       cy=cam0[5], doffs=doffs, focal_y=cam0[4], ndisp=ndisp, size=size,
                       min_disp=min_disp)


def _check_rectified(cam0: np.ndarray, cam1: np.ndarray) -> None:
    """A rectified pair's two cameras share their focal lengths and their principal
    point's row (cam1's cx may differ: doffs); otherwise the views are not rectified."""
    if cam1.size != 9:
        raise ValueError("cam1 must be a 3x3 matrix")
    for name, k, tolerance in (("focal length", 0, 1e-3 * abs(cam0[0])),
                               ("vertical focal length", 4, 1e-3 * abs(cam0[4])),
                               ("principal point's row cy", 5, 0.5)):
        if not abs(cam1[k] - cam0[k]) <= tolerance:
            raise ValueError(f"cam1's {name} {cam1[k]:g} differs from cam0's {cam0[k]:g}: "
                             "the views are not rectified as one camera (rectify them "
                             "first, from the raw rig's calibration)")


def _integer(fields: dict[str, str], key: str) -> int:
    value = _number(fields, key)
    if value != int(value):
        raise ValueError(f"{key} must be a whole number")
    return int(value)


def _whole(fields: dict[str, str], key: str) -> int:
    value = _number(fields, key)
    if value != int(value) or value < 1:
        raise ValueError(f"{key} must be a whole number of at least 1")
    return int(value)


def _kitti(fields: dict[str, str]) -> Calibration:
    p2, p3 = _numbers(fields, "P_rect_02"), _numbers(fields, "P_rect_03")
    if p2.size != 12 or p3.size != 12:
        raise ValueError("P_rect_02 and P_rect_03 must be 3x4 matrices")
    focal = p2[0]
    # P = K [I | t]: P[0, 3] = f t_x; the right camera sits at +B along x.
    baseline = (p2[3] - p3[3]) / focal
    size = None
    if "S_rect_02" in fields:  # the rectified views' size (width, height)
        rect = _numbers(fields, "S_rect_02")
        if rect.size != 2 or not np.all(rect == np.round(rect)) or not np.all(rect >= 1):
            raise ValueError("S_rect_02 must be two whole numbers (width, height)")
        size = (int(rect[0]), int(rect[1]))
    return Calibration(focal=focal, baseline=baseline, cx=p2[2], cy=p2[6],
                       doffs=p3[2] - p2[2], focal_y=p2[5], size=size)


def depth_from_disparity(disp: np.ndarray, calib: Calibration) -> np.ndarray:
    """Depth ``f B / (d + doffs)`` (float32, the baseline's unit); ``inf`` where the
    disparity is invalid or ``d + doffs <= 0`` (a point at or beyond infinity)."""
    _check_calibration_argument(calib)
    disp = _disparity_argument(disp)
    denominator = disp + calib.doffs
    depth = np.full(disp.shape, np.inf, dtype=np.float32)
    ok = np.isfinite(denominator) & (denominator > 0)
    depth[ok] = (calib.focal * calib.baseline / denominator[ok]).astype(np.float32)
    return depth


def depth_of(calib: Calibration | None):
    """``d -> f B / (d + doffs)`` for one disparity (``inf`` at or beyond infinity), or
    None without a calibration: a colour bar's labels in depth."""
    if calib is None:
        return None
    return lambda d: float(depth_from_disparity(np.array([[d]], np.float32), calib)[0, 0])


def point_cloud(disp: np.ndarray, image: np.ndarray, calib: Calibration, *,
                max_depth: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The 3D points of the valid pixels, in the left camera's frame, and their colours.

    Returns ``points`` (N, 3) float32 (x right, y down, z forward, the baseline's unit)
    and ``colours`` (N, 3) uint8 in RGB order, row by row. ``image`` is the left view,
    BGR or grey. With ``max_depth``, points farther than it are left out.
    """
    disp = _disparity_argument(disp)
    if not isinstance(image, np.ndarray) or image.dtype != np.uint8 or not (
            image.ndim == 2 or (image.ndim == 3 and image.shape[2] == 3)):
        raise ValueError("image must be the left view as (H, W, 3) BGR or (H, W) grey "
                         f"uint8, got {_describe_array(image)}")
    if image.shape[:2] != disp.shape:
        raise ValueError(f"image is {image.shape[1]}x{image.shape[0]} but the disparity "
                         f"{disp.shape[1]}x{disp.shape[0]}: give the left view of the pair")
    if max_depth is not None and (isinstance(max_depth, bool) or not isinstance(
            max_depth, (int, float, np.number)) or not max_depth > 0
            or not np.isfinite(max_depth)):
        raise ValueError(f"max_depth must be a positive finite number, got {max_depth!r}")
    depth = depth_from_disparity(disp, calib)
    keep = np.isfinite(depth)
    if max_depth is not None:
        keep &= depth <= max_depth
    ys, xs = np.nonzero(keep)
    z = depth[ys, xs].astype(np.float64)
    cx, cy = calib.principal_point(disp.shape)
    focal_y = calib.focal_y or calib.focal
    points = np.stack([(xs - cx) * z / calib.focal, (ys - cy) * z / focal_y, z],
                      axis=1).astype(np.float32)
    pixels = image[ys, xs]
    colours = (np.repeat(pixels[:, None], 3, axis=1) if image.ndim == 2
               else pixels[:, ::-1]).astype(np.uint8)
    return points, np.ascontiguousarray(colours)


def _check_calibration_argument(calib) -> None:
    if not isinstance(calib, Calibration):
        raise ValueError("calib must be a vsmatch.Calibration (vsmatch.read_calibration "
                         f"reads a file), got {type(calib).__name__}")


def _disparity_argument(disp) -> np.ndarray:
    """``disp`` as an (H, W) float64 array, or a ValueError naming the argument."""
    try:
        array = np.asarray(disp, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"disparity must be an (H, W) array of numbers, got "
                         f"{type(disp).__name__}") from None
    if array.ndim != 2:
        raise ValueError(f"disparity must be an (H, W) array, got shape {array.shape}")
    return array


def _describe_array(value) -> str:
    if isinstance(value, np.ndarray):
        return f"{value.dtype} of shape {value.shape}"
    return type(value).__name__


def ply_vertices(points: np.ndarray, colours: np.ndarray) -> np.ndarray:
    """The PLY vertex records: float32 x, y, z and uchar red, green, blue."""
    vertex = np.empty(len(points), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                          ("red", "u1"), ("green", "u1"), ("blue", "u1")])
    for k, axis in enumerate("xyz"):
        vertex[axis] = points[:, k]
    for k, channel in enumerate(("red", "green", "blue")):
        vertex[channel] = colours[:, k]
    return vertex
