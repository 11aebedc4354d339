"""Raw stereo rigs: calibration files of unrectified cameras, and their rectification.

A raw rig is two cameras with intrinsics, lens distortion and the pose of the second in
the first's frame (X2 = R X1 + T). Read from, detected by content:

- OpenCV FileStorage YAML or XML as ``cv2.stereoCalibrate`` users save it: ``K1``/``M1``/
  ``cameraMatrix1``, ``D1``/``distCoeffs1``, the same for camera 2, ``R``, ``T``, and the
  image size (``image_width``/``image_height`` or ``imageSize``; else the images' own);
- a ROS ``camera_info`` pair (two files: left, then right), which carries its own
  rectification (``rectification_matrix``) and projection (``projection_matrix``);
- a Kalibr ``camchain.yaml`` (pinhole; ``radtan`` or ``equidistant`` (fisheye) distortion).

:class:`Rectifier` computes the rectification maps once (OpenCV's ``stereoRectify`` and
``initUndistortRectifyMap``, or their ``fisheye`` variants) and applies them to each pair.
The rectified principal points may differ (``doffs``, as in Middlebury's calib.txt): forced
together (``CALIB_ZERO_DISPARITY``), a verged rig's disparities grow by their distance (on
a Middlebury 2014 scene made raw, 0..657 instead of 0..~200, and far fewer points kept);
:meth:`Rectifier.calibration` is the rectified rig as a :class:`vsmatch.geometry.
Calibration`, in the calibration's units. Disparity, depth and points are then in the
*rectified* left camera's frame, as OpenCV's ``reprojectImageTo3D`` and ROS's
``stereo_image_proc`` give them.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import yaml

from . import yamlsafe
from .geometry import FLOAT32_MAX, Calibration, CalibrationError

#: Bytes of a calibration file read at most (real ones are a few kB).
MAX_CALIBRATION_BYTES = 1 << 20


@dataclass(frozen=True)
class RawRig:
    """Two cameras before rectification. ``model`` is ``pinhole`` or ``fisheye``
    (equidistant); ``size`` is (width, height) or None (the images' own). ``rectify`` and
    ``project``, when the file gives them (ROS), are each camera's rectification rotation
    and rectified projection matrix."""

    K1: np.ndarray
    D1: np.ndarray
    K2: np.ndarray
    D2: np.ndarray
    R: np.ndarray
    T: np.ndarray
    size: tuple[int, int] | None = None
    model: str = "pinhole"
    rectify: tuple[np.ndarray, np.ndarray] | None = None
    project: tuple[np.ndarray, np.ndarray] | None = None
    source: str = ""  # the file(s) it was read from, for messages


def is_raw_rig(paths) -> bool:
    """Whether the ``--calib`` file(s) describe a raw rig rather than a rectified pair."""
    paths = [Path(p) for p in paths]
    if len(paths) == 2:
        return True
    text = _read(paths[0])
    return _written_by_opencv(text) or (
        "cam0:" in text and "cam1:" in text) or "camera_matrix" in text or any(
        re.search(rf"^{key}\s*:", text, re.MULTILINE)
        or re.search(rf'"{key}"\s*:', text) for key in STEREO_CALIBRATE_KEYS) or (
        "T_BS" in text and "intrinsics" in text)  # one EuRoC sensor.yaml: said below


def read_rig(paths) -> RawRig:
    """The raw rig of one OpenCV or Kalibr file, or of a left and a right ROS
    ``camera_info`` or EuRoC ``sensor.yaml`` file."""
    paths = [Path(p) for p in paths]
    return dataclasses.replace(_read_rig(paths), source=", ".join(str(p) for p in paths))


def _read_rig(paths: list[Path]) -> RawRig:
    if len(paths) == 2:
        first = _mapping(paths[0])
        if isinstance(first, dict) and "T_BS" in first:
            return _euroc_pair(*paths)
        return _ros_pair(*paths)
    if len(paths) != 1:
        raise CalibrationError("--calib takes one rig file, or a left and a right ROS "
                               "camera_info file")
    path = paths[0]
    text = _read(path)
    data = _opencv_mapping(path) if _written_by_opencv(text) else _yaml(path, text)
    if isinstance(data, dict) and "T_BS" in data:
        raise CalibrationError(f"{path}: a EuRoC sensor.yaml describes one camera; give "
                               "both cameras' (--calib cam0/sensor.yaml --calib "
                               "cam1/sensor.yaml)")
    if isinstance(data, dict) and data.keys() & set(STEREO_CALIBRATE_KEYS):
        return _stereo_calibrate_rig(path, data)
    if isinstance(data, dict) and "cam0" in data and "cam1" in data:
        return _kalibr(path, data)
    if isinstance(data, dict) and "camera_matrix" in data:
        raise CalibrationError(ROS_HINT.format(path=path))
    if _written_by_opencv(text):
        return _stereo_calibrate_rig(path, data)  # names what is missing
    raise CalibrationError(f"{path}: not an OpenCV, ROS or Kalibr stereo calibration")


ROS_HINT = ("{path}: a ROS camera_info file describes one camera; give the left and the "
            "right one (--calib left.yaml --calib right.yaml)")


#: Keys that make a file a cv2.stereoCalibrate rig (OpenCV FileStorage or plain YAML).
STEREO_CALIBRATE_KEYS = ("K1", "M1", "cameraMatrix1", "intrinsic1")


def _written_by_opencv(text: str) -> bool:
    """An OpenCV FileStorage file: its YAML header (``%YAML:1.0``, or ``%YAML 1.2`` from
    OpenCV 5, with ``!!opencv-matrix`` tags PyYAML does not read) or its XML."""
    return text.lstrip().startswith(("%YAML", "<?xml", "<opencv_storage"))


def _opencv_mapping(path: Path) -> dict:
    """An OpenCV FileStorage file's top level as plain Python values; an OpenCV matrix
    as ``{"rows", "cols", "data"}`` (as ROS writes its matrices)."""
    try:
        storage = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        opened = storage.isOpened()
    except (cv2.error, SystemError):
        opened = False
    if not opened:
        raise CalibrationError(f"{path}: not a readable OpenCV FileStorage file (malformed "
                               "or truncated YAML/XML)")
    twice = _repeated_top_keys(path)
    if twice:
        storage.release()
        raise CalibrationError(f"{path}: {twice} is given twice (which one holds?)")
    try:
        root = storage.root()
        return {key: _plain(root.getNode(key)) for key in root.keys()}
    except (cv2.error, SystemError):
        raise CalibrationError(f"{path}: not a readable OpenCV FileStorage file") from None
    finally:
        storage.release()


def _repeated_top_keys(path: Path) -> str | None:
    """The first top-level key an OpenCV YAML file gives twice (OpenCV keeps one of them
    without a word), or None; XML files are not looked at."""
    seen = set()
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError:
        return None
    for line in lines:
        match = re.match(r"([A-Za-z_][\w]*)\s*:", line)  # a key at the start of a line
        if match:
            if match.group(1) in seen:
                return match.group(1)
            seen.add(match.group(1))
    return None


def _plain(node, depth: int = 0):
    """A FileStorage node as plain Python values (nested at most a few levels)."""
    if depth > 8:
        raise CalibrationError("a calibration nested deeper than any real one")
    if node.isInt():
        return int(node.real())
    if node.isReal():
        return node.real()
    if node.isString():
        return node.string()
    if node.isSeq():
        return [_plain(node.at(i), depth + 1) for i in range(node.size())]
    if node.isMap():
        if "dt" in node.keys():  # an !!opencv-matrix
            matrix = np.asarray(node.mat(), dtype=np.float64)
            return {"rows": matrix.shape[0], "cols": matrix.shape[1] if matrix.ndim > 1 else 1,
                    "data": matrix.ravel().tolist()}
        return {key: _plain(node.getNode(key), depth + 1) for key in node.keys()}
    return None


def _mapping(path: Path):
    """A calibration file's content: an OpenCV FileStorage file's top level, or YAML."""
    text = _read(path)
    return _opencv_mapping(path) if _written_by_opencv(text) else _yaml(path, text)


def _euroc_pair(left: Path, right: Path) -> RawRig:
    """The EuRoC / ASL format: each camera's ``sensor.yaml`` (intrinsics, distortion,
    resolution) with its pose in the body frame, ``T_BS`` (a body point X_B = T_BS X_S);
    the right camera's pose in the left's follows: X_1 = T_BS1^-1 T_BS0 X_0."""
    cams, poses = [], []
    for path in (left, right):
        data = _mapping(path)
        if not isinstance(data, dict) or "T_BS" not in data:
            raise CalibrationError(f"{path}: not a EuRoC sensor.yaml (T_BS, intrinsics, ...)"
                                   f"; {left} is one")
        cams.append(_pinhole_camera(path, path.name, data, "distortion_coefficients"))
        pose = _matrix(path, "T_BS", _numbers_of(path, "T_BS", data["T_BS"]), (4, 4))
        if not np.allclose(pose[3], (0, 0, 0, 1)):
            raise CalibrationError(f"{path}: T_BS's last row must be 0 0 0 1")
        check_rotation(path, "T_BS (rotation)", pose[:3, :3])
        poses.append(pose)
    relative = np.linalg.inv(poses[1]) @ poses[0]
    rig = _two_cameras(right, (str(left), str(right)), cams, relative[:3, :3].copy(),
                       relative[:3, 3].copy())
    return check_rig(right, rig, {"K1": f"{left}'s intrinsics", "K2": "intrinsics",
                                  "D1": f"{left}'s distortion_coefficients",
                                  "D2": "distortion_coefficients",
                                  "R": "T_BS (the cameras' relative rotation)",
                                  "T": "T_BS (the cameras' relative translation)"})


def _read(path: Path) -> str:
    try:
        if path.stat().st_size > MAX_CALIBRATION_BYTES:
            raise CalibrationError(f"{path}: larger than any calibration file")
        return path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise CalibrationError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CalibrationError(f"{path}: cannot read the calibration ({exc})") from None


#: YAML nodes a calibration file may hold, its aliases expanded: a camchain of two
#: cameras has about a hundred.
MAX_CALIBRATION_NODES = 20_000


def _yaml(path: Path, text: str):
    """The YAML document. Its size with every alias expanded is counted on the parsed
    node graph first (aliases point to one node there): a few hundred bytes of nested
    aliases expand to gigabytes, and such a file is refused before anything is built."""
    loader = yamlsafe.UniqueKeyLoader(text)
    try:
        root = loader.get_single_node()
        if root is None:
            return None
        if _expanded_size(root, {}) > MAX_CALIBRATION_NODES:
            raise CalibrationError(f"{path}: more YAML nodes than a calibration holds "
                                   f"(over {MAX_CALIBRATION_NODES} with its aliases "
                                   "expanded)")
        return loader.construct_document(root)  # from the nodes parsed once
    except yamlsafe.DuplicateKeyError as exc:
        raise CalibrationError(f"{path}: {exc.problem}") from None
    except (yaml.YAMLError, RecursionError):
        raise CalibrationError(f"{path}: not valid YAML") from None
    finally:
        loader.dispose()


def _expanded_size(node, sizes: dict) -> int:
    """Nodes under ``node`` with its aliases expanded, each shared node counted once
    per use but walked once."""
    if id(node) in sizes:
        return sizes[id(node)]
    if isinstance(node, yaml.SequenceNode):
        size = 1 + sum(_expanded_size(child, sizes) for child in node.value)
    elif isinstance(node, yaml.MappingNode):
        size = 1 + sum(_expanded_size(k, sizes) + _expanded_size(v, sizes)
                       for k, v in node.value)
    else:
        size = 1
    sizes[id(node)] = size
    return size


def _matrix(path: Path, key: str, value, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as a finite float64 array of ``shape`` (sizes may match in total)."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise CalibrationError(f"{path}: {key} is not a matrix of numbers") from None
    if array.size != math.prod(shape):
        raise CalibrationError(f"{path}: {key} must have {math.prod(shape)} numbers, "
                               f"has {array.size}")
    if not np.all(np.isfinite(array)):
        raise CalibrationError(f"{path}: {key} holds a number that is not finite")
    return np.ascontiguousarray(array.reshape(shape))


def _first_key(path: Path, data: dict, names: tuple[str, ...], required: bool = True
               ) -> str | None:
    for name in names:
        if name in data:
            return name
    if required:
        raise CalibrationError(f"{path}: missing {' / '.join(names)}")
    return None


def _numbers_of(path: Path, name: str, value) -> np.ndarray:
    """The numbers of a matrix as a file gives it: an OpenCV or ROS matrix
    (``{rows, cols, data}``), a list (of lists) or one number."""
    if isinstance(value, dict):
        value = value.get("data")
    if value is None or isinstance(value, (str, bool)):
        raise CalibrationError(f"{path}: {name} is not a matrix of numbers")
    try:
        return np.asarray(value, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise CalibrationError(f"{path}: {name} is not a matrix of numbers") from None


def _opencv(path: Path) -> RawRig:
    """An OpenCV FileStorage file (YAML or XML), as cv2.stereoCalibrate users save it."""
    return _stereo_calibrate_rig(path, _opencv_mapping(path))


def _stereo_calibrate_rig(path: Path, data: dict) -> RawRig:
    """The rig of a mapping with cv2.stereoCalibrate's names (``K1``/``M1``/
    ``cameraMatrix1``/``intrinsic1``, ``D1``/``distCoeffs1``, the same for camera 2, ``R``,
    ``T``, and ``image_width``/``image_height``, ``imageSize`` or ``res1``), from an OpenCV
    FileStorage file, a plain YAML file or JSON (as the published ``rig.json`` files)."""
    values, found = {}, {}
    for key, names, shape in (("K1", ("K1", "M1", "cameraMatrix1", "intrinsic1"), (3, 3)),
                              ("K2", ("K2", "M2", "cameraMatrix2", "intrinsic2"), (3, 3)),
                              ("R", ("R",), (3, 3)), ("T", ("T",), (3,))):
        name = _first_key(path, data, names)
        values[key] = _matrix(path, name, _numbers_of(path, name, data[name]), shape)
        found[key] = name
    for key, names in (("D1", ("D1", "distCoeffs1")), ("D2", ("D2", "distCoeffs2"))):
        name = _first_key(path, data, names, required=False)
        found[key] = name or key
        if name is None:
            values[key] = np.zeros(5)
        else:
            numbers = _numbers_of(path, name, data[name])
            values[key] = _matrix(path, name, numbers, (numbers.size,))
    size = None
    if "image_width" in data and "image_height" in data:
        size = (_whole_number(path, "image_width", data["image_width"]),
                _whole_number(path, "image_height", data["image_height"]))
    else:
        name = _first_key(path, data, ("imageSize", "res1"), required=False)
        if name is not None:
            numbers = _numbers_of(path, name, data[name])
            if numbers.size != 2:
                raise CalibrationError(f"{path}: {name} must be two numbers (width, "
                                       f"height), has {numbers.size}")
            size = tuple(_whole_number(path, name, [v]) for v in numbers)
    return check_rig(path, RawRig(size=size, **values), found)


#: Largest image side a calibration may name.
MAX_IMAGE_SIDE = 100_000


def _whole_number(path: Path, key: str, value) -> int:
    """One whole number in 1 .. MAX_IMAGE_SIDE (an image size), or a one-line error."""
    values = np.ravel(np.asarray(value, dtype=object))
    try:
        number = float(values[0]) if values.size == 1 else None
    except (TypeError, ValueError):
        number = None
    if number is None or not math.isfinite(number) or number != int(number) or not (
            1 <= number <= MAX_IMAGE_SIDE):
        shown = values[0] if values.size == 1 else list(values)
        raise CalibrationError(f"{path}: {key} must be a whole number of pixels from 1 to "
                               f"{MAX_IMAGE_SIDE}, got {shown}")
    return int(number)


#: Distortion coefficient counts OpenCV's pinhole model takes (k1 k2 p1 p2 [k3 [k4 k5 k6
#: [s1 s2 s3 s4 [tx ty]]]]); its fisheye model takes exactly four.
PINHOLE_COEFFICIENTS = (4, 5, 8, 12, 14)
#: How far R R^T may be from the identity, and det R from +1.
ROTATION_TOLERANCE = 1e-3


def check_rig(path: Path, rig: RawRig, names: dict[str, str]) -> RawRig:
    """Refuse a rig no camera can have, naming the key: K with a focal length that is
    not positive, a distortion of a length the model does not take, R that is not a
    rotation, T zero, not finite, not mostly along x, or so long that depths overflow
    float32. ``names`` gives each matrix's key in the file."""
    for K, D, k, d in ((rig.K1, rig.D1, "K1", "D1"), (rig.K2, rig.D2, "K2", "D2")):
        check_camera_matrix(path, names[k], K, rig.size)
        allowed = (4,) if rig.model == "fisheye" else PINHOLE_COEFFICIENTS
        if D.size not in allowed:
            raise CalibrationError(
                f"{path}: {names[d]} has {D.size} distortion coefficients; the "
                f"{rig.model} model takes {' or '.join(str(n) for n in allowed)}")
    check_rotation(path, names["R"], rig.R)
    longest = float(np.abs(rig.T).max())
    if not longest > 0:
        raise CalibrationError(f"{path}: {names['T']} is zero: the cameras are at one place")
    if abs(rig.T[0]) <= math.hypot(rig.T[1], rig.T[2]):
        raise CalibrationError(f"{path}: {names['T']} = {np.round(rig.T, 6).tolist()} is not "
                               "mostly along x: a side-by-side rig is expected")
    if rig.K1[0, 0] * longest * 256 > FLOAT32_MAX:
        raise CalibrationError(f"{path}: {names['T']} = {np.round(rig.T, 6).tolist()} is so "
                               "long that depths overflow float32")
    return rig


