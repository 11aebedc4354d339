"""Reading stereo images and writing disparity maps, atomically.

Every file is written under a temporary name in its destination folder and renamed into
place, so an interrupted run never leaves a partial file behind.
"""

from __future__ import annotations

import contextlib
import contextvars
import glob
import os
import re
import shutil
import signal
import sys
import tempfile
import threading
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np

from .disparity import INVALID_DISPARITY
from .image_header import header_size

#: Output formats of a disparity map, by file extension.
DISPARITY_FORMATS = (".pfm", ".png")
#: The image files read as views (a batch's folders, a video's folders of frames).
IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".ppm", ".pgm")


class ImageError(ValueError):
    """An input image that cannot be used; the message is one line and names the file."""


#: Largest view read, in megapixels, whatever the memory budget (config
#: ``memory.max_megapixels``): a full-size Middlebury 2014 view has 6, a 50-megapixel
#: camera's 50.
MAX_MEGAPIXELS = 200.0
#: Memory the whole-image arrays of a run take per pixel of one view, outside the cost
#: volumes that the stripes bound: both views (6 bytes), their grey levels, gradients
#: and census codes (36), the disparities, labels and refinement copies (~20). Measured:
#: Adirondack upscaled 4x and 6x (5.7 and 12.8 Mpx) searching 17 disparities peaks 101
#: and 76 bytes per pixel above the warm start, its small cost volume included; so an
#: image refused at 64 bytes per pixel certainly cannot fit the budget.
IMAGE_BYTES_PER_PIXEL = 64


def check_image_size(path: str | Path, width: int, height: int, *,
                     max_mb: float | None = None,
                     max_megapixels: float = MAX_MEGAPIXELS) -> None:
    """Refuse a view too large to read: over ``max_megapixels``, or whose whole-image
    arrays alone would not fit ``max_mb`` megabytes."""
    megapixels = width * height / 1e6
    if megapixels > max_megapixels:
        shown = f"{megapixels:.0f}" if megapixels >= 100 else f"{megapixels:.2f}"
        raise ImageError(f"{path}: {width}x{height} is {shown} megapixels, over the limit of "
                         f"{max_megapixels:g} (config memory.max_megapixels)")
    needed = width * height * IMAGE_BYTES_PER_PIXEL / 2**20
    if max_mb is not None and needed > max_mb:
        raise ImageError(f"{path}: {width}x{height} needs about {needed:.0f} MB for its "
                         f"whole-image arrays, more than the budget of {max_mb:g} MB "
                         "(--max-memory)")


def read_image(path: str | Path, *, max_mb: float | None = None,
               max_megapixels: float = MAX_MEGAPIXELS) -> np.ndarray:
    """Read a stereo view as (H, W, 3) uint8 BGR.

    Grey images are repeated over three channels and an alpha channel is dropped.
    16-bit images keep their 8 most significant bits *in use*: a 12-bit camera's values
    (0..4095 in a 16-bit PNG) are scaled by 1/16, not cut to their top byte (0..15).
    The size is checked from the header before decoding (:func:`check_image_size`).
    """
    raw = _decode(path, max_mb, max_megapixels)
    return _to_bgr8(path, raw, _significant_shift(raw))


def _decode(path: str | Path, max_mb: float | None, max_megapixels: float) -> np.ndarray:
    """The image as stored (uint8 or uint16, any channels), its size checked first."""
    path = Path(path)
    if not path.exists():
        raise ImageError(f"{path}: file not found")
    if not path.is_file():
        raise ImageError(f"{path}: not a file")
    size = header_size(path)
    if size is not None:
        check_image_size(path, *size, max_mb=max_mb, max_megapixels=max_megapixels)
    data = np.fromfile(str(path), dtype=np.uint8)
    try:
        with native_stderr_silenced():
            image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
    except cv2.error:  # OpenCV's own limits (CV_IO_MAX_IMAGE_PIXELS), a broken header
        image = None
    if image is not None:
        check_image_size(path, image.shape[1], image.shape[0], max_mb=max_mb,
                         max_megapixels=max_megapixels)
    if image is None or image.size == 0:
        raise ImageError(f"{path}: not a readable image (unknown format, or truncated)")
    if image.dtype not in (np.uint8, np.uint16):
        raise ImageError(f"{path}: unsupported pixel type {image.dtype} (8- or 16-bit expected)")
    return image


