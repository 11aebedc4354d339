import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]


def data_root() -> Path | None:
    """VSMATCH_DATA, else ../shared/data beside the checkout."""
    env = os.environ.get("VSMATCH_DATA")
    candidates = [Path(env)] if env else [REPO.parent / "shared" / "data"]
    for root in candidates:
        if (root / "middlebury2").is_dir():
            return root
    return None


def no_way_to(what: str):
    """Fail in CI (a check that cannot run there is a hole in it), skip elsewhere."""
    if os.environ.get("CI") == "true":
        pytest.fail(f"cannot {what} here: in CI this test must run")
    pytest.skip(f"cannot {what} here")


@pytest.fixture(scope="session")
def data_dir() -> Path:
    root = data_root()
    if root is None:
        env = os.environ.get("VSMATCH_DATA")
        if env:  # a data root given but unusable is a mistake, not a reason to skip
            pytest.fail(f"VSMATCH_DATA={env} holds no middlebury2/: the data tests cannot "
                        "run (unset it to skip them where there is no data)")
        no_way_to("find the Middlebury data (set VSMATCH_DATA)")
    return root


@pytest.fixture(scope="session", autouse=True)
def warm_kernels():
    """Compile the kernels before the first test when Numba's cache is cold: else the first
    test that runs a match (whichever it is) also prints "compiling the kernels once", and a
    test counting a refusal's lines fails only on a fresh cache."""
    from vsmatch import _kernels, pipeline

    if _kernels.cache_is_cold():
        left, right = random_pair(np.random.default_rng(0), height=32, width=48, shift=3)
        pipeline.run(left, right, max_disp=8)


@pytest.fixture
def rng():
    return np.random.default_rng(0)


def random_pair(rng, height=14, width=20, shift=2, channels=3):
    """Random texture; left pixel x shows what right pixel x - shift shows."""
    wide = rng.integers(0, 256, size=(height, width + shift, channels), dtype=np.uint8)
    left = np.ascontiguousarray(wide[:, :width])
    right = np.ascontiguousarray(wide[:, shift:])
    return left, right


@pytest.fixture
def pair_files(tmp_path, rng):
    """A small random pair (32 x 48, every disparity 3) written as l.png and r.png."""
    import cv2

    left, right = random_pair(rng, height=32, width=48, shift=3)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), right)
    return tmp_path / "l.png", tmp_path / "r.png"


#: The hard scenes (a blank wall, shelves) added to the data beside the standard sets:
#: measured apart (tests/test_hard_scenes.py), so that the standard sets' figures stay
#: comparable from version to version.
HARD_SCENES = ("Vintage", "terrains_2l", "terrains_2s")


def standard_scenes(scenes):
    """The scenes of a data set without :data:`HARD_SCENES`."""
    return [scene for scene in scenes if scene.name not in HARD_SCENES]


@pytest.fixture
def lowest_cloud_threshold() -> float:
    """The lowest ``cloud.min_confidence`` of the bundled configs: a cap meant to keep a
    pixel out of every cloud must stay below it."""
    from vsmatch.config import bundled_config_names, load_config

    return min(load_config(name).cloud.min_confidence for name in bundled_config_names())


#: File-size limits to lift as soon as the test function returns: pytest reports the test
#: before its fixtures' teardown, and where its output goes to a file already past the
#: limit (``pytest > log``), that report's write would fail EFBIG.
_LIFT_AFTER_CALL: list = []


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_call(item):
    yield
    while _LIFT_AFTER_CALL:
        _LIFT_AFTER_CALL.pop()()


@pytest.fixture
def small_disk(tmp_path):
    """``small_disk(kilobytes, read_only=False, mount=True, whole_disk=False)``: a folder
    that fills up past that size, or that cannot be written. A tmpfs that small is mounted
    (read-only if asked) and unmounted after the test; where mounting is not allowed (or
    ``mount=False``), a full disk is a file-size limit instead (RLIMIT_FSIZE: a write past
    it fails, EFBIG, as a full disk's does, ENOSPC; the limit holds for every file the test
    writes from then on; so not for a test that fills the ``whole_disk``, with many small
    files or a filler), and a read-only folder is one without write permission (for a user
    other than root). Neither possible: the test fails in CI and skips elsewhere."""
    import resource
    import signal
    import subprocess

    undo = []

    def disk(kilobytes: int, read_only: bool = False, mount: bool = True,
             whole_disk: bool = False):
        folder = tmp_path / f"disk{len(undo)}"
        folder.mkdir()
        options = ("ro," if read_only else "") + f"size={kilobytes}k"
        if mount and subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs",
                                     str(folder)], capture_output=True).returncode == 0:
            undo.append(lambda: subprocess.run(["umount", str(folder)], capture_output=True))
        elif read_only and os.geteuid() != 0:
            folder.chmod(0o555)
            undo.append(lambda: folder.chmod(0o755))
        elif not read_only and not whole_disk:
            limits = resource.getrlimit(resource.RLIMIT_FSIZE)
            handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # EFBIG, not a kill
            resource.setrlimit(resource.RLIMIT_FSIZE, (kilobytes * 1024, limits[1]))

            def lift():
                resource.setrlimit(resource.RLIMIT_FSIZE, limits)
                signal.signal(signal.SIGXFSZ, handler)

            undo.append(lift)
            _LIFT_AFTER_CALL.append(lift)
        elif read_only:
            no_way_to("mount a read-only tmpfs or drop write permission (root)")
        else:
            no_way_to("mount a small tmpfs (a file-size limit cannot fill a whole disk)")
        return folder

    yield disk
    for step in reversed(undo):
        step()