def check_camera_matrix(path: Path, key: str, K: np.ndarray, size) -> None:
    """Positive focal lengths, the last row (0, 0, 1), and the principal point inside the
    image (when its size is known)."""
    if not (K[0, 0] > 0 and K[1, 1] > 0):
        raise CalibrationError(f"{path}: {key} has focal lengths {K[0, 0]:g}, {K[1, 1]:g}; "
                               "both must be positive")
    if not np.allclose(K[2], (0, 0, 1)) or K[1, 0] != 0:
        raise CalibrationError(f"{path}: {key} is not a camera matrix [fx s cx; 0 fy cy; "
                               "0 0 1]")
    if size is not None and not (0 <= K[0, 2] < size[0] and 0 <= K[1, 2] < size[1]):
        raise CalibrationError(f"{path}: {key}'s principal point ({K[0, 2]:g}, {K[1, 2]:g}) "
                               f"is outside the {size[0]}x{size[1]} image")


def check_rotation(path: Path, key: str, R: np.ndarray) -> None:
    if (np.abs(R @ R.T - np.eye(3)).max() > ROTATION_TOLERANCE
            or abs(np.linalg.det(R) - 1) > ROTATION_TOLERANCE):
        raise CalibrationError(f"{path}: {key} is not a rotation (orthonormal with "
                               "determinant +1)")