def _significant_shift(*images: np.ndarray) -> int:
    """The right shift that keeps the 8 most significant bits in use of 16-bit images
    (all of them together, so that two views keep one scale); 0 for 8-bit ones."""
    if images[0].dtype != np.uint16:
        return 0
    top = max(int(image.max()) for image in images)
    return max(0, top.bit_length() - 8)


def _to_bgr8(path: str | Path, image: np.ndarray, shift: int) -> np.ndarray:
    """A decoded image as (H, W, 3) uint8 BGR, 16-bit values shifted right by ``shift``."""
    if image.dtype == np.uint16:
        image = (image >> shift).astype(np.uint8)
    if image.ndim == 2:
        image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    elif image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    elif image.shape[2] == 1:
        image = cv2.cvtColor(image[:, :, 0], cv2.COLOR_GRAY2BGR)
    elif image.shape[2] != 3:
        raise ImageError(f"{path}: unsupported number of channels {image.shape[2]}")
    return np.ascontiguousarray(image)


@contextlib.contextmanager
def native_stderr_silenced():
    """Keep the C libraries' own complaints (OpenCV 4's libpng: "libpng error: ...") off
    stderr while decoding: our one-line error says what went wrong. OpenCV 5 routes them
    through its logging, which the CLI silences."""
    try:
        fd = sys.stderr.fileno()
    except (AttributeError, OSError, ValueError):  # no real stderr (captured, embedded)
        yield
        return
    sys.stderr.flush()
    saved, devnull = os.dup(fd), os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    try:
        yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)
        os.close(devnull)


def read_pair(left_path: str | Path, right_path: str | Path, *, max_mb: float | None = None,
              max_megapixels: float = MAX_MEGAPIXELS) -> tuple[np.ndarray, np.ndarray]:
    """Both views of a stereo pair (see :func:`read_image`; 16-bit views keep one scale),
    which must be two files of one size and bit depth."""
    if same_file(Path(left_path), Path(right_path)):
        raise ImageError(f"{left_path} and {right_path} are the same file: give the left "
                         "and the right view")
    raw = [_decode(path, max_mb, max_megapixels) for path in (left_path, right_path)]
    if raw[0].dtype != raw[1].dtype:
        raise ImageError(f"{left_path} is {raw[0].dtype.itemsize * 8}-bit and {right_path} "
                         f"{raw[1].dtype.itemsize * 8}-bit: give both views of one camera")
    shift = _significant_shift(*raw)  # one scale for both views
    left, right = (_to_bgr8(path, image, shift)
                   for path, image in zip((left_path, right_path), raw))
    if left.shape != right.shape:
        raise ImageError(f"{left_path} ({left.shape[1]}x{left.shape[0]}) and {right_path} "
                         f"({right.shape[1]}x{right.shape[0]}) differ in size")
    return left, right


#: The outputs of the innermost :func:`all_or_none` block: (temporary, final path) pairs.
_STAGED: contextvars.ContextVar[list | None] = contextvars.ContextVar("staged", default=None)