def _ros_pair(left: Path, right: Path) -> RawRig:
    cams = []
    for path in (left, right):
        data = _mapping(path)
        if not isinstance(data, dict) or "camera_matrix" not in data:
            raise CalibrationError(f"{path}: not a ROS camera_info file (camera_matrix ...)")
        try:
            size = (_whole_number(path, "image_width", data["image_width"]),
                    _whole_number(path, "image_height", data["image_height"]))
            matrices = {key: _matrix(path, key, _ros_data(path, key, data[key]), shape)
                        for key, shape in (("camera_matrix", (3, 3)),
                                           ("rectification_matrix", (3, 3)),
                                           ("projection_matrix", (3, 4)))}
            coeffs = (_ros_data(path, "distortion_coefficients",
                                data["distortion_coefficients"])
                      if "distortion_coefficients" in data else [0, 0, 0, 0, 0])
            matrices["distortion"] = _matrix(path, "distortion_coefficients", coeffs,
                                             (len(coeffs),))
        except KeyError as exc:
            raise CalibrationError(f"{path}: missing {exc}") from None
        model = "fisheye" if data.get("distortion_model") == "equidistant" else "pinhole"
        check_camera_matrix(path, "camera_matrix", matrices["camera_matrix"], size)
        check_rotation(path, "rectification_matrix", matrices["rectification_matrix"])
        projection = matrices["projection_matrix"]
        check_camera_matrix(path, "projection_matrix", projection[:, :3], None)
        cams.append((matrices, size, model))
    (left_cam, size, model), (right_cam, right_size, right_model) = cams
    if right_size != size:
        raise CalibrationError(f"{right}: image size {right_size[0]}x{right_size[1]} differs "
                               f"from {left}'s {size[0]}x{size[1]}")
    if right_model != model:
        raise CalibrationError(f"{right}: distortion_model differs from {left}'s")
    # Rectified views share one focal length and one row of the principal point.
    left_p, right_p = left_cam["projection_matrix"], right_cam["projection_matrix"]
    for (i, j), what in (((0, 0), "fx"), ((1, 1), "fy"), ((1, 2), "cy")):
        if not math.isclose(left_p[i, j], right_p[i, j], rel_tol=1e-4, abs_tol=1e-3):
            raise CalibrationError(
                f"{right}: projection_matrix has {what} {right_p[i, j]:g}, {left}'s "
                f"{left_p[i, j]:g}: rectified views share them (are the files of one rig?)")
    # The pose of the right camera from the rectifications: X2 = R2^T R1 X1 + T with the
    # baseline along the rectified x axis, Tx = -fx' B in P2.
    rotation = right_cam["rectification_matrix"].T @ left_cam["rectification_matrix"]
    baseline = -right_cam["projection_matrix"][0, 3] / right_cam["projection_matrix"][0, 0]
    if not baseline > 0:
        raise CalibrationError(f"{right}: projection_matrix gives the baseline {baseline:g} "
                               "(Tx = -fx B must be negative for the right camera); are the "
                               "files swapped?")
    translation = right_cam["rectification_matrix"].T @ np.array([-baseline, 0.0, 0.0])
    rig = RawRig(K1=left_cam["camera_matrix"], D1=left_cam["distortion"],
                 K2=right_cam["camera_matrix"], D2=right_cam["distortion"], R=rotation,
                 T=translation, size=size, model=model,
                 rectify=(left_cam["rectification_matrix"], right_cam["rectification_matrix"]),
                 project=(left_cam["projection_matrix"], right_cam["projection_matrix"]))
    return check_rig(right, rig, {"K1": f"{left}'s camera_matrix",
                                  "K2": "camera_matrix",
                                  "D1": f"{left}'s distortion_coefficients",
                                  "D2": "distortion_coefficients",
                                  "R": "rectification_matrix",
                                  "T": "projection_matrix"})


def _ros_data(path: Path, key: str, field):
    if not isinstance(field, dict) or "data" not in field:
        raise CalibrationError(f"{path}: {key} has no data: list")
    return field["data"]


#: Radial-tangential distortion by the names Kalibr and EuRoC give it (k1 k2 p1 p2, as
#: OpenCV's first four), and the equidistant (fisheye) model.
RADTAN = ("radtan", "radial-tangential")
EQUIDISTANT = "equidistant"


def _pinhole_camera(path: Path, name: str, cam, coeffs_key: str):
    """One camera of a Kalibr camchain or a EuRoC ``sensor.yaml``: ``intrinsics`` [fu,
    fv, pu, pv], distortion coefficients under ``coeffs_key``, ``distortion_model`` and
    ``resolution``. Returns K, D (radial-tangential padded to OpenCV's five), the model
    (``pinhole`` or ``fisheye``) and the size."""
    if not isinstance(cam, dict):
        raise CalibrationError(f"{path}: {name} must be a mapping (camera_model, "
                               f"intrinsics, {coeffs_key}, resolution, ...)")
    for key in ("intrinsics", coeffs_key, "resolution"):
        if key not in cam:
            raise CalibrationError(f"{path}: {name} lacks {key}")
    intrinsics = _numbers_of(path, f"{name}.intrinsics", cam["intrinsics"])
    if intrinsics.size != 4:
        raise CalibrationError(f"{path}: {name}.intrinsics must be four numbers [fu, fv, "
                               f"pu, pv], has {intrinsics.size}")
    fu, fv, pu, pv = (float(v) for v in intrinsics)
    coeffs = list(_numbers_of(path, f"{name}.{coeffs_key}", cam[coeffs_key]))
    model = cam.get("distortion_model", RADTAN[0])
    resolution = cam["resolution"]
    if not isinstance(resolution, list) or len(resolution) != 2:
        raise CalibrationError(f"{path}: {name}.resolution must be [width, height], "
                               f"got {resolution}")
    size = tuple(_whole_number(path, f"{name}.resolution", [v]) for v in resolution)
    if cam.get("camera_model", "pinhole") != "pinhole":
        raise CalibrationError(f"{path}: {name}: camera_model "
                               f"{cam.get('camera_model')} is not supported (pinhole)")
    if model not in (*RADTAN, EQUIDISTANT):
        raise CalibrationError(f"{path}: {name}: distortion_model {model} is not "
                               f"supported ({', '.join((*RADTAN, EQUIDISTANT))})")
    K = _matrix(path, f"{name}.intrinsics", [[fu, 0, pu], [0, fv, pv], [0, 0, 1]], (3, 3))
    D = _matrix(path, f"{name}.{coeffs_key}", coeffs, (len(coeffs),))
    if model in RADTAN:
        if D.size not in (4, 5):  # three would be padded into a different lens
            raise CalibrationError(f"{path}: {name}.{coeffs_key} must be 4 numbers (k1, k2, "
                                   f"p1, p2) or 5 (and k3) for {model}, has {D.size}")
        D = np.concatenate([D, np.zeros(max(0, 5 - D.size))])
    return K, D, "fisheye" if model == EQUIDISTANT else "pinhole", size