def write_atomic(path: str | Path, encode, *, silenced: bool = True) -> None:
    """Write bytes made by ``encode(tmp_path)`` to ``path`` through a temporary file.

    ``encode`` receives a temporary path with the same extension (OpenCV picks the format
    from it) and must create that file; the result is renamed onto ``path`` (inside an
    :func:`all_or_none` block, when the block ends). A failure names ``path``, never the
    temporary. ``silenced`` False: ``encode`` keeps the C libraries off stderr itself (a
    video's writer, whose frame loop shows a progress bar there).
    """
    path = Path(path)
    folder = check_output_file(path)
    shown = final_path(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=_temporary_prefix(path),
                                   suffix=_temporary_suffix(path), dir=folder)
    except OSError as exc:
        raise OSError(f"{shown}: could not be written ({exc.strerror or exc})") from None
    os.close(fd)
    try:
        try:
            with native_stderr_silenced() if silenced else contextlib.nullcontext():
                encode(tmp)  # libpng's own "Write Error" line kept off stderr
        except OSError as exc:
            if str(shown) in str(exc):
                raise
            reason = exc.strerror or str(exc) or type(exc).__name__
            if str(path) in reason or tmp in reason:
                reason = exc.strerror or "write error"
            raise OSError(f"{shown}: could not be written ({reason})") from None
        # mkstemp makes the file private (0600); give it the mode any new file gets.
        os.chmod(tmp, 0o666 & ~current_umask())
        _land(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


#: Staged folders being written: their temporary path -> the path they will land at.
_STAGED_FOLDERS: dict[Path, Path] = {}


def final_path(path: str | Path) -> Path:
    """``path`` as the user will see it: inside a staged folder, under the folder's final
    name rather than its temporary one (for messages)."""
    path = Path(path)
    for tmp, final in _STAGED_FOLDERS.items():
        if path.is_relative_to(tmp):
            return final / path.relative_to(tmp)
    return path


def check_output_file(path: str | Path) -> Path:
    """The existing folder that ``path`` goes in; an output that names a folder, or goes
    in a missing one, is refused (OSError naming ``path``)."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise OSError(f"{path}: output folder '{folder}' does not exist")
    if path.is_dir():
        raise OSError(f"{path}: is a folder, not a file name")
    return folder


def _land(tmp: str | Path, path: Path) -> None:
    """Rename a finished temporary onto ``path`` now, or when the enclosing
    :func:`all_or_none` block ends."""
    staged = _STAGED.get()
    if staged is None:
        _replace(tmp, path)
    else:
        staged.append((str(tmp), path))


def followed_folder(path: str | Path) -> Path:
    """An output folder's path, a symbolic link to a folder followed (what it holds is
    replaced, the link kept); a link to nothing is an OSError naming both."""
    path = Path(path)
    if not path.is_symlink():
        return path
    target = resolved(path)
    if not target.exists():
        raise OSError(f"{path}: a link to {target}, which does not exist (make that folder, "
                      "or name another)")
    return target


def check_replaceable_folder(path: str | Path, *, overwrite: bool,
                             ours: Callable[[Path], bool]) -> None:
    """Refuse to replace the folder ``path`` as a whole when it is a file, the current
    folder or one above it, or holds anything: with ``overwrite``, anything that
    ``ours`` does not recognise as an earlier run's output (a user's own file or
    sub-folder is never deleted). A link is followed (:func:`followed_folder`)."""
    path = followed_folder(path)
    if path.exists() and not path.is_dir():
        raise OSError(f"{path}: is a file, not a folder")
    if not path.is_dir():
        return
    if Path.cwd().resolve().is_relative_to(resolved(path)):
        raise OSError(f"{path}: is the current folder or holds it; name a folder of "
                      "its own")
    entries = sorted(path.iterdir())
    if entries and not overwrite:
        raise OSError(f"{path}: the folder is not empty (--overwrite replaces an earlier "
                      "run's folder as a whole)")
    foreign = [entry for entry in entries if not ours(entry)]
    if foreign:
        raise OSError(f"{path}: holds {foreign[0].name}, which is not an output of this "
                      "command; --overwrite replaces only a folder of earlier outputs "
                      "(name a new folder)")


@contextlib.contextmanager
def staged_folder(path: str | Path, *, overwrite: bool = False,
                  ours: Callable[[Path], bool] = lambda entry: False):
    """A new folder that replaces ``path`` as a whole when the block (and the enclosing
    :func:`all_or_none` block) ends without an error, or is removed otherwise. An
    existing ``path`` that holds anything is refused unless ``overwrite`` and each of
    its entries is an earlier output (``ours``; see :func:`check_replaceable_folder`).
    A link to a folder is followed: the folder it leads to is replaced, the link kept."""
    path = followed_folder(path)
    parent = path.parent if str(path.parent) else Path(".")
    check_replaceable_folder(path, overwrite=overwrite, ours=ours)
    parent.mkdir(parents=True, exist_ok=True)
    try:
        tmp = tempfile.mkdtemp(prefix=_temporary_prefix(path), suffix=".tmp", dir=parent)
    except OSError as exc:
        raise OSError(f"{path}: could not be written ({exc.strerror or exc})") from None
    _STAGED_FOLDERS[Path(tmp)] = path
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o777 & ~current_umask())
        _land(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        _STAGED_FOLDERS.pop(Path(tmp), None)


@contextlib.contextmanager
def output_folder(path: str | Path | None):
    """``path`` made (with its parents) if missing; the folders made here are removed
    again when the block fails and they are still empty, so a failed command leaves no
    empty output folder behind. ``None``: nothing to make."""
    if path is None:
        yield None
        return
    path = followed_folder(path)
    made = []
    for folder in [path, *path.parents]:
        if folder.exists():
            break
        made.append(folder)
    path.mkdir(parents=True, exist_ok=True)
    try:
        yield path
    except BaseException:
        for folder in made:  # deepest first
            try:
                folder.rmdir()
            except OSError:  # not empty (or already gone): left as it is
                break
        raise


def _replace(tmp: str | Path, path: Path) -> None:
    """``os.replace``, and for a folder over an existing one: the old one set aside,
    the new one renamed in, the old one removed."""
    if not os.path.isdir(tmp) or not path.exists():
        os.replace(tmp, path)
        return
    old = tempfile.mkdtemp(prefix=_temporary_prefix(path), suffix=".old",
                           dir=path.parent if str(path.parent) else ".")
    os.replace(path, Path(old) / path.name)
    try:
        os.replace(tmp, path)
    except BaseException:
        os.replace(Path(old) / path.name, path)
        raise
    finally:
        shutil.rmtree(old, ignore_errors=True)


#: Signals whose delivery is put off while the outputs of a block are renamed into place.
_DEFERRED_SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP",
                                                              "SIGQUIT") if hasattr(signal, name))


@contextlib.contextmanager
def _signals_deferred():
    """SIGINT and SIGTERM held back and delivered when the block ends, so that a run is
    stopped before or after its renames, never between two of them. (Masking the signals
    would not do: the kernel hands them to a worker thread that does not mask them.)"""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending: list[int] = []
    saved = {}
    for number in _DEFERRED_SIGNALS:
        handler = signal.getsignal(number)
        if callable(handler) or handler == signal.SIG_DFL:
            saved[number] = signal.signal(number, lambda n, frame: pending.append(n))
    try:
        yield
    finally:
        for number, handler in saved.items():
            signal.signal(number, handler)
        if pending:
            signal.raise_signal(pending[0])


#: Called before the outputs of an :func:`all_or_none` block land; each raises if the
#: process was asked to stop in a way the stop's own exception did not carry through.
_STOP_CHECKS: list[Callable[[], None]] = []


def add_stop_check(check: Callable[[], None]) -> None:
    """Run ``check()`` before every group of outputs lands (see :data:`_STOP_CHECKS`)."""
    if check not in _STOP_CHECKS:
        _STOP_CHECKS.append(check)


@contextlib.contextmanager
def all_or_none():
    """Writes inside the block land together when it ends without an error; on an error
    (or Ctrl-C, or SIGTERM) none of them does and their temporaries are removed. The
    renames at the end run with SIGINT and SIGTERM deferred."""
    if _STAGED.get() is not None:  # inside another block: its writes land with that one's
        yield
        return
    staged: list[tuple[str, Path]] = []
    token = _STAGED.set(staged)
    try:
        yield
        for check in _STOP_CHECKS:
            check()
        with _signals_deferred():
            while staged:
                tmp, path = staged[0]
                _replace(tmp, path)
                staged.pop(0)
    finally:
        _STAGED.reset(token)
        for tmp, _ in staged:
            if os.path.isdir(tmp):
                shutil.rmtree(tmp, ignore_errors=True)
            elif os.path.exists(tmp):
                os.unlink(tmp)


def _temporary_prefix(path: Path) -> str:
    return f".{path.stem}."


def _temporary_suffix(path: Path) -> str:
    return f".tmp{path.suffix}"


def remove_stale_temporaries(path: str | Path) -> list[Path]:
    """Remove the temporary files (or staged folders, :func:`staged_folder`) that writes
    of ``path`` left behind when their process was killed (a normal failure removes its
    own), and return them. Only for when no write of ``path`` is under way."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    prefix, suffix = _temporary_prefix(path), _temporary_suffix(path)
    removed: list[Path] = []
    if not folder.is_dir():
        return removed
    for candidate in folder.glob(f"{glob.escape(prefix)}*{glob.escape(suffix)}"):
        middle = candidate.name[len(prefix):-len(suffix)]
        if re.fullmatch(r"[a-z0-9_]{8}", middle):  # tempfile's random part, nothing else
            if candidate.is_dir() and not candidate.is_symlink():  # a staged folder's
                shutil.rmtree(candidate, ignore_errors=True)
            else:
                candidate.unlink(missing_ok=True)
            removed.append(candidate)
    return removed