def _two_cameras(path: Path, names: tuple[str, str], cams, R: np.ndarray, T: np.ndarray
                 ) -> RawRig:
    """The rig of two cameras (:func:`_pinhole_camera`) of one model and size."""
    (K1, D1, model, size), (K2, D2, model2, size2) = cams
    if model2 != model:
        raise CalibrationError(f"{path}: {names[1]}'s distortion_model differs from "
                               f"{names[0]}'s")
    if size2 != size:
        raise CalibrationError(f"{path}: {names[1]}'s resolution {list(size2)} differs from "
                               f"{names[0]}'s {list(size)}")
    return RawRig(K1=K1, D1=D1, K2=K2, D2=D2, R=R, T=T, size=size, model=model)


def _kalibr(path: Path, data: dict) -> RawRig:
    cams = [_pinhole_camera(path, name, data[name], "distortion_coeffs")
            for name in ("cam0", "cam1")]
    if "T_cn_cnm1" not in data["cam1"]:
        raise CalibrationError(f"{path}: cam1 lacks T_cn_cnm1")
    pose = _matrix(path, "cam1.T_cn_cnm1",
                   _numbers_of(path, "cam1.T_cn_cnm1", data["cam1"]["T_cn_cnm1"]), (4, 4))
    rig = _two_cameras(path, ("cam0", "cam1"), cams, pose[:3, :3].copy(), pose[:3, 3].copy())
    return check_rig(path, rig, {"K1": "cam0.intrinsics", "K2": "cam1.intrinsics",
                                 "D1": "cam0.distortion_coeffs",
                                 "D2": "cam1.distortion_coeffs",
                                 "R": "cam1.T_cn_cnm1 (rotation)",
                                 "T": "cam1.T_cn_cnm1 (translation)"})