def current_umask() -> int:
    """The process's umask (reading it means setting it; it is set straight back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def check_distinct_paths(inputs, outputs) -> None:
    """Refuse an output that names an input, or two outputs that name the same file.

    Paths are compared after resolving links and ``..``, and by identity on disk where
    both exist (hard links); ``None`` entries are ignored. Raises ValueError.
    """
    inputs = [Path(p) for p in inputs if p is not None]
    outputs = [Path(p) for p in outputs if p is not None]
    for k, out in enumerate(outputs):
        for other in inputs + outputs[:k]:
            if same_file(out, other):
                role = "input" if other in inputs else "output"
                raise ValueError(f"{out}: the output would overwrite the {role} {other}")


def resolved(path: str | Path) -> Path:
    """``path`` with links and ``..`` resolved; a link that loops is an OSError naming
    ``path`` (Python raises RuntimeError for it, or OSError ELOOP)."""
    try:
        return Path(path).resolve()
    except (RuntimeError, OSError):
        raise OSError(f"{path}: a symbolic link that loops (it leads back to itself)") from None


def same_file(a: Path, b: Path) -> bool:
    """The same file: one path after resolving links and ``..``, or one file on disk."""
    if resolved(a) == resolved(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write UTF-8 text to ``path`` through a temporary file (see :func:`write_atomic`)."""
    write_atomic(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def imwrite_atomic(path: str | Path, image: np.ndarray) -> None:
    """An image written through a temporary file (see :func:`write_atomic`), in the format
    its extension names. OpenCV encodes it in memory and Python writes the bytes: some
    OpenCV encoders (PFM in 4.x) report success on a full disk and leave a cut file, where
    Python's write raises."""
    def encode(tmp: str) -> None:
        ok, data = cv2.imencode(Path(tmp).suffix, image)
        if not ok:
            raise OSError("OpenCV could not encode the image")
        with open(tmp, "wb") as fh:
            fh.write(data.tobytes())
    write_atomic(path, encode)


#: The largest disparity a 16-bit PNG holds (KITTI's value = round(256 d) <= 65535).
PNG16_MAX_DISPARITY = 65535 / 256.0


def png_range_problem(path: str | Path, min_disp: int, max_disp: int) -> str | None:
    """Why a disparity map of range ``min_disp .. max_disp`` cannot go to ``path``, or
    None. A 16-bit PNG holds 1/256 .. 255.996 (0 is "invalid"): a negative or larger
    disparity would be clipped or lost, so such an output is refused before the work."""
    if Path(path).suffix.lower() != ".png":
        return None
    # The disparities stay within the searched range (pipeline.run).
    if min_disp < 0 or max_disp > PNG16_MAX_DISPARITY:
        return (f"{path}: a 16-bit PNG holds disparities 0..{PNG16_MAX_DISPARITY:.3f}, "
                f"but the search range is {min_disp}..{max_disp}; write .pfm instead")
    return None


def disparity_to_png16(disp: np.ndarray) -> np.ndarray:
    """KITTI convention: uint16 value = round(256 d), 0 = invalid. Raises ValueError on
    a disparity the format cannot hold (negative, or above 255.996), never clips."""
    finite = np.isfinite(disp)
    values = disp[finite]
    if values.size and (values.min() < 0 or values.max() > PNG16_MAX_DISPARITY):
        raise ValueError(f"disparities {values.min():.2f}..{values.max():.2f} do not fit a "
                         f"16-bit PNG (0..{PNG16_MAX_DISPARITY:.3f}); write .pfm instead")
    out = np.zeros(disp.shape, dtype=np.uint16)
    out[finite] = np.maximum(np.round(values * 256.0), 1).astype(np.uint16)
    return out


def png16_to_disparity(png: np.ndarray) -> np.ndarray:
    out = png.astype(np.float32) / 256.0
    out[png == 0] = INVALID_DISPARITY
    return out


def write_disparity(path: str | Path, disp: np.ndarray) -> None:
    """Write a disparity map: ``.pfm`` float32 (Middlebury, inf = invalid) or ``.png``
    16-bit (KITTI, value = round(256 d), 0 = invalid)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".pfm":
        imwrite_atomic(path, np.ascontiguousarray(disp, dtype=np.float32))
    elif suffix == ".png":
        try:
            png = disparity_to_png16(disp)
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None
        imwrite_atomic(path, png)
    else:
        raise ValueError(f"{path}: unknown disparity format '{suffix}' "
                         f"(use {' or '.join(DISPARITY_FORMATS)})")


#: Output formats of a confidence map, by file extension.
CONFIDENCE_FORMATS = (".pfm", ".png")


def write_confidence(path: str | Path, confidence: np.ndarray) -> None:
    """A confidence map in [0, 1]: ``.pfm`` float32, or ``.png`` 16-bit scaled to
    0 .. 65535."""
    suffix = Path(path).suffix.lower()
    if suffix == ".pfm":
        imwrite_atomic(path, np.ascontiguousarray(confidence, dtype=np.float32))
    elif suffix == ".png":
        scaled = np.round(np.clip(confidence, 0, 1) * 65535).astype(np.uint16)
        imwrite_atomic(path, scaled)
    else:
        raise ValueError(f"{path}: unknown confidence format '{suffix}' "
                         f"(use {' or '.join(CONFIDENCE_FORMATS)})")


def write_depth(path: str | Path, depth: np.ndarray) -> None:
    """Depth as float32 PFM (``inf`` where unknown), the baseline's unit."""
    if Path(path).suffix.lower() != ".pfm":
        raise ValueError(f"{path}: depth is written as .pfm (float32)")
    imwrite_atomic(path, np.ascontiguousarray(depth, dtype=np.float32))


def write_point_cloud(path: str | Path, vertices: np.ndarray) -> None:
    """A binary little-endian PLY of ``vertices`` (see ``geometry.ply_vertices``)."""
    from plyfile import PlyData, PlyElement

    ply = PlyData([PlyElement.describe(vertices, "vertex")], text=False, byte_order="<")
    write_atomic(path, lambda tmp: ply.write(tmp))


def read_pfm(path: str | Path) -> np.ndarray:
    """A PFM image as float32, (H, W) or (H, W, 3), top row first.

    The scale's sign gives the byte order; its magnitude is not applied (some writers
    store an arbitrary one there, which OpenCV's reader would multiply in).
    """
    path = Path(path)
    try:
        with path.open("rb") as fh:
            kind = fh.readline().strip()
            dims = fh.readline().split()
            scale = float(fh.readline())
            data = fh.read()
        if kind not in (b"Pf", b"PF") or len(dims) != 2:
            raise ValueError("bad header")
        width, height = int(dims[0]), int(dims[1])
        if width < 1 or height < 1:
            raise ValueError("bad size")
    except FileNotFoundError:
        raise ImageError(f"{path}: file not found") from None
    except (OSError, ValueError, IndexError):
        raise ImageError(f"{path}: not a PFM file") from None
    channels = 3 if kind == b"PF" else 1
    count = width * height * channels
    if len(data) < 4 * count:
        raise ImageError(f"{path}: truncated PFM")
    values = np.frombuffer(data, dtype="<f4" if scale < 0 else ">f4", count=count)
    image = values.reshape((height, width, channels) if channels == 3 else (height, width))
    return np.ascontiguousarray(image[::-1], dtype=np.float32)


def read_disparity(path: str | Path) -> np.ndarray:
    """Read a disparity map written by :func:`write_disparity` (float32, inf = invalid)."""
    path = Path(path)
    if path.suffix.lower() == ".pfm":
        return read_pfm(path)
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise ImageError(f"{path}: not a readable disparity map")
    if path.suffix.lower() == ".png":
        return png16_to_disparity(image)
    return image.astype(np.float32)