def _opencv_reason(exc: Exception) -> str:
    """The reason OpenCV gives, without its source file and line."""
    text = " ".join(str(exc).split())
    return text.split(") ", 1)[-1].split(" in function")[0][:200]


#: A rectification that scales the views by more than this (or less than its inverse), or
#: leaves less than MIN_SHOWN of a view showing the camera's image, comes from a lens no
#: camera has (distortion k1 = 1e4 gave a focal length of 2.9e5 px from 300, the view a
#: uniform grey; k1 = -1e3 showed 8 % of the image). Real lenses: a scale of 0.97-1.04
#: and 96-100 % shown (k1 from -0.3 to 0.5, alpha 0 and 1).
MAX_RECTIFIED_SCALE, MIN_SHOWN = 10.0, 0.2


def _listed(values) -> str:
    """Coefficients as a short list (``[0.1, -0.02, 0, 0, 0]``)."""
    return "[" + ", ".join(f"{float(v):.3g}" for v in np.ravel(values)) + "]"


class Rectifier:
    """The rectification of a raw rig, computed once for an image size and reused.

    ``alpha`` as OpenCV's: 0 keeps only valid pixels (default), 1 keeps every source pixel.
    """

    def __init__(self, rig: RawRig, size: tuple[int, int], alpha: float = 0.0):
        if rig.size is not None and tuple(rig.size) != tuple(size):
            raise CalibrationError(f"the calibration is for {rig.size[0]}x{rig.size[1]} "
                                   f"images, these are {size[0]}x{size[1]}")
        self.size = size
        for key, K in (("the left camera matrix", rig.K1), ("the right camera matrix", rig.K2)):
            if not (0 <= K[0, 2] < size[0] and 0 <= K[1, 2] < size[1]):
                raise CalibrationError(f"{key}'s principal point ({K[0, 2]:g}, {K[1, 2]:g}) "
                                       f"is outside the {size[0]}x{size[1]} images")
        try:
            self._make_maps(rig, size, alpha)
        except cv2.error as exc:
            raise CalibrationError("OpenCV cannot rectify with this calibration "
                                   f"({_opencv_reason(exc)})") from None
        problem = self._lens_problem(rig)
        if problem is not None:
            named = f"{rig.source}: " if rig.source else ""
            raise CalibrationError(f"{named}{problem}: no camera's lens does that; check the "
                                   f"distortion coefficients (left {_listed(rig.D1)}, "
                                   f"right {_listed(rig.D2)})")

    def _lens_problem(self, rig: RawRig) -> str | None:
        """What is absurd about this rectification, or None: views scaled by more than
        :data:`MAX_RECTIFIED_SCALE` (either way), or less than :data:`MIN_SHOWN` of a
        rectified view showing the camera's image."""
        scale = float(self.projections[0][0, 0]) / float(rig.K1[0, 0])
        if not 1 / MAX_RECTIFIED_SCALE <= scale <= MAX_RECTIFIED_SCALE:
            return (f"the rectification scales the views by {scale:.3g} (a focal length of "
                    f"{float(self.projections[0][0, 0]):.0f} px from {float(rig.K1[0, 0]):.0f})")
        width, height = self.size
        for side, (mx, my) in zip(("left", "right"), self.maps):
            shown = float(((mx >= 0) & (mx <= width - 1) & (my >= 0)
                           & (my <= height - 1)).mean())
            if shown < MIN_SHOWN:
                return f"only {100 * shown:.0f} % of the rectified {side} view shows its image"
        return None

    def _make_maps(self, rig: RawRig, size: tuple[int, int], alpha: float) -> None:
        if rig.rectify is not None and rig.project is not None:
            r1, r2 = rig.rectify
            p1, p2 = rig.project
        elif rig.model == "fisheye":
            r1, r2, p1, p2, _ = cv2.fisheye.stereoRectify(
                rig.K1, rig.D1[:4], rig.K2, rig.D2[:4], size, rig.R, rig.T.reshape(3, 1),
                flags=0, newImageSize=size, balance=alpha)
        else:
            r1, r2, p1, p2, *_ = cv2.stereoRectify(
                rig.K1, rig.D1, rig.K2, rig.D2, size, rig.R, rig.T.reshape(3, 1),
                flags=0, alpha=alpha)
        self.rotations, self.projections = (r1, r2), (p1, p2)
        make = (cv2.fisheye.initUndistortRectifyMap if rig.model == "fisheye"
                else cv2.initUndistortRectifyMap)
        self.maps = [make(K, D[:4] if rig.model == "fisheye" else D, Rr, P, size,
                          cv2.CV_32FC1)
                     for K, D, Rr, P in ((rig.K1, rig.D1, r1, p1), (rig.K2, rig.D2, r2, p2))]

    def rectify(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Both views rectified (same size and type as given)."""
        if left.shape[1::-1] != tuple(self.size):
            raise CalibrationError(f"images of {left.shape[1]}x{left.shape[0]} do not match "
                                   f"the rig's {self.size[0]}x{self.size[1]}")
        return tuple(cv2.remap(view, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
                     for view, (mx, my) in zip((left, right), self.maps))

    def calibration(self) -> Calibration:
        """The rectified rig: f, principal points and the baseline, in the calibration's
        units (the translation's)."""
        p1, p2 = self.projections
        focal = float(p1[0, 0])
        baseline = -float(p2[0, 3]) / float(p2[0, 0])
        if not baseline > 0:
            raise CalibrationError("the right camera is not to the right of the left one "
                                   f"after rectification (baseline {baseline:g}); are the "
                                   "cameras swapped?")
        return Calibration(focal=focal, baseline=baseline, cx=float(p1[0, 2]),
                           cy=float(p1[1, 2]), doffs=float(p2[0, 2] - p1[0, 2]),
                           focal_y=float(p1[1, 1]))


def middlebury_calib_text(calib: Calibration, size: tuple[int, int],
                          search: tuple[int, int] | None) -> str:
    """A Middlebury-style ``calib.txt`` that ``vsmatch run --calib`` reads; with the
    range ``search`` = (min, max) searched: ``ndisp`` and, for a range that does not
    start at 0 (a verged rig's), vsmatch's own ``dmin``."""
    cx, cy = calib.principal_point((size[1], size[0]))
    fy = calib.focal_y or calib.focal
    lines = [f"cam0=[{calib.focal:.6f} 0 {cx:.6f}; 0 {fy:.6f} {cy:.6f}; 0 0 1]",
             f"cam1=[{calib.focal:.6f} 0 {cx + calib.doffs:.6f}; 0 {fy:.6f} {cy:.6f}; 0 0 1]",
             f"doffs={calib.doffs:.6f}", f"baseline={calib.baseline:.6f}",
             f"width={size[0]}", f"height={size[1]}"]
    if search is not None:
        lines.append(f"ndisp={search[1] - search[0] + 1}")
        if search[0] != 0:
            lines.append(f"dmin={search[0]}")
    return "\n".join(lines) + "\n"
